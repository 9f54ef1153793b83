"""Choose the finest voxel of `prepare_points` (treebook.reconstruct.VOXEL) on procedural scans of several densities.

Usage: python benchmarks/choose_voxel.py [--fractions 0,0.002,0.0025,0.003,0.004,0.005] [--trees-per-species 2] [--out results/reconstruct_voxel.json]

Each tree (seeds 7100 onwards: not the benchmark's trees) is scanned four ways: 16,384 points, 4,096 points (sparse),
49,152 points (dense, still under `prepare_points`'s 60,000: above it a cloud is thinned to 60,000 anyway), and the 16,384-point scan three times over, two of the copies jittered by 0.05% of the diagonal
(two or three scan stations registered a few millimetres apart: "double surfaces"). Each scan is reconstructed with the
default method at every voxel fraction (0: no evening, the old behaviour) and scored against the tree it came from:
skeleton Chamfer and Hausdorff distance (% of the diagonal) and the share of the scan's points within 1% of the diagonal
from the mesh. The chosen fraction has the lowest Chamfer distance averaged over the four kinds of scan. Real scans are
not used for the choice.
"""
import argparse, json, os, platform, sys, time
from pathlib import Path

import numpy as np
from tqdm.auto import tqdm

root = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(root)); sys.path.insert(0, str(root / "scripts"))
import provenance
from treebook.tree import _atomic_write
from treebook.botany import SPECIES, grow
from treebook.scan import scan
from treebook.mesh import tree_mesh
from treebook.reconstruct import reconstruct, coverage, skeleton_distance, _diag

KINDS = ("16k", "4k", "48k", "double")


def scans_of(truth, seed: int) -> dict:
    "The four scans of `truth` (float64 points)."
    s = lambda n: scan(truth, n_points=n, seed=seed, noise=0.002, outliers=0.01).points.astype(np.float64)
    p = s(16384)
    rng = np.random.default_rng(seed)
    j = 0.0005 * _diag(p)
    return {"16k": p, "4k": s(4096), "48k": s(49152), "double": np.vstack([p, p + rng.normal(0, j, p.shape), p + rng.normal(0, j, p.shape)])}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--fractions", default="0,0.002,0.0025,0.003,0.004,0.005")
    ap.add_argument("--trees-per-species", type=int, default=2)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--out", default=str(root / "results" / "reconstruct_voxel.json"))
    a = ap.parse_args()
    try: fr = [float(x) for x in a.fractions.split(",")]
    except ValueError: sys.exit(f"--fractions must be numbers separated by commas, got {a.fractions!r}")
    if not fr or any(not 0 <= f < 0.05 for f in fr): sys.exit(f"--fractions must lie in [0, 0.05), got {a.fractions!r}")
    if a.trees_per_species < 1: sys.exit(f"--trees-per-species must be >= 1, got {a.trees_per_species}")
    import torch; torch.set_num_threads(a.threads)
    t0, rows = time.perf_counter(), []
    jobs = [(sp, 7100 + i) for sp in SPECIES for i in range(a.trees_per_species)]
    for sp, seed in tqdm(jobs, desc="trees"):
        truth = grow(sp, seed=seed, stages=1)[-1]
        for kind, p in scans_of(truth, seed).items():
            for f in fr:
                tree = reconstruct(p, seed=0, voxel=f)
                d = skeleton_distance(tree, truth)
                rows.append(dict(species=sp, seed=seed, scan=kind, points=len(p), fraction=f, chamfer=round(d["chamfer"], 4),
                                 hausdorff=round(d["hausdorff"], 3), coverage=round(coverage(p, tree_mesh(tree, sides=12)), 4)))
    table = {}
    for f in fr:
        for kind in KINDS:
            r = [x for x in rows if x["fraction"] == f and x["scan"] == kind]
            table[f"{f}/{kind}"] = {m: round(float(np.mean([x[m] for x in r])), 4) for m in ("chamfer", "hausdorff", "coverage")}
    mean = {str(f): round(float(np.mean([table[f"{f}/{k}"]["chamfer"] for k in KINDS])), 4) for f in fr}
    chosen = float(min(mean, key=mean.get))
    res = dict(command="python benchmarks/choose_voxel.py " + " ".join(sys.argv[1:]), commit=provenance.commit(short=True),
               machine=f"{platform.machine()}, {os.cpu_count()} cores, {platform.python_version()}", minutes=round((time.perf_counter() - t0) / 60, 1),
               trees=len(jobs), kinds=list(KINDS), fractions=fr, mean_chamfer=mean, chosen=chosen, table=table, rows=rows)
    _atomic_write(Path(a.out), lambda fh: fh.write(json.dumps(res, indent=1).encode()))
    print(json.dumps(dict(mean_chamfer=mean, chosen=chosen), indent=1)); print("wrote", a.out)


if __name__ == "__main__":
    main()
