"""Train and ship the wood/leaf PointNet++ (chapter 09c) on leafy procedural scans, and measure what it does for
reconstruction. Usage: python scripts/train_foliage.py [--per-species 40] [--test-per-species 5] [--minutes 40]
[--steps 3000] [--work tmp/foliage] [--out treebook/data/weights/foliage.pt] [--results results/foliage.json]
Training scans: seeds 20000 on, held-out 29000 on (`foliage_pool`, cached in --work; training resumes from
--work/checkpoint.pt). Held-out `wood_scores`; then, on --skeleton-trees held-out trees per species, the skeleton of
the leafy scan as it is, with the geometric filter, with the network's wood, and of the same tree scanned without
leaves, each against the tree. Writes the weights, their card (`foliage_card`) and the record."""
import argparse, json, os, platform, sys, time
from pathlib import Path
import provenance   # scripts/provenance.py, beside this script
import numpy as np, torch
from tqdm.auto import tqdm
from treebook.tree import _atomic_write
from treebook.botany import SPECIES, grow
from treebook.scan import scan
from treebook.foliage import FOLIAGE_POINTS, foliage_card, foliage_pool, save_foliage, train_foliage, wood_scores
from treebook.reconstruct import reconstruct, skeleton_distance

p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
for k, v in dict(per_species=40, test_per_species=5, steps=3000, batch=2, width=32, threads=2).items():
    p.add_argument(f"--{k.replace('_', '-')}", type=int, default=v)
p.add_argument("--minutes", type=float, default=40.0, help="stop early after this long (the planned --steps set the schedule)")
p.add_argument("--lr", type=float, default=1e-3); p.add_argument("--work", default=str(provenance.ROOT / "tmp" / "foliage"))
p.add_argument("--skeleton-trees", type=int, default=2, help="held-out trees per species for the skeleton table")
p.add_argument("--out", default=str(provenance.ROOT / "treebook" / "data" / "weights" / "foliage.pt"))
p.add_argument("--results", default=str(provenance.ROOT / "results" / "foliage.json"))
a = p.parse_args()
for name in ("per_species", "test_per_species", "steps", "batch", "width"):
    if getattr(a, name) < 1: sys.exit(f"--{name.replace('_', '-')} must be >= 1, got {getattr(a, name)}")
if not 0 <= a.skeleton_trees <= a.test_per_species: sys.exit(f"--skeleton-trees must be in 0..--test-per-species, got {a.skeleton_trees}")
torch.set_num_threads(a.threads)
work = Path(a.work); work.mkdir(parents=True, exist_ok=True); t0 = time.time()
train = foliage_pool(work / "pool.npz", [(s, 20000 + i) for s in SPECIES for i in range(a.per_species)], "training scans")
test = foliage_pool(work / "test.npz", [(s, 29000 + i) for s in SPECIES for i in range(a.test_per_species)], "held-out scans")
t1 = time.time()
net, losses = train_foliage(train, steps=a.steps, batch=a.batch, lr=a.lr, width=a.width, seed=0, checkpoint=work / "checkpoint.pt", minutes=a.minutes)
t2 = time.time()
scores = wood_scores(net, test); print(json.dumps(scores))
meta = dict(command="python scripts/train_foliage.py " + " ".join(sys.argv[1:]), commit=provenance.commit(short=True), steps=len(losses), batch=a.batch,
            minutes=round((t2 - t1) / 60, 1), train_scans=len(train), test_scans=len(test), held_out=scores,
            machine=f"{platform.machine()}, {os.cpu_count()} cores, {platform.python_version()}")
out, rows = save_foliage(net, a.out, **meta), []
for s in tqdm(SPECIES, desc="skeletons"):
    for i in range(a.skeleton_trees):
        truth = grow(s, seed=29000 + i, stages=1)[-1]
        leafy = test[list(SPECIES).index(s) * a.test_per_species + i][0].astype(np.float64)
        bare = scan(truth, n_points=FOLIAGE_POINTS, seed=29000 + i).points.astype(np.float64)
        for kind, cloud, fol in (("leafy", leafy, False), ("geometric filter", leafy, "geometric"), ("network", leafy, "network"), ("no leaves", bare, False)):
            for m in ("classic", "partnet"):
                tree, info = reconstruct(cloud, method=m, seed=0, foliage=fol, foliage_weights=out, return_info=True)
                d = skeleton_distance(tree, truth)
                rows.append(dict(species=s, seed=29000 + i, cloud=kind, method=m, points=len(info["points"]), chamfer=round(d["chamfer"], 4), hausdorff=round(d["hausdorff"], 3)))
summary = {f"{k}/{m}": {x: round(float(np.mean([r[x] for r in rows if r["cloud"] == k and r["method"] == m])), 4) for x in ("chamfer", "hausdorff", "points")}
           for k in ("leafy", "geometric filter", "network", "no leaves") for m in ("classic", "partnet")} if rows else {}
_atomic_write(Path(a.out).with_suffix(".md"), lambda f: f.write(foliage_card(net, out, meta, a.per_species, a.lr, a.steps).encode()))
res = dict(meta, pool_minutes=round((t1 - t0) / 60, 1), loss_first=float(np.mean(losses[:50])), loss_last=float(np.mean(losses[-50:])),
           skeletons=summary, rows=rows, parameters=sum(q.numel() for q in net.parameters()))
_atomic_write(Path(a.results), lambda f: f.write(json.dumps(res, indent=1).encode()))
print(json.dumps(summary, indent=1)); print("wrote", a.out, "and", a.results)
