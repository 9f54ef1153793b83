"""Train a conditional model (chapter 10a), evaluate it, ship it; resumable. --eval-only: the run as it stands (--fit
--candidates 4: fitted, best of 4); --device cuda --workers 12 --train-only: train on a GPU, write the training record.
Writes results/conditions_<kind>_<order>[_glimpse][_<tag>][_fit][_bestK].{json,png}, a row of results/conditions.json."""
import argparse, json, os, re, sys, time
import provenance   # scripts/provenance.py, beside this script
import torch
import treebook.condition as C
from treebook.datasets import load_trees
from treebook.train import WEIGHTS

p, R = argparse.ArgumentParser(description=__doc__), provenance.ROOT; p.add_argument("--order", default="dfs", choices=("dfs", "bfs"))
p.add_argument("--kind", required=True, choices=("image", "sketch", "points")); p.add_argument("--out", required=True)
for k, v in dict(data="data/elm", init=None, baseline=None, from_=None, device="cpu", tag="").items():
    p.add_argument(f"--{k.rstrip('_')}", dest=k, default=v)
for k, v in dict(dim=64, depth=5, heads=4, trees=4000, steps=300, batch=8, warmup=20, threads=1, n_eval=50, seed=0,
                 candidates=1, workers=0, lr=1e-3, time_limit=None).items():
    p.add_argument(f"--{k.replace('_', '-')}", type=float if k in ("lr", "time_limit") else int, default=v)
for k in ("eval-only", "ship", "fit", "no-broadcast", "glimpse", "train-only"): p.add_argument(f"--{k}", action="store_true")
a = p.parse_args()
variant = ("+fit" if a.fit else "") + (f"+best{a.candidates}" if a.candidates > 1 else "")
if variant and a.kind == "points": p.error("--fit and --candidates are for --kind image or sketch")
if variant and a.ship: p.error("--ship stores the network's own scores: ship without --fit / --candidates")
if a.train_only and (a.eval_only or a.ship or variant): p.error("--train-only stops after training: no --eval-only, --ship, --fit or --candidates")
if a.device != "cpu" and not torch.cuda.is_available(): p.error(f"--device {a.device}: no GPU is visible to PyTorch here")
torch.set_num_threads(a.threads); out = R / a.out; out.mkdir(parents=True, exist_ok=True)
train, test = load_trees(R / a.data, "train")[:a.trees], load_trees(R / a.data, "test")[:a.n_eval]
try: model, tok = C.conditional_model(a.kind, train, test, a.init, a.from_, a.glimpse, not a.no_broadcast, a.dim, a.depth, a.heads, a.seed)
except C.TreebookError as e: p.error(f"--from {e}" if a.from_ else str(e))
tok.save(out / "tokenizer.json")
meta = {"kind": a.kind, "order": a.order, "init": a.from_ or a.init, "broadcast": model.broadcast, "glimpse": a.glimpse,
        "trees": len(train), "batch": a.batch, "lr": a.lr, "seed": a.seed, "device": torch.cuda.get_device_name(a.device)
        if a.device != "cpu" else f"{a.threads} thread{'s' if a.threads > 1 else ''} of a {os.cpu_count()}-core CPU"}
if a.init and not a.from_ and a.init.endswith(".pt"):
    meta["init_meta"] = {k: v for k, v in torch.load(a.init, weights_only=True).get("meta", {}).items() if k in ("step", "val_loss")}
def make_batch(k): return C.cond_batch(a.kind, train, tok, k, a.batch, a.seed, a.order)   # in forked workers too
if not a.eval_only:
    r = C.train_conditional(model, make_batch, out, a.steps, a.lr, a.warmup, a.device, a.workers, a.time_limit, meta)
    print(json.dumps(r), flush=True)
base = f"conditions_{a.kind}_{a.order}" + ("_glimpse" if a.glimpse else "") + (f"_{a.tag}" if a.tag else "")
if a.train_only:   # the record --eval-only reads back: command, commit and machine of the training
    provenance.record("scripts/train_conditions.py", {"run": r | meta}, f"results/{base}.json", device=meta["device"],
                      torch=torch.__version__); print("trained; evaluate with --eval-only"); sys.exit(0)
model, ck = C.load_run(model, tok, out); meta["broadcast"] = model.broadcast
res = {"run": {"step": ck["step"], "steps_planned": None if a.eval_only else a.steps, "seconds": ck["seconds"],
               "n_params": sum(q.numel() for q in model.parameters()), **meta, **ck.get("meta", {}), "decoder": vars(model.decoder.config)}}
res["held_out_loss"], t0, name = C.held_out_loss(model, tok, test, a.order, a.seed + 7), time.time(), base + variant.replace("+", "_")
res |= {"eval": C.evaluate_conditional((model, tok), test, a.seed, a.fit, a.candidates, a.baseline), "seconds_eval": time.time() - t0}
if a.eval_only and (R / "results" / f"{base}.json").exists():   # keep the command that trained the run
    old = json.loads((R / "results" / f"{base}.json").read_text())
    res |= {f"train_{k}": old.get(f"train_{k}", old.get(k)) for k in ("command", "commit", "machine")}
    res["run"]["steps_planned"] = int(m.group(1)) if (m := re.search(r"--steps (\d+)", res["train_command"] or "")) else None
C.conditional_figure((model, tok), test[:4], a.seed, a.fit, a.candidates).save(R / "results" / f"{name}.png")
res = provenance.record("scripts/train_conditions.py", res, f"results/{name}.json", threads=a.threads, torch=torch.__version__)
key = f"{a.kind}/{a.order}{'+glimpse' if a.glimpse else ''}{'+' + a.tag if a.tag else ''}{variant}"
C.conditions_row(R / "results" / "conditions.json", key, {"step": ck["step"], "held_out_loss": res["held_out_loss"], **res["eval"]},
                 res, f"results/{name}.json"); print(json.dumps(res, indent=1))
if a.ship:
    C.save_conditional(model, tok, WEIGHTS / f"elm-{a.kind}.pt", **meta, step=ck["step"]); print("shipped", WEIGHTS / f"elm-{a.kind}.pt")
    (WEIGHTS / f"elm-{a.kind}.md").write_text(C.conditional_card(model, res, name, len(train), a.order, a.init, a.from_, a.lr,
                                                                  a.warmup, a.batch, a.steps, a.threads, a.n_eval, ck.get("meta", {}).get("device")))
