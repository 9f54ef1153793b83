"""Train the `elm-grow` growth model (HourglassTree 4.3), evaluate it, and optionally ship it.

Usage (resumable: run the same command again after a kill):
    python scripts/train_growth.py --out runs/elm-grow --init runs/elm/best.pt --trees 2000 --steps 300 --threads 1 [--time-limit S] [--ship]
    python scripts/train_growth.py --out runs/elm-grow --eval-only --ship      (evaluate the run as it stands and ship it)

Data: the growth histories (10 stages, `botany.grow`) of the training trees of data/elm (the same seeds as the `elm` dataset,
regrown with stages=10), the incremental layout of `treebook.growth.encode_growth`. The decoder starts from `--init`
(an unconditional checkpoint, its tokenizer beside it) with room for the nine [STAGE] blocks, or from scratch (--dim ...).
Writes results/growth.json (command, commit, machine, steps, losses, containment, stage statistics).
"""
import argparse, json, os, platform, shutil, sys, time
from pathlib import Path
import provenance   # scripts/provenance.py, beside this script
import numpy as np, torch
from treebook.tree import Tree
from treebook.botany import grow
from treebook.datasets import load_manifest
from treebook.tokens import Tokenizer
from treebook.hourglass import ModelConfig, TreeTransformer
from treebook.train import WEIGHTS, perplexity, load_pretrained
from treebook.growth import (encode_growth, decode_growth, containment, extend_context, fit, growth_batch, lm_loss,
                             generate, write_growth)

root = Path(__file__).resolve().parent.parent
p = argparse.ArgumentParser()
p.add_argument("--out", default="runs/elm-grow"); p.add_argument("--data", default="data/elm")
p.add_argument("--init", default=None, help="unconditional checkpoint (.pt with tokenizer beside it) or shipped name")
p.add_argument("--dim", type=int, default=64); p.add_argument("--depth", type=int, default=5); p.add_argument("--heads", type=int, default=4)
p.add_argument("--trees", type=int, default=2000); p.add_argument("--steps", type=int, default=300)
p.add_argument("--batch", type=int, default=8); p.add_argument("--lr", type=float, default=1e-3); p.add_argument("--warmup", type=int, default=20)
p.add_argument("--threads", type=int, default=1); p.add_argument("--time-limit", type=float, default=None)
p.add_argument("--samples", type=int, default=16); p.add_argument("--val", type=int, default=32); p.add_argument("--seed", type=int, default=0)
p.add_argument("--eval-only", action="store_true"); p.add_argument("--ship", action="store_true")
a = p.parse_args()
torch.set_num_threads(a.threads)
out = root / a.out if not Path(a.out).is_absolute() else Path(a.out)
out.mkdir(parents=True, exist_ok=True)
STAGES, MAX_BRANCHES = 10, 200

# 1. growth histories of the elm dataset's trees (cached: growing 2,000 elms takes a few minutes on one thread)
m = load_manifest(root / a.data)
cache = out / "histories.npz"
def histories(idx, key):
    if (out / f"{key}.npz").exists():
        z = np.load(out / f"{key}.npz"); off = z["offsets"]
        return [Tree(z["start"][i:j], z["end"][i:j], z["parent"][i:j], stage=z["stage"][i:j]) for i, j in zip(off[:-1], off[1:])]
    ts = [grow("elm", seed=m["seeds"][i], stages=STAGES, max_branches=MAX_BRANCHES)[-1] for i in idx]
    cat = lambda k: np.concatenate([getattr(t, k) for t in ts])
    np.savez(out / f"{key}.npz", start=cat("start"), end=cat("end"), parent=cat("parent"), stage=cat("stage"),
             offsets=np.concatenate([[0], np.cumsum([t.n for t in ts])]))
    return ts
train = histories(m["splits"]["train"][:a.trees], "train_histories")
test = histories(m["splits"]["test"][:max(a.val, a.samples)], "test_histories")
print(f"{len(train)} training histories, {len(test)} held out", flush=True)

# 2. model: from --init (extended by nine [STAGE] blocks) or from scratch; the tokenizer of --init, else fitted
max_len = 8 * (MAX_BRANCHES + STAGES - 1 + 2)
if a.init:
    net, tok = load_pretrained(a.init)
    net = extend_context(net, max_len)
else:
    tok = Tokenizer.fit(train)
    torch.manual_seed(a.seed)
    net = TreeTransformer(ModelConfig(arch="full", dim=a.dim, depth=a.depth, heads=a.heads, max_len=max_len))
tok.save(out / "tokenizer.json")
meta = {"init": a.init, "trees": len(train), "batch": a.batch, "lr": a.lr, "seed": a.seed}
if a.init and Path(a.init).suffix == ".pt": meta["init_meta"] = {k: v for k, v in torch.load(a.init, weights_only=True).get("meta", {}).items() if k in ("step", "val_loss")}
if not a.eval_only:
    r = fit(net, lambda k: growth_batch(train, tok, k, a.batch, a.seed, STAGES), lm_loss, out, steps=a.steps, lr=a.lr,
            warmup=a.warmup, ckpt_every=5, log_every=5, time_limit=a.time_limit, meta=meta)
    print(json.dumps(r), flush=True)
