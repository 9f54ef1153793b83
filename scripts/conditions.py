"""Measurements of the conditional models (chapter 10a), each writing its record under results/:

python scripts/conditions.py usage [--models elm-image,elm-sketch,elm-points] [--batches 4]   condition_usage.json
python scripts/conditions.py unconditional --model elm [--fit] [--candidates 4]   conditions_unconditional[_fit][_bestK]
    .json and the row unconditional/<model>[+fit][+bestK] of conditions.json (the baseline of image and sketch to tree)
python scripts/conditions.py fit-settings [--n 40]   fit_settings.json (how fit_silhouette was set, on training trees)
python scripts/conditions.py ceiling [--pool 3000]   silhouette_ceiling.json (the best of the training elms by IoU)
"""
import argparse, json, time
from pathlib import Path
import provenance   # scripts/provenance.py, beside this script
import torch
import treebook.condition as C
from treebook.datasets import load_trees

ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
sub = ap.add_subparsers(dest="what", required=True)
def command(name, seed=0, **flags):
    p = sub.add_parser(name); p.add_argument("--data", default="data/elm"); p.add_argument("--seed", type=int, default=seed)
    for k, v in flags.items():
        p.add_argument(f"--{k.replace('_', '-')}", **({"action": "store_true"} if v is False else {"type": type(v), "default": v}))
command("usage", seed=7, models="elm-image,elm-sketch,elm-points", batches=4, threads=2)
command("unconditional", model="elm", n_eval=50, threads=1, fit=False, candidates=1)
command("fit-settings", n=40); command("ceiling", pool=3000, n_eval=50)
a = ap.parse_args()
R, t0 = provenance.ROOT, time.time()
record = lambda res, out, **machine: provenance.record(f"scripts/conditions.py", res, f"results/{out}.json", **machine)
if a.what == "usage":
    torch.set_num_threads(a.threads)
    rows = C.condition_usage(a.models.split(","), load_trees(R / a.data, "test")[:50], a.batches, a.seed)
    print(json.dumps(rows, indent=1)); record({"batches_of_8": a.batches, "rows": rows}, "condition_usage", threads=a.threads)
elif a.what == "unconditional":
    if a.candidates < 1: ap.error("--candidates must be at least 1")
    torch.set_num_threads(a.threads)
    ev = C.unconditional_silhouettes(a.model, load_trees(R / a.data, "test")[:a.n_eval], a.seed, a.fit, a.candidates)
    meta = torch.load(a.model, weights_only=True).get("meta", {}) if Path(a.model).suffix == ".pt" else {}
    variant = ("+fit" if a.fit else "") + (f"+best{a.candidates}" if a.candidates > 1 else "")
    name = "conditions_unconditional" + variant.replace("+", "_")
    res = record({"model": a.model, "model_step": meta.get("step"), "eval": ev}, name, threads=a.threads, torch=torch.__version__)
    C.conditions_row(R / "results" / "conditions.json", f"unconditional/{Path(a.model).stem}{variant}", {"step": meta.get("step"), **ev},
                     res, f"results/{name}.json"); print(json.dumps(res, indent=1))
elif a.what == "fit-settings":
    rows = C.fit_settings(load_trees(R / a.data, "train"), a.n, a.seed)
    record({"pairs": a.n, "rows": rows}, "fit_settings"); print(json.dumps(rows, indent=1))
else:
    res = C.silhouette_ceiling(load_trees(R / a.data, "train"), load_trees(R / a.data, "test")[:a.n_eval], a.pool, a.seed)
    print(json.dumps(record(res | {"seconds": time.time() - t0}, "silhouette_ceiling"), indent=1))
