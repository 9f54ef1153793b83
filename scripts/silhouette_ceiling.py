"""How high can silhouette IoU go for a model that draws real elms but does not place each twig? For each held-out
silhouette (the same 50 the image models are scored on), the IoU of the best of --pool training elms, chosen with the
held-out silhouette in hand (an oracle no model has), and of the best of k random ones for a few k.

Usage: python scripts/silhouette_ceiling.py [--pool 3000] [--n-eval 50] [--seed 0]
Writes results/silhouette_ceiling.json.
"""
import argparse, json, os, platform, sys, time
from pathlib import Path
import provenance   # scripts/provenance.py, beside this script
import numpy as np
from tqdm.auto import tqdm
from treebook.datasets import load_trees
from treebook.scan import silhouette

root = Path(__file__).resolve().parent.parent
p = argparse.ArgumentParser()
p.add_argument("--data", default="data/elm"); p.add_argument("--pool", type=int, default=3000)
p.add_argument("--n-eval", type=int, default=50); p.add_argument("--seed", type=int, default=0)
a = p.parse_args()
t0 = time.time()
test = load_trees(root / a.data, "test")[:a.n_eval]
train = load_trees(root / a.data, "train")
idx = np.random.default_rng(a.seed).choice(len(train), min(a.pool, len(train)), replace=False)
S = np.stack([silhouette(train[i]) > 0 for i in tqdm(idx, desc="training silhouettes")]).reshape(len(idx), -1).astype(np.float32)
T = np.stack([silhouette(t) > 0 for t in test]).reshape(len(test), -1).astype(np.float32)
inter = T @ S.T
iou = inter / (T.sum(1)[:, None] + S.sum(1)[None] - inter)
ks = [k for k in (1, 4, 16, 64) if k <= len(idx)]
res = {"command": " ".join(["python scripts/silhouette_ceiling.py", *sys.argv[1:]]),
       "commit": provenance.commit(),
       "time": time.strftime("%Y-%m-%d %H:%M:%S"), "machine": {"platform": platform.platform(), "cpus": os.cpu_count()},
       "n_eval": len(test), "pool": len(idx),
       "iou_random_pair": float(iou.mean()),
       "iou_best_of_pool": float(iou.max(1).mean()),
       "iou_best_of_k_random": {k: float(np.mean([iou[:, j * k:(j + 1) * k].max(1).mean() for j in range(len(idx) // k)])) for k in ks},
       "seconds": time.time() - t0}
(root / "results").mkdir(exist_ok=True)
(root / "results" / "silhouette_ceiling.json").write_text(json.dumps(res, indent=1))
print(json.dumps(res, indent=1))
