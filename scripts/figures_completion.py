"""Completion figure and check (HourglassTree Figure 12): held-out elms cut to a DFS prefix, completed n times by a model.

Usage: python scripts/figures_completion.py [--model elm | PATH.pt] [--n 4] [--seed 0] [--cut 0.25] [--trees 3]
Writes results/completion.png (one row per tree: the given part, then the completions; given branches brown, new green)
and results/completion.json (command, commit, model, per tree: prompt kept exactly, completions pairwise distinct, sizes).
"""
import argparse, json, sys, tempfile, time
from pathlib import Path
import provenance   # scripts/provenance.py, beside this script
import numpy as np, torch
from PIL import Image
from treebook.botany import grow
from treebook.growth import complete, write_trees

root = Path(__file__).resolve().parent.parent
p = argparse.ArgumentParser()
p.add_argument("--model", default="elm"); p.add_argument("--n", type=int, default=4); p.add_argument("--seed", type=int, default=0)
p.add_argument("--cut", type=float, default=0.25); p.add_argument("--trees", type=int, default=3); p.add_argument("--threads", type=int, default=1)
a = p.parse_args()
torch.set_num_threads(a.threads)
meta = {}
if Path(a.model).suffix == ".pt": meta = {k: v for k, v in torch.load(a.model, weights_only=True).get("meta", {}).items() if k in ("step", "val_loss")}
rows, pics = [], []
t0 = time.time()
with tempfile.TemporaryDirectory() as d:
    for k in range(a.trees):
        full = grow("elm", seed=10 ** 6 + k)[-1]                       # seeds far from the dataset's
        part = full.prefix(max(1, int(a.cut * full.n)), "dfs")
        out = complete(part, n=a.n, seed=a.seed + k, model=a.model)
        from treebook.train import load_pretrained
        tok = load_pretrained(a.model)[1]
        ref = part.take(tok.order(part, "dfs", normalize=False))
        kept = all(np.array_equal(t.start[:part.n], ref.start) and np.array_equal(t.end[:part.n], ref.end)
                   and np.array_equal(t.parent[:part.n], ref.parent) for t in out)
        distinct = all(not (out[i].n == out[j].n and np.array_equal(out[i].end, out[j].end)) for i in range(len(out)) for j in range(i))
        rows.append({"tree_seed": 10 ** 6 + k, "full_branches": full.n, "given": part.n, "completed_branches": [t.n for t in out],
                     "prompt_kept_exactly": bool(kept), "pairwise_distinct": bool(distinct)})
        write_trees(out, Path(d) / str(k), "completion", meshes=False, first=part)
        pics.append(Image.open(Path(d) / str(k) / "completion.png").convert("RGB"))
w, h = max(i.width for i in pics), sum(i.height for i in pics)
fig = Image.new("RGB", (w, h), "white"); y = 0
for i in pics: fig.paste(i, (0, y)); y += i.height
fig.save(root / "results" / "completion.png")
res = {"command": "python scripts/figures_completion.py " + " ".join(sys.argv[1:]),
       "commit": provenance.commit(),
       "time": time.strftime("%Y-%m-%d %H:%M:%S"), "model": a.model, "model_meta": meta, "seconds": time.time() - t0, "trees": rows,
       "all_prompts_kept": all(r["prompt_kept_exactly"] for r in rows), "all_distinct": all(r["pairwise_distinct"] for r in rows)}
(root / "results" / "completion.json").write_text(json.dumps(res, indent=1))
print(json.dumps(res, indent=1))
