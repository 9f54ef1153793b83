"""Pack a TreePartNet scan pool (train_partnet.py's train_pool.npz / test_pool.npz) small enough to travel, and unpack it.

Usage: python scripts/pool_pack.py pack tmp/partnet5 gpu/pools.npz [train|test]   (points as 16-bit steps of each scan's box,
       python scripts/pool_pack.py unpack gpu/pools.npz tmp/partnet-gpu            1/65535 of its size; labels exact; the
                                                                                   points of each scan in another order)
Used to train on a machine that cannot scan (no open3d) from the pools made here; unpacked pools load like made ones.
"""
import sys
from pathlib import Path
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
    np.savez_compressed(dest, **out)

def unpack(src, work):
    Path(work).mkdir(parents=True, exist_ok=True)
    with np.load(src) as z:
        for name in ("train", "test"):
            if f"{name}_q" not in z:   # a pool left behind: an empty one (a --train-only run never evaluates)
                np.savez(Path(work) / f"{name}_pool.npz", points=np.zeros((0, 3), np.float32), part=np.zeros(0, np.int32),
                         junction=np.zeros(0, bool), offsets=np.zeros(1, np.int64), species=np.zeros(0, "<U8")); continue
            g = {k: z[f"{name}_{k}"] for k in ("q", "lo", "hi", "part", "junction", "offsets", "species")}
            scan = np.repeat(np.arange(len(g["offsets"]) - 1), np.diff(g["offsets"]))
            P = (g["lo"][scan] + g["q"] / 65535 * (g["hi"] - g["lo"])[scan]).astype(np.float32)
            np.savez(Path(work) / f"{name}_pool.npz", points=P, part=g["part"].astype(np.int32), junction=g["junction"], offsets=g["offsets"], species=g["species"])

if __name__ == "__main__":
    if len(sys.argv) not in (4, 5) or sys.argv[1] not in ("pack", "unpack"): sys.exit(__doc__)
    if sys.argv[1] == "pack": pack(sys.argv[2], sys.argv[3], sys.argv[4:] or ("train", "test"))
    else: unpack(sys.argv[2], sys.argv[3])
