"""Does a conditional model use its condition? The held-out loss of each shipped conditional model with each tree's own
condition (matched) and with another tree's (shuffled: the batch's conditions rolled by one). A model that reads its
input does worse with the wrong one; equal losses mean the condition is ignored.

Usage: python scripts/condition_usage.py [--models elm-image,elm-sketch,elm-points] [--batches 4] [--threads 2]
Writes results/condition_usage.json.
"""
import argparse, json, os, platform, sys, time
from pathlib import Path
import provenance   # scripts/provenance.py, beside this script
import numpy as np, torch
from treebook.datasets import load_trees
from treebook.condition import load_conditional, cond_batch, input_reliance

root = Path(__file__).resolve().parent.parent
p = argparse.ArgumentParser()
p.add_argument("--models", default="elm-image,elm-sketch,elm-points"); p.add_argument("--data", default="data/elm")
p.add_argument("--batches", type=int, default=4); p.add_argument("--seed", type=int, default=7); p.add_argument("--threads", type=int, default=2)
a = p.parse_args()
torch.set_num_threads(a.threads)
test = load_trees(root / a.data, "test")[:50]
rows = {}
for name in a.models.split(","):
    model, tok = load_conditional(name)
    # the batches of train_conditions.py's held-out loss (seed + 7, no augmentation)
    r = [input_reliance(model, cond_batch(model.kind, test, tok, k, 8, a.seed, "dfs", False)) for k in range(a.batches)]
    matched, shuffled = [x["own"] for x in r], [x["other"] for x in r]
    rows[name] = {"kind": model.kind, "matched": float(np.mean(matched)), "shuffled": float(np.mean(shuffled)),
                  "gain_nats_per_token": float(np.mean(shuffled) - np.mean(matched))}
    print(name, rows[name], flush=True)
res = {"command": " ".join(["python scripts/condition_usage.py", *sys.argv[1:]]),
       "commit": provenance.commit(),
       "time": time.strftime("%Y-%m-%d %H:%M:%S"), "machine": {"platform": platform.platform(), "cpus": os.cpu_count(), "threads": a.threads},
       "batches_of_8": a.batches, "rows": rows}
(root / "results").mkdir(exist_ok=True)
(root / "results" / "condition_usage.json").write_text(json.dumps(res, indent=1))
