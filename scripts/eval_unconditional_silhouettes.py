"""Baseline for image / sketch to tree: silhouette IoU, precision, recall and F1 of *unconditional* samples against the same
held-out silhouettes the conditional models are scored on (results/conditions.json). If a conditional model does not beat
this row, its condition is not being used.

Usage: python scripts/eval_unconditional_silhouettes.py --model elm [--n-eval 50] [--seed 0] [--fit] [--candidates 4]
Adds the row "unconditional/<name>[+fit][+bestK]" to results/conditions.json and writes results/conditions_unconditional[_fit][_bestK].json.
With --fit each sample is fitted to the held-out silhouette (condition.fit_silhouette); with --candidates K the best of K
samples by silhouette IoU is kept: the same steps `image_to_tree(fit=..., candidates=...)` takes after the image model.
"""
import argparse, json, os, platform, sys, time
from pathlib import Path
import provenance   # scripts/provenance.py, beside this script
import numpy as np, torch
from treebook.datasets import load_trees
from treebook.scan import silhouette
from treebook.train import load_pretrained
from treebook.growth import generate
from treebook.condition import best_by_silhouette

root = Path(__file__).resolve().parent.parent
p = argparse.ArgumentParser()
p.add_argument("--model", default="elm"); p.add_argument("--data", default="data/elm"); p.add_argument("--n-eval", type=int, default=50)
p.add_argument("--seed", type=int, default=0); p.add_argument("--threads", type=int, default=1)
p.add_argument("--fit", action="store_true"); p.add_argument("--candidates", type=int, default=1)
a = p.parse_args()
if a.candidates < 1: p.error("--candidates must be at least 1")
variant = ("+fit" if a.fit else "") + (f"+best{a.candidates}" if a.candidates > 1 else "")
torch.set_num_threads(a.threads)
test = load_trees(root / a.data, "test")[:a.n_eval]
net, tok = load_pretrained(a.model)
rows = []
for i, t in enumerate(test):   # the same seeds as evaluate_image: sample i uses seed + i
    gs = [tok.decode(s) for s in generate(net, a.candidates, tok=tok, temperature=0.9, top_p=0.95, seed=a.seed + i)]
    rows.append(best_by_silhouette(gs, silhouette(t), fit=a.fit)[1])  # one candidate, no fit: that sample's own scores
ev = {k: float(np.mean([r[k] for r in rows])) for k in rows[0]} | {"n": len(rows)}
meta = torch.load(a.model, weights_only=True).get("meta", {}) if Path(a.model).suffix == ".pt" else {}
res = {"command": "python scripts/eval_unconditional_silhouettes.py " + " ".join(sys.argv[1:]),
       "commit": provenance.commit(),
       "time": time.strftime("%Y-%m-%d %H:%M:%S"), "model": a.model, "model_step": meta.get("step"),
       "machine": {"platform": platform.platform(), "cpus": os.cpu_count(), "threads": a.threads, "torch": torch.__version__},
       "eval": ev}
name = "conditions_unconditional" + variant.replace("+", "_")
(root / "results" / f"{name}.json").write_text(json.dumps(res, indent=1))
tp = root / "results" / "conditions.json"
table = json.loads(tp.read_text()) if tp.exists() else {"table": {}}
table["table"][f"unconditional/{Path(a.model).stem}{variant}"] = {"step": meta.get("step"), **ev,
                                                          "details": {"record": f"results/{name}.json", **{k: v for k, v in res.items() if k != "eval"}}}
tp.write_text(json.dumps(table, indent=1))
print(json.dumps(res, indent=1))
