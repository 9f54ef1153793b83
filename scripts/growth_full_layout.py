"""The paper's full growth layout (every stage whole, [STAGE] between stages) on small elms: is containment learned?

Usage (resumable):
    python scripts/growth_full_layout.py --out runs/growth-full --branches 30 --trees 2000 --steps 500 [--threads 1]
A tiny hourglass (from scratch) learns growth sequences of elms of at most --branches branches; we sample --samples
sequences and measure containment (chapter 10, `growth_scores`), against the procedural histories (1.0) and against
unrelated stages (`stage_mix`, a chance level). Writes results/growth_full.json.
"""
import argparse, json, time
from pathlib import Path
import provenance   # scripts/provenance.py, beside this script
import numpy as np, torch
from treebook.botany import grow
from treebook.tokens import Tokenizer
from treebook.hourglass import ModelConfig, TreeTransformer
from treebook.growth import (encode_growth, decode_growth, containment, fit, growth_batch, growth_scores, lm_loss,
                             generate, stage_mix)

p = argparse.ArgumentParser()
p.add_argument("--out", default="runs/growth-full"); p.add_argument("--branches", type=int, default=30)
p.add_argument("--trees", type=int, default=2000); p.add_argument("--steps", type=int, default=500)
p.add_argument("--batch", type=int, default=8); p.add_argument("--lr", type=float, default=2e-3)
p.add_argument("--dim", type=int, default=64); p.add_argument("--depth", type=int, default=5)
p.add_argument("--heads", type=int, default=4); p.add_argument("--samples", type=int, default=32)
p.add_argument("--threads", type=int, default=1); p.add_argument("--time-limit", type=float, default=None)
p.add_argument("--seed", type=int, default=0)
a = p.parse_args()
torch.set_num_threads(a.threads)
out = provenance.ROOT / a.out; out.mkdir(parents=True, exist_ok=True)
hist = [grow("elm", seed=s, max_branches=a.branches) for s in range(a.trees)]
held = [grow("elm", seed=10 ** 6 + s, max_branches=a.branches) for s in range(a.samples)]
finals = [h[-1] for h in hist]
tok = Tokenizer.fit(finals)
L = max(len(encode_growth(tok, h, mode="full")) for h in hist + held)
torch.manual_seed(a.seed)
net = TreeTransformer(ModelConfig(arch="full", dim=a.dim, depth=a.depth, heads=a.heads, max_len=L + 64))
# growth_batch encodes a final tree with `stage`; the full layout rebuilds the stage trees with botany.stage_tree
r = fit(net, lambda k: growth_batch(finals, tok, k, a.batch, a.seed, 10, mode="full"), lm_loss, out, steps=a.steps,
        lr=a.lr, warmup=20, ckpt_every=10, time_limit=a.time_limit)
print(json.dumps(r), flush=True)
t0 = time.time()
seqs = generate(net, a.samples, tok=tok, stages=10, mode="full", temperature=0.9, top_p=0.95, seed=a.seed)
sc = growth_scores([decode_growth(tok, s, mode="full") for s in seqs], tok, held)
run = {"n_params": net.n_params, "max_len": net.config.max_len, "trees": a.trees, "max_branches": a.branches}
res = {"run": r | run,
       "containment": {"samples": sc["containment"],
                       "procedural": float(np.mean([containment(h, tok) for h in held])),
                       "unrelated_stages": float(np.mean([containment(h, tok) for h in stage_mix(held)]))},
       "branches_per_stage": sc["branches_per_stage"], "seconds_sampling": time.time() - t0}
res = provenance.record("scripts/growth_full_layout.py", res, "results/growth_full.json", threads=a.threads,
                        torch=torch.__version__)
print(json.dumps(res, indent=1))