ck = torch.load(out / "last.pt", weights_only=True)
net.load_state_dict(ck["model"]); net.eval()

# 3. evaluation: held-out loss, growth samples (containment, stages, branches per stage), a filmstrip
res = {"command": "python scripts/train_growth.py " + " ".join(sys.argv[1:]),
       "commit": provenance.commit(),
       "time": time.strftime("%Y-%m-%d %H:%M:%S"),
       "machine": {"platform": platform.platform(), "cpus": os.cpu_count(), "threads": a.threads, "torch": torch.__version__},
       "run": {"step": ck["step"], "steps_planned": a.steps, "seconds": ck["seconds"], "n_params": net.n_params, **meta,
               "config": vars(net.config)}}
if a.eval_only and (root / "results" / "growth.json").exists():     # keep the command that trained the run
    old = json.loads((root / "results" / "growth.json").read_text())
    res["train_command"] = old.get("train_command", old.get("command"))
seqs = np.stack([encode_growth(tok, t, STAGES, length=max_len) for t in test[:a.val]])
res["val"] = perplexity(net, seqs, batch_size=4)
t0 = time.time()
samples = []
for i in range(a.samples):
    s = generate(net, 1, tok=tok, stages=STAGES, temperature=0.9, top_p=0.95, seed=a.seed + i, progress=False)[0]
    samples.append(decode_growth(tok, s, STAGES))
res["seconds_sampling"] = time.time() - t0
res["containment"] = float(np.nanmean([containment(h, tok) for h in samples]))
res["containment_note"] = "incremental layout: stage k is a prefix of stage k+1 by construction; 1.0 checks the decoding"
res["stages_complete"] = float(np.mean([len(h) == STAGES and all(t.n for t in h) for h in samples]))
res["branches_per_stage"] = {"samples": np.mean([[t.n for t in h] for h in samples], 0).round(1).tolist(),
                             "data": np.mean([[int((t.stage <= k).sum()) for k in range(STAGES)] for t in test[:a.samples]], 0).round(1).tolist()}
(root / "results").mkdir(exist_ok=True)
write_growth(samples[0], root / "results" / "growth_sample", meshes=False)
_ = [p.unlink() for p in (root / "results" / "growth_sample").glob("stage_*.npz")]
(root / "results" / "growth.json").write_text(json.dumps(res, indent=1))
print(json.dumps(res, indent=1))
if a.ship:
    net.save(WEIGHTS / "elm-grow.pt", step=ck["step"], val_loss=res["val"]["loss"], order="dfs", growth="incremental", stages=STAGES)
    shutil.copyfile(out / "tokenizer.json", WEIGHTS / "elm-grow.tok.json")
    c = net.config
    card = f"""# elm-grow: an hourglass transformer that grows elms in ten stages

- **Data**: the growth histories (`botany.grow('elm', seed, stages=10, max_branches=200)`) of the first {len(train)} training trees of the `elm` dataset (`data/elm`, same seeds), in the incremental layout of `treebook.growth.encode_growth` (each stage's new branches in DFS order, one block of eight [STAGE] tokens between stages); rotation about z and mirroring.
- **Model**: arch `{c.arch}`, dim {c.dim}, depth {c.depth}, heads {c.heads}, {net.n_params:,} parameters, max_len {c.max_len}; {'started from `' + str(a.init) + '` (branch positions extended)' if a.init else 'trained from scratch'}.
- **Training**: AdamW, peak lr {a.lr}, {a.warmup} warm-up steps then cosine, batch {a.batch}; {ck['step']} of {a.steps} planned steps in {ck['seconds'] / 60:.0f} minutes on {a.threads} thread{'s' if a.threads > 1 else ''} of a 2-core CPU (give --eval-only the training run's --threads).
- **Command**: `{res.get('train_command', res['command'])}`{'; evaluated and shipped by `' + res['command'] + '`' if 'train_command' in res else ''}; commit {res['commit']}.
- **Metrics** (`results/growth.json`): held-out loss {res['val']['loss']:.3f} (perplexity {res['val']['ppl']:.1f}) on {a.val} histories; containment {res['containment']:.3f} over {a.samples} samples (1.0 by construction of the layout); all ten stages present in {100 * res['stages_complete']:.0f}% of samples; mean branches per stage, samples {res['branches_per_stage']['samples']} against data {res['branches_per_stage']['data']}.
- **Limits**: a small model trained briefly on a CPU: its trees are rougher than the procedural ones; retrain with more steps for better shapes.
"""
    (WEIGHTS / "elm-grow.md").write_text(card)
    print("shipped", WEIGHTS / "elm-grow.pt")
