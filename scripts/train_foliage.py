"""Train and ship the wood/leaf PointNet++ (chapter 09c) on leafy procedural scans, and measure what it does for reconstruction.

Usage: python scripts/train_foliage.py [--per-species 40] [--test-per-species 5] [--minutes 40] [--steps 3000] [--work tmp/foliage]
                                       [--out treebook/data/weights/foliage.pt] [--results results/foliage.json]

Training scans: trees of seeds 20000 onwards (per species), scanned with leaves at 16,384 points (`foliage.foliage_scan`);
held-out scans: seeds 29000 onwards. The scans are cached in --work (pool.npz); the training resumes from --work/checkpoint.pt
if it was interrupted. Held-out scores: per point accuracy and wood precision / recall / IoU at probability 0.5. Then, on two
held-out trees per species, the skeleton (`reconstruct`, classic and partnet) of the leafy scan as it is, with the geometric
wood filter, with the network's wood, and of a scan of the same tree without leaves, each against the tree (Chamfer and
Hausdorff distance, % of the diagonal). Writes the weights with a card beside them, and the record.
"""
import argparse, json, os, platform, sys, time
from pathlib import Path

import numpy as np
import torch
from tqdm.auto import tqdm

root = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(root)); sys.path.insert(0, str(root / "scripts"))
import provenance
from treebook.tree import _atomic_write
from treebook.botany import SPECIES, grow
from treebook.scan import scan
from treebook.foliage import foliage_scan, train_foliage, wood_probability, save_foliage, FOLIAGE_POINTS
from treebook.reconstruct import reconstruct, skeleton_distance


