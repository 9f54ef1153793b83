"""The growth runs of chapter 10 (HourglassTree 4.3, Figure 12), one subcommand each; the training is resumable.
  train         train the `elm-grow` model (`growth_run`), evaluate it, --ship it: results/growth.json, growth_sample/
  full-layout   the paper's full layout on small elms: is containment learned? (`full_layout_run`) results/growth_full.json
  completion    held-out elms cut to a DFS prefix, completed --n times (`completion_figure`): results/completion.{png,json}
Usage: python scripts/growth.py train --out runs/elm-grow --init runs/elm/best.pt --trees 2000 --steps 300 [--ship]
       python scripts/growth.py train --out runs/elm-grow --eval-only --ship   (evaluate the run as it stands, ship it)
       python scripts/growth.py full-layout --out runs/growth-full --branches 30 --trees 2000 --steps 500 [--threads 1]
       python scripts/growth.py completion [--model elm | PATH.pt] [--n 4] [--seed 0] [--cut 0.25] [--trees 3]"""
import argparse, json, shutil, time
from pathlib import Path
import provenance   # scripts/provenance.py, beside this script
import torch
from treebook.train import WEIGHTS
from treebook.growth import completion_figure, evaluate_growth, full_layout_run, growth_card, growth_run, write_growth

ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
sub = ap.add_subparsers(dest="cmd", required=True)
flags = {"train": dict(dim=64, depth=5, heads=4, trees=2000, steps=300, batch=8, warmup=20, threads=1, samples=16,
                       val=32, seed=0, out="runs/elm-grow", data="data/elm", init=None, lr=1e-3, time_limit=None),
         "full-layout": dict(out="runs/growth-full", branches=30, trees=2000, steps=500, batch=8, lr=2e-3, dim=64,
                             depth=5, heads=4, samples=32, threads=1, time_limit=None, seed=0),
         "completion": dict(model="elm", n=4, seed=0, cut=0.25, trees=3, threads=1)}
for name, fl in flags.items():
    p = sub.add_parser(name)
    for k, v in fl.items():
        p.add_argument(f"--{k.replace('_', '-')}", default=v, type=float if k in ("lr", "cut", "time_limit") else
                       int if isinstance(v, int) else str)
    if name == "train": p.add_argument("--eval-only", action="store_true"); p.add_argument("--ship", action="store_true")
a = ap.parse_args(); torch.set_num_threads(a.threads); R = provenance.ROOT
script = "scripts/growth.py"   # the record's command adds the subcommand and its flags
if a.cmd == "train":
    kw = {k: getattr(a, k) for k in flags["train"] if k not in ("threads", "out", "data")}
    net, tok, run, held = growth_run(R / a.out, R / a.data, **kw, train=not a.eval_only)
    res = {"run": run}
    if a.eval_only and (R / "results" / "growth.json").exists():     # keep the command that trained the run
        old = json.loads((R / "results" / "growth.json").read_text())
        res["train_command"] = old.get("train_command", old.get("command"))
    rec, samples = evaluate_growth(net, tok, held, 10, a.samples, a.val, a.seed)
    write_growth(samples[0], R / "results" / "growth_sample", meshes=False)
    _ = [f.unlink() for f in (R / "results" / "growth_sample").glob("stage_*.npz")]
    res = provenance.record(script, res | rec, "results/growth.json", threads=a.threads, torch=torch.__version__)
    print(json.dumps(res, indent=1))
    if a.ship:
        net.save(WEIGHTS / "elm-grow.pt", step=run["step"], val_loss=res["val"]["loss"], order="dfs",
                 growth="incremental", stages=10)
        shutil.copyfile(R / a.out / "tokenizer.json", WEIGHTS / "elm-grow.tok.json")
        (WEIGHTS / "elm-grow.md").write_text(growth_card(net, res))
elif a.cmd == "full-layout":
    kw = {k: getattr(a, k) for k in flags["full-layout"] if k not in ("threads", "out")}
    res = provenance.record(script, full_layout_run(R / a.out, **kw), "results/growth_full.json", threads=a.threads,
                            torch=torch.__version__)
    print(json.dumps(res, indent=1))
else:
    meta = torch.load(a.model, weights_only=True).get("meta", {}) if Path(a.model).suffix == ".pt" else {}
    t0 = time.time(); rows, fig = completion_figure(a.model, a.n, a.seed, a.cut, a.trees)
    fig.save(R / "results" / "completion.png")
    res = {"model": a.model, "model_meta": {k: v for k, v in meta.items() if k in ("step", "val_loss")},
           "seconds": time.time() - t0, "trees": rows, "all_prompts_kept": all(r["prompt_kept_exactly"] for r in rows),
           "all_distinct": all(r["pairwise_distinct"] for r in rows)}
    print(json.dumps(provenance.record(script, res, "results/completion.json"), indent=1))
