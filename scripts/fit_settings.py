"""How `condition.fit_silhouette` was set: IoU and the mean bend between parent and child branches (degrees, front view) of
training elms fitted to the silhouettes of other training elms, for a few settings. Training trees only: the held-out
silhouettes the image models are scored on are not used.

Usage: python scripts/fit_settings.py [--n 40] [--seed 0]
Writes results/fit_settings.json.
"""
import argparse, json, os, platform, sys, time
from pathlib import Path
import provenance   # scripts/provenance.py, beside this script
import numpy as np
from tqdm.auto import tqdm
from treebook.datasets import load_trees
from treebook.scan import silhouette
from treebook.condition import fit_silhouette, silhouette_scores

root = Path(__file__).resolve().parent.parent
p = argparse.ArgumentParser()
p.add_argument("--data", default="data/elm"); p.add_argument("--n", type=int, default=40); p.add_argument("--seed", type=int, default=0)
a = p.parse_args()
train = load_trees(root / a.data, "train")
rng = np.random.default_rng(a.seed)
targets = rng.choice(len(train), a.n, replace=False)
sources = rng.choice(len(train), a.n, replace=False)

def bend(t):
    "Mean angle (degrees) between each child branch and its parent, as the front camera sees them."
    d = (t.end - t.start)[:, [0, 2]]; ch = np.flatnonzero(t.parent >= 0)
    u, v = d[ch], d[t.parent[ch]]
    c = (u * v).sum(1) / np.maximum(np.linalg.norm(u, axis=1) * np.linalg.norm(v, axis=1), 1e-12)
    return float(np.degrees(np.arccos(np.clip(c, -1, 1))).mean())

settings = {"as grown": None, "straight to the nearest pixel": dict(steps=0, snap_px=40),
            "8 steps, snap 4 px": dict(steps=8), "16 steps, no snap": dict(snap_px=0), "16 steps, snap 4 px (default)": {}}
rows = {}
for name, kw in tqdm(settings.items(), desc="settings"):
    iou, b = [], []
    for ti, si in zip(targets, sources):
        target = silhouette(train[ti])
        g = train[si] if kw is None else fit_silhouette(train[si], target, **kw)
        iou.append(silhouette_scores(silhouette(g), target)["iou"]); b.append(bend(g))
    rows[name] = {"iou": float(np.mean(iou)), "bend_degrees": float(np.mean(b)), "kwargs": kw}
res = {"command": " ".join(["python scripts/fit_settings.py", *sys.argv[1:]]),
       "commit": provenance.commit(),
       "time": time.strftime("%Y-%m-%d %H:%M:%S"), "machine": {"platform": platform.platform(), "cpus": os.cpu_count()},
       "pairs": a.n, "rows": rows}
(root / "results").mkdir(exist_ok=True)
(root / "results" / "fit_settings.json").write_text(json.dumps(res, indent=1))
print(json.dumps(rows, indent=1))
