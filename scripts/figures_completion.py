"""Completion figure and check (HourglassTree Figure 12): held-out elms cut to a DFS prefix, completed n times.

Usage: python scripts/figures_completion.py [--model elm | PATH.pt] [--n 4] [--seed 0] [--cut 0.25] [--trees 3]
Writes results/completion.png (one row per tree: the given part, then the completions; given branches brown, new green)
and results/completion.json (command, commit, model, per tree: `growth.completion_check` and the sizes).
"""
import argparse, json, tempfile, time
from pathlib import Path
import provenance   # scripts/provenance.py, beside this script
import torch
from PIL import Image
from treebook.botany import grow
from treebook.growth import complete, completion_check, write_tree_set
from treebook.train import load_pretrained

p = argparse.ArgumentParser()
p.add_argument("--model", default="elm"); p.add_argument("--n", type=int, default=4)
p.add_argument("--seed", type=int, default=0); p.add_argument("--cut", type=float, default=0.25)
p.add_argument("--trees", type=int, default=3); p.add_argument("--threads", type=int, default=1)
a = p.parse_args()
torch.set_num_threads(a.threads)
meta = {}
if Path(a.model).suffix == ".pt":
    meta = torch.load(a.model, weights_only=True).get("meta", {})
    meta = {k: v for k, v in meta.items() if k in ("step", "val_loss")}
tok = load_pretrained(a.model)[1]
rows, pics, t0 = [], [], time.time()
with tempfile.TemporaryDirectory() as d:
    for k in range(a.trees):
        full = grow("elm", seed=10 ** 6 + k)[-1]                       # seeds far from the dataset's
        part = full.prefix(max(1, int(a.cut * full.n)), "dfs")
        out = complete(part, n=a.n, seed=a.seed + k, model=a.model)
        rows.append({"tree_seed": 10 ** 6 + k, "full_branches": full.n, "given": part.n,
                     "completed_branches": [t.n for t in out], **completion_check(part, out, tok)})
        write_tree_set(out, Path(d) / str(k), "completion", meshes=False, first=part)
        pics.append(Image.open(Path(d) / str(k) / "completion.png").convert("RGB"))
fig, y = Image.new("RGB", (max(i.width for i in pics), sum(i.height for i in pics)), "white"), 0
for i in pics: fig.paste(i, (0, y)); y += i.height
fig.save(provenance.ROOT / "results" / "completion.png")
res = {"model": a.model, "model_meta": meta, "seconds": time.time() - t0, "trees": rows,
       "all_prompts_kept": all(r["prompt_kept_exactly"] for r in rows),
       "all_distinct": all(r["pairwise_distinct"] for r in rows)}
res = provenance.record("scripts/figures_completion.py", res, "results/completion.json")
print(json.dumps(res, indent=1))
