"""The stages of each shipped species' model: the model it went on from, and the one before that, with the figures
each had when it shipped (chapter 05a, "Training goes on later").

A model that trained on from its species' shipped weights records the earlier model's steps (`run.init_from` in
results/NAME_eval.json). This walks the git history of that record, newest first, and follows the chain back: each
stage is the last record of the model with that many steps in all. A model that shipped and was replaced by one that
did not go on from it (two runs from one start, compared) is kept under "replaced". Writes results/model_stages.json.

    .venv/bin/python benchmarks/model_stages.py                       # every shipped species, a few seconds
    .venv/bin/python benchmarks/model_stages.py --species elm --out tmp/stages.json
"""
import argparse, json, subprocess, sys
from pathlib import Path
sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "scripts"))
import provenance   # scripts/provenance.py
from treebook.metrics import quality_targets
from treebook.species_runs import record_steps, run_key


def versions(path: str):
    "(commit, record) of each committed version of `path`, newest first."
    log = subprocess.run(["git", "log", "--format=%H", "--", path], capture_output=True, text=True,
                         cwd=provenance.ROOT, check=True).stdout.split()
    for c in log:
        text = subprocess.run(["git", "show", f"{c}:{path}"], capture_output=True, text=True, cwd=provenance.ROOT)
        if text.returncode == 0: yield c, json.loads(text.stdout)


def stage(r: dict, commit: str) -> dict:
    "The figures of one stage, from its evaluation record (the targets as counted today)."
    s, ref, run = r["scores"], r["reference_train_vs_test"], r["run"]
    met = quality_targets(r)
    return {"steps": record_steps(r), "run_steps": run["last_step"], "lr": run["args"].get("lr"),
            "window": run["args"].get("window") or 0,   # 0: full attention
            "minutes": round(run["train_seconds"] / 60, 1) if run.get("train_seconds") else None,
            "PPL": r["PPL"], "1-NNA": s["1-NNA"], "COV-CD": s["COV-CD"], "MMD-CD / ref": s["MMD-CD"] / ref["MMD-CD"],
            "JSD": s["JSD"], "FPD": s["FPD"], "Connect_free": r["Connect_free"]["Connect"],
            "decoding": r["sampling"].get("decoding", "structure-aware"),   # how the scored samples were drawn
            "met": sum(met.values()), "of": len(met), "held_out": r["data"]["test"], "commit": commit}


def stages(name: str) -> tuple:
    """The stages of `name`'s shipped model, oldest first, and the models that shipped and were replaced by one that
    did not go on from them (a run from the same start, compared), newest first."""
    found, replaced, seen, want = [], [], set(), None
    for c, r in versions(f"results/{name}_eval.json"):
        n, run = record_steps(r), r["run"]
        key = run_key(run)
        if want is None or n == want:
            found.append(stage(r, c)); seen.add(key)
            p0 = run.get("init_from")
            if not p0: break
            want = p0["steps"]
        elif key not in seen:   # a model no stage went on from (a record evaluated again is the same model)
            replaced.append(stage(r, c)); seen.add(key)
    if not found: raise SystemExit(f"error: results/{name}_eval.json has no committed version")
    return found[::-1], replaced


if __name__ == "__main__":
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--species", nargs="+", default=None, help="default: every species whose model ships")
    p.add_argument("--out", default="results/model_stages.json")
    a = p.parse_args()
    from treebook.train import shipped_species
    got = {n: stages(n) for n in (a.species or shipped_species())}
    res = {"species": {n: g[0] for n, g in got.items()}, "replaced": {n: g[1] for n, g in got.items() if g[1]}}
    provenance.record("benchmarks/model_stages.py", res, a.out)
    for n, st in res["species"].items():
        print(n, " -> ".join(f"{s['steps']:,} ({s['1-NNA']:.3f}, {s['met']} of {s['of']})" for s in st))
    for n, st in res["replaced"].items():
        print(n, "replaced:", ", ".join(f"{s['steps']:,} (window {s['window']}, {s['1-NNA']:.3f})" for s in st))
