"""Train the `elm-grow` growth model (HourglassTree 4.3; chapter 10), evaluate it, and optionally ship it.

Usage (resumable: run the same command again after a kill):
    python scripts/train_growth.py --out runs/elm-grow --init runs/elm/best.pt --trees 2000 --steps 300 [--ship]
    python scripts/train_growth.py --out runs/elm-grow --eval-only --ship   (evaluate the run as it stands, ship it)
From `--init` (a checkpoint or shipped name) or from scratch. Writes results/growth.json and results/growth_sample/.
"""
import argparse, json, shutil
import provenance   # scripts/provenance.py, beside this script
import torch
from treebook.datasets import load_manifest
from treebook.tokens import Tokenizer
from treebook.hourglass import ModelConfig, TreeTransformer
from treebook.train import WEIGHTS, load_pretrained
from treebook.growth import (evaluate_growth, extend_context, fit, grown_histories, growth_batch, growth_card, lm_loss,
                             write_growth)

p = argparse.ArgumentParser()
for k, v in dict(dim=64, depth=5, heads=4, trees=2000, steps=300, batch=8, warmup=20, threads=1, samples=16, val=32,
                 seed=0).items(): p.add_argument(f"--{k}", type=int, default=v)
p.add_argument("--out", default="runs/elm-grow"); p.add_argument("--data", default="data/elm"); p.add_argument("--init")
p.add_argument("--lr", type=float, default=1e-3); p.add_argument("--time-limit", type=float, default=None)
p.add_argument("--eval-only", action="store_true"); p.add_argument("--ship", action="store_true")
a = p.parse_args(); torch.set_num_threads(a.threads)
root, STAGES, out = provenance.ROOT, 10, provenance.ROOT / a.out; out.mkdir(parents=True, exist_ok=True)
m = load_manifest(root / a.data)
seeds = lambda split, k: [m["seeds"][i] for i in m["splits"][split][:k]]
train = grown_histories(seeds("train", a.trees), cache=out / "train_histories.npz")
test = grown_histories(seeds("test", max(a.val, a.samples)), cache=out / "test_histories.npz")
max_len = 8 * (200 + STAGES - 1 + 2)                   # 200 branches, nine [STAGE] blocks, [SOS] and [EOS]
if a.init: net, tok = load_pretrained(a.init); net = extend_context(net, max_len)
else:
    tok = Tokenizer.fit(train); torch.manual_seed(a.seed)
    net = TreeTransformer(ModelConfig(arch="full", dim=a.dim, depth=a.depth, heads=a.heads, max_len=max_len))
tok.save(out / "tokenizer.json")
meta = {"init": a.init, "trees": len(train), "batch": a.batch, "lr": a.lr, "seed": a.seed, "warmup": a.warmup,
        "val_histories": a.val, "samples": a.samples}
m0 = torch.load(a.init, weights_only=True).get("meta", {}) if (a.init or "").endswith(".pt") else None
if m0 is not None: meta["init_meta"] = {k: m0[k] for k in m0 if k in ("step", "val_loss")}
if not a.eval_only:
    batch = lambda k: growth_batch(train, tok, k, a.batch, a.seed, STAGES)
    print(json.dumps(fit(net, batch, lm_loss, out, steps=a.steps, lr=a.lr, warmup=a.warmup, ckpt_every=5, log_every=5,
                         time_limit=a.time_limit, meta=meta)))
ck = torch.load(out / "last.pt", weights_only=True); net.load_state_dict(ck["model"]); net.eval()
res = {"run": {"step": ck["step"], "steps_planned": a.steps, "seconds": ck["seconds"], "n_params": net.n_params, **meta,
               "config": vars(net.config)}}
if a.eval_only and (root / "results" / "growth.json").exists():     # keep the command that trained the run
    old = json.loads((root / "results" / "growth.json").read_text())
    res["train_command"] = old.get("train_command", old.get("command"))
rec, samples = evaluate_growth(net, tok, test, STAGES, a.samples, a.val, a.seed)
write_growth(samples[0], root / "results" / "growth_sample", meshes=False)
_ = [f.unlink() for f in (root / "results" / "growth_sample").glob("stage_*.npz")]
res = provenance.record("scripts/train_growth.py", res | rec, "results/growth.json", threads=a.threads,
                        torch=torch.__version__)
print(json.dumps(res, indent=1))
if a.ship:
    net.save(WEIGHTS / "elm-grow.pt", step=ck["step"], val_loss=res["val"]["loss"], order="dfs", growth="incremental",
             stages=STAGES)
    shutil.copyfile(out / "tokenizer.json", WEIGHTS / "elm-grow.tok.json")
    (WEIGHTS / "elm-grow.md").write_text(growth_card(net, res))
