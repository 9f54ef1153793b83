"""The paper's full growth layout (every stage written whole, [STAGE] between stages) on small elms: is containment learned?

Usage (resumable): python scripts/growth_full_layout.py --out runs/growth-full --branches 30 --trees 2000 --steps 500 [--threads 1]
A tiny hourglass (from scratch) learns growth sequences of elms grown to at most --branches branches; we sample --samples
sequences and measure containment (share of stage-k branches found again, within one bin, in stage k+1), against the
procedural histories (1.0) and against unrelated stages (a chance level). Writes results/growth_full.json.
"""
import argparse, json, os, platform, sys, time
from pathlib import Path
import provenance   # scripts/provenance.py, beside this script
import numpy as np, torch
from treebook.botany import grow
from treebook.tokens import Tokenizer
from treebook.hourglass import ModelConfig, TreeTransformer
from treebook.growth import encode_growth, decode_growth, containment, fit, growth_batch, lm_loss, generate

root = Path(__file__).resolve().parent.parent
p = argparse.ArgumentParser()
p.add_argument("--out", default="runs/growth-full"); p.add_argument("--branches", type=int, default=30)
p.add_argument("--trees", type=int, default=2000); p.add_argument("--steps", type=int, default=500); p.add_argument("--batch", type=int, default=8)
p.add_argument("--dim", type=int, default=64); p.add_argument("--depth", type=int, default=5); p.add_argument("--heads", type=int, default=4)
p.add_argument("--lr", type=float, default=2e-3); p.add_argument("--samples", type=int, default=32); p.add_argument("--threads", type=int, default=1)
p.add_argument("--time-limit", type=float, default=None); p.add_argument("--seed", type=int, default=0)
a = p.parse_args()
torch.set_num_threads(a.threads)
out = root / a.out; out.mkdir(parents=True, exist_ok=True)
hist = [grow("elm", seed=s, max_branches=a.branches) for s in range(a.trees)]
held = [grow("elm", seed=10 ** 6 + s, max_branches=a.branches) for s in range(a.samples)]
finals = [h[-1] for h in hist]
tok = Tokenizer.fit(finals)
L = max(len(encode_growth(tok, h, mode="full")) for h in hist + held)
torch.manual_seed(a.seed)
net = TreeTransformer(ModelConfig(arch="full", dim=a.dim, depth=a.depth, heads=a.heads, max_len=L + 64))
# growth_batch encodes a final tree with `stage`; the full layout rebuilds the stage trees with botany.stage_tree (pipe radii)
r = fit(net, lambda k: growth_batch(finals, tok, k, a.batch, a.seed, 10, mode="full"), lm_loss, out, steps=a.steps, lr=a.lr,
        warmup=20, ckpt_every=10, time_limit=a.time_limit)
print(json.dumps(r), flush=True)
t0 = time.time()
seqs = generate(net, a.samples, tok=tok, stages=10, mode="full", temperature=0.9, top_p=0.95, seed=a.seed)
samples = [decode_growth(tok, s, mode="full") for s in seqs]
mixed = [[held[(j + k) % len(held)][k] for k in range(10)] for j in range(len(held))]   # stage k of another tree: chance level
res = {"command": "python scripts/growth_full_layout.py " + " ".join(sys.argv[1:]),
       "commit": provenance.commit(),
       "time": time.strftime("%Y-%m-%d %H:%M:%S"),
       "machine": {"platform": platform.platform(), "cpus": os.cpu_count(), "threads": a.threads, "torch": torch.__version__},
       "run": r | {"n_params": net.n_params, "max_len": net.config.max_len, "trees": a.trees, "max_branches": a.branches},
       "containment": {"samples": float(np.nanmean([containment(h, tok) for h in samples])),
                       "procedural": float(np.mean([containment(h, tok) for h in held])),
                       "unrelated_stages": float(np.mean([containment(h, tok) for h in mixed]))},
       "branches_per_stage": {"samples": np.mean([[t.n for t in h] for h in samples], 0).round(1).tolist(),
                              "data": np.mean([[t.n for t in h] for h in held], 0).round(1).tolist()},
       "seconds_sampling": time.time() - t0}
(root / "results").mkdir(exist_ok=True)
(root / "results" / "growth_full.json").write_text(json.dumps(res, indent=1))
print(json.dumps(res, indent=1))
