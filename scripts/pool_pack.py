"""Pack a TreePartNet scan pool (train_partnet.py's {train,test}_pool.npz) small enough to travel, and unpack it, to train
on a machine that cannot scan (no open3d). Points: 16-bit steps of each scan's box, each scan's points in another order;
labels exact. `make` scans and packs a further train pool (trees 1000 * SEED + i, i < N_PER_SPECIES, every species, 8,192
points; train_partnet.py's own: SEED 1, tests 999); `unpack` of several files puts their train scans in one pool.
Usage: python scripts/pool_pack.py pack tmp/partnet5 gpu/pools.npz [train|test]
       python scripts/pool_pack.py unpack gpu/pools.npz[,MORE.npz...] tmp/partnet-gpu
       python scripts/pool_pack.py make SEED N_PER_SPECIES gpu/pool-s2.npz"""
import sys; from pathlib import Path
import numpy as np
def pack(work, dest, names=("train", "test")):
    out = {}
    for name in names:
        with np.load(Path(work) / f"{name}_pool.npz") as z: P, T, J, off, sp = (z[k] for k in ("points", "part", "junction", "offsets", "species"))
        lo = np.stack([P[a:b].min(0) for a, b in zip(off[:-1], off[1:])]); hi = np.stack([P[a:b].max(0) for a, b in zip(off[:-1], off[1:])])
        scan = np.repeat(np.arange(len(off) - 1), np.diff(off))
        q = np.round((P - lo[scan]) / np.maximum(hi - lo, 1e-9)[scan] * 65535).astype(np.uint16)
        # a scan is a set of points (training draws a random subset of it): ordering each one by part and height loses
        # nothing and lets the labels compress to almost nothing (the pool of 360 scans: 21.1 MB unsorted, 17.8 MB sorted)
        order = np.concatenate([a + np.lexsort((q[a:b, 2], T[a:b])) for a, b in zip(off[:-1], off[1:])])
        q, T, J = q[order], T[order], J[order]
        out |= {f"{name}_{k}": v for k, v in dict(q=q, lo=lo, hi=hi, part=T.astype(np.int16), junction=J, offsets=off, species=sp).items()}
    Path(dest).parent.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(dest, **out)
def _read(z, name):
    "One packed pool of `z` as (points, part, junction, offsets, species); None if `z` holds none of that name."
    if f"{name}_q" not in z: return None
    g = {k: z[f"{name}_{k}"] for k in ("q", "lo", "hi", "part", "junction", "offsets", "species")}
    scan = np.repeat(np.arange(len(g["offsets"]) - 1), np.diff(g["offsets"]))
    P = (g["lo"][scan] + g["q"] / 65535 * (g["hi"] - g["lo"])[scan]).astype(np.float32)
    return P, g["part"].astype(np.int32), g["junction"], g["offsets"], g["species"]
def unpack(srcs, work):
    "The packed pools `srcs` (a comma-separated list) into `work`'s train_pool.npz and test_pool.npz, each pool's scans one after another."
    Path(work).mkdir(parents=True, exist_ok=True)
    for name in ("train", "test"):
        parts = []
        for src in srcs.split(","):
            with np.load(src) as z: parts.append(_read(z, name))
        parts = [p for p in parts if p is not None]
        if not parts:   # a pool left behind: an empty one (a --train-only run never evaluates)
            np.savez(Path(work) / f"{name}_pool.npz", points=np.zeros((0, 3), np.float32), part=np.zeros(0, np.int32),
                     junction=np.zeros(0, bool), offsets=np.zeros(1, np.int64), species=np.zeros(0, "<U8")); continue
        P, T, J, off, sp = zip(*parts)
        off = np.concatenate([[0], np.cumsum(np.concatenate([np.diff(o) for o in off]))])   # the scans' sizes, one pool after another
        np.savez(Path(work) / f"{name}_pool.npz", points=np.concatenate(P), part=np.concatenate(T), junction=np.concatenate(J),
                 offsets=off, species=np.concatenate(sp))

def make(seed, n_per_species, dest, n_points=8192):
    "A further train pool scanned here (train_partnet.make_pool's trees for `seed`) and packed into `dest`."
    import tempfile
    from train_partnet import load_or_make_pool   # beside this script
    with tempfile.TemporaryDirectory() as work:
        load_or_make_pool(Path(work) / "train_pool.npz", n_per_species=n_per_species, seed=seed, n_points=n_points, desc=f"train scans, seed {seed}")
        pack(work, dest, ("train",))

if __name__ == "__main__":
    if len(sys.argv) not in (4, 5) or sys.argv[1] not in ("pack", "unpack", "make") or (sys.argv[1] == "make") != (len(sys.argv) == 5):
        sys.exit(__doc__)
    if sys.argv[1] == "pack": pack(sys.argv[2], sys.argv[3], sys.argv[4:] or ("train", "test"))
    elif sys.argv[1] == "make": make(int(sys.argv[2]), int(sys.argv[3]), sys.argv[4])
    else: unpack(sys.argv[2], sys.argv[3])