def pool(path: Path, seeds, desc):
    "Scans of (species, seed) in `seeds`, cached in `path` (made again if the list differs)."
    key = np.array([f"{s}:{k}" for s, k in seeds])
    if path.exists():
        z = np.load(path)
        if np.array_equal(z["key"], key): return [(p, w) for p, w in zip(z["points"], z["wood"])]
    out = [foliage_scan(s, k) for s, k in tqdm(seeds, desc=desc)]
    np.savez(path, key=key, points=np.stack([p for p, _ in out]), wood=np.stack([w for _, w in out]))
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--per-species", type=int, default=40); ap.add_argument("--test-per-species", type=int, default=5)
    ap.add_argument("--steps", type=int, default=3000); ap.add_argument("--minutes", type=float, default=40.0, help="stop early after this long (the planned --steps set the schedule)")
    ap.add_argument("--batch", type=int, default=2); ap.add_argument("--lr", type=float, default=1e-3); ap.add_argument("--width", type=int, default=32)
    ap.add_argument("--skeleton-trees", type=int, default=2, help="held-out trees per species for the skeleton table")
    ap.add_argument("--threads", type=int, default=2); ap.add_argument("--work", default=str(root / "tmp" / "foliage"))
    ap.add_argument("--out", default=str(root / "treebook" / "data" / "weights" / "foliage.pt"))
    ap.add_argument("--results", default=str(root / "results" / "foliage.json"))
    a = ap.parse_args()
    for name in ("per_species", "test_per_species", "steps", "batch", "width"):
        if getattr(a, name) < 1: sys.exit(f"--{name.replace('_', '-')} must be >= 1, got {getattr(a, name)}")
    if not 0 <= a.skeleton_trees <= a.test_per_species: sys.exit(f"--skeleton-trees must be in 0..--test-per-species, got {a.skeleton_trees}")
    torch.set_num_threads(a.threads)
    work = Path(a.work); work.mkdir(parents=True, exist_ok=True)
    t0 = time.time()
    train = pool(work / "pool.npz", [(s, 20000 + i) for s in SPECIES for i in range(a.per_species)], "training scans")
    test = pool(work / "test.npz", [(s, 29000 + i) for s in SPECIES for i in range(a.test_per_species)], "held-out scans")
    t1 = time.time()
    net, losses = train_foliage(train, steps=a.steps, batch=a.batch, lr=a.lr, width=a.width, seed=0, checkpoint=work / "checkpoint.pt", minutes=a.minutes)
    t2 = time.time()
    tp = fp = fn = tn = 0
    for p, w in tqdm(test, desc="held-out"):
        pr = wood_probability(net, p) >= 0.5
        tp += int((pr & w).sum()); fp += int((pr & ~w).sum()); fn += int((~pr & w).sum()); tn += int((~pr & ~w).sum())
    scores = dict(accuracy=(tp + tn) / (tp + fp + fn + tn), wood_precision=tp / max(tp + fp, 1), wood_recall=tp / max(tp + fn, 1),
                  wood_iou=tp / max(tp + fp + fn, 1), wood_share=(tp + fn) / (tp + fp + fn + tn))
    print(json.dumps(scores))
    cmd = "python scripts/train_foliage.py " + " ".join(sys.argv[1:])
    commit = provenance.commit(short=True)
    meta = dict(command=cmd, commit=commit, steps=len(losses), batch=a.batch, minutes=round((t2 - t1) / 60, 1), train_scans=len(train), test_scans=len(test),
                held_out=scores, machine=f"{platform.machine()}, {os.cpu_count()} cores, {platform.python_version()}")
    out = save_foliage(net, a.out, **meta)
    rows = []
    for s in tqdm(SPECIES, desc="skeletons"):
        for i in range(a.skeleton_trees):
            seed = 29000 + i
            truth = grow(s, seed=seed, stages=1)[-1]
            p = test[list(SPECIES).index(s) * a.test_per_species + i][0].astype(np.float64)
            bare = scan(truth, n_points=FOLIAGE_POINTS, seed=seed).points.astype(np.float64)
            for kind, cloud, fol in (("leafy", p, False), ("geometric filter", p, "geometric"), ("network", p, "network"), ("no leaves", bare, False)):
                for m in ("classic", "partnet"):
                    tree, info = reconstruct(cloud, method=m, seed=0, foliage=fol, foliage_weights=out, return_info=True)
                    d = skeleton_distance(tree, truth)
                    rows.append(dict(species=s, seed=seed, cloud=kind, method=m, points=len(info["points"]), chamfer=round(d["chamfer"], 4), hausdorff=round(d["hausdorff"], 3)))
    summary = {f"{k}/{m}": {x: round(float(np.mean([r[x] for r in rows if r["cloud"] == k and r["method"] == m])), 4) for x in ("chamfer", "hausdorff", "points")}
               for k in ("leafy", "geometric filter", "network", "no leaves") for m in ("classic", "partnet")} if rows else {}
    n_par = sum(p.numel() for p in net.parameters())
    card = f"""# Wood/leaf PointNet++ weights (`foliage.pt`)

- **Model**: `treebook.foliage.FoliageNet` {json.dumps(net.cfg)}; {n_par:,} parameters, {out.stat().st_size / 1e6:.1f} MB.
- **Data**: {len(train)} procedural trees ({a.per_species} per species: {", ".join(SPECIES)}; seeds 20000 on), each scanned once with leaves by `treebook.foliage.foliage_scan` at {FOLIAGE_POINTS:,} points with noise 0-0.4% of the size, 0-2% outliers, 0-2 missing regions and 2-4 views; every step takes the scan turned about z, tilted up to 10 degrees, scaled 0.8-1.2, jittered, normalised into the unit sphere. Target: wood (neither leaf nor outlier), from the scanner's flags.
- **Training**: {len(losses)} steps of batch {a.batch}, Adam lr {a.lr} (x0.1 for the last fifth of the planned {a.steps} steps), {meta['minutes']} minutes on {meta['machine']}.
- **Command**: `{cmd}` (commit {commit}), which wrote this file and `results/foliage.json`.
- **Held-out scores** ({len(test)} scans of trees with seeds 29000 on, all {FOLIAGE_POINTS:,} points, probability 0.5): accuracy {scores['accuracy']:.3f}; wood precision {scores['wood_precision']:.3f}, recall {scores['wood_recall']:.3f}, IoU {scores['wood_iou']:.3f} ({scores['wood_share']:.0%} of the points are wood).
- **Limits**: procedural leaves only (quads in clusters at the twigs); real foliage, needles and understorey differ. Use it through `wood_probability`, `reconstruct(..., foliage=True)` or `treebook reconstruct --foliage`. On the held-out leafy trees of `results/foliage.json` a skeleton traced from the wood it keeps is *farther* from the whole tree (Chamfer distance) than one traced through the leaves: the leaves hang where the fine twigs are, the twigs it misses go with them, and what is left is the visible wood. Chapter 09c shows the table.
"""
    _atomic_write(Path(a.out).with_suffix(".md"), lambda f: f.write(card.encode()))
    res = dict(meta, pool_minutes=round((t1 - t0) / 60, 1), loss_first=float(np.mean(losses[:50])), loss_last=float(np.mean(losses[-50:])),
               skeletons=summary, rows=rows, parameters=n_par)
    _atomic_write(Path(a.results), lambda f: f.write(json.dumps(res, indent=1).encode()))
    print(json.dumps(summary, indent=1)); print("wrote", a.out, "and", a.results)


if __name__ == "__main__":
    main()
