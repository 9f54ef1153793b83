"""Benchmark: the set metrics (MMD-CD, COV-CD, 1-NNA, JSD, Unique, Novel) for N generated vs N reference trees.

Usage: python benchmarks/metrics.py [--n 1000] [--points 2048]
Writes results/metrics_bench.json. Trees: procedural elms from treebook.botany (two disjoint seed ranges).
Goal (issue 6): 1,000 vs 1,000 trees in at most 5 minutes on 2 cores.
"""
import argparse, json, os, platform, sys, time
from pathlib import Path
sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "scripts"))
import provenance   # scripts/provenance.py

import numpy as np

root = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(root))
from treebook.metrics import tree_clouds, evaluate

ap = argparse.ArgumentParser(description=__doc__)
ap.add_argument("--n", type=int, default=1000)
ap.add_argument("--points", type=int, default=2048)
ap.add_argument("--species", default="elm")
ap.add_argument("--check", type=int, default=100, help="also compare nearest neighbours with brute force on CHECK vs CHECK trees (0: skip)")
args = ap.parse_args()

from treebook.botany import grow_tree, species
from tqdm.auto import tqdm
sp = species(args.species)
t0 = time.time()
gen = [grow_tree(sp, seed=s) for s in tqdm(range(args.n), desc="growing G")]
ref = [grow_tree(sp, seed=100000 + s) for s in tqdm(range(args.n), desc="growing R")]
t_grow = time.time() - t0

t0 = time.time()
G, R = tree_clouds(gen, args.points, seed=0), tree_clouds(ref, args.points, seed=10**6)
t_sample = time.time() - t0
t0, c0 = time.time(), time.process_time()
m = evaluate(G, R, train=R)
t_metrics, c_metrics = time.time() - t0, time.process_time() - c0

check = None
if args.check:
    from scipy.spatial import cKDTree
    from treebook.metrics import chamfer, nearest
    c = args.check
    Gc, Rc = G[:c].astype(np.float64), R[:c].astype(np.float64)
    kg, kr = [cKDTree(x) for x in Gc], [cKDTree(x) for x in Rc]
    t0 = time.time()
    ex = np.array([[chamfer(Gc[i], Rc[j], kg[i], kr[j]) for j in range(c)] for i in tqdm(range(c), desc="brute force")])
    t_brute = time.time() - t0
    check = {"trees": c, "brute_force_seconds": round(t_brute, 1), "by_k": {}}
    for k in (1, 2, 3, 5, 10):
        d, i, cert = nearest(Gc, Rc, k, kd=(kg, kr))
        check["by_k"][k] = {"same_nearest": float((i == ex.argmin(1)).mean()), "max_abs_error": float(np.abs(d - ex.min(1)).max()), "certified": cert}

commit = provenance.commit()
res = {"command": "python benchmarks/metrics.py " + " ".join(sys.argv[1:]), "commit": commit,
       "machine": {"cpus": os.cpu_count(), "platform": platform.platform(), "processor": platform.processor(),
                   "load_avg_1min_at_end": os.getloadavg()[0]},
       "n_gen": args.n, "n_ref": args.n, "points": args.points, "species": args.species,
       "seconds": {"grow_trees": round(t_grow, 1), "sample_clouds": round(t_sample, 1), "metrics": round(t_metrics, 1),
                   "sample_plus_metrics": round(t_sample + t_metrics, 1),
                   "metrics_cpu_all_threads": round(c_metrics, 1)},
       "timing_note": "wall-clock seconds; metrics_cpu_all_threads is the CPU time of this process summed over its threads "
                      "(k-d tree queries use both cores), the cost on an otherwise idle machine is between the two",
       "goal_seconds": 300, "metrics": m, "nearest_vs_brute_force": check,
       "note": "R also serves as the 'training' set for Novel here, so Novel measures only the duplicate test's cost."}
out = root / "results" / "metrics_bench.json"
out.parent.mkdir(exist_ok=True)
out.write_text(json.dumps(res, indent=1))
print(json.dumps(res, indent=1))
