"""The one results file chapter 09a reads: `python scripts/partnet_results.py [--at REV]` -> results/partnet.json.

Gathers the records of the TreePartNet runs (results/partnet_*.json, and the clustering table of
results/reconstruct.json) into one curated file. With --at, the records are read as they were at that commit
(`git show REV:results/...`), so that the file can be made again once the records have left the tree."""
import argparse, json, subprocess
from provenance import ROOT, commit

ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
ap.add_argument("--at", help="read the records at this commit instead of the working tree")
ap.add_argument("--out", default=str(ROOT / "results" / "partnet.json"))
a = ap.parse_args()
git = lambda *args: subprocess.run(["git", *args], cwd=ROOT, check=True, capture_output=True, text=True).stdout
at = git("rev-parse", a.at).strip() if a.at else None
read = lambda f: json.loads(git("show", f"{at}:results/{f}") if at else (ROOT / "results" / f).read_text())
R = {f: read(f"partnet_{f}.json") for f in ("train_soup", "held600_soup", "large_soup", "eval60_soup", "confirm_soup",
     "context", "train_tta1_closure", "train", "eval60_base", "train_patch", "eval60_patch", "train_joint3",
     "eval60_joint3", "eval60_jseeds", "train_jseeds_noretrain", "train_jseeds", "eval60_ft", "train_8k",
     "eval60_8k", "errors_soup", "ablation")}
ctx = R["context"]["tests"]
set_ = lambda name, r: dict(name=name, scans=len(r["per_scan"]["aff_f1"]), metrics=r["metrics"], per_scan=r["per_scan"])
held = [set_("600 scans, seed 980", R["held600_soup"]), set_("300 scans, seed 990", R["large_soup"]),
        set_("60 scans, seed 999", R["eval60_soup"]), set_("60 scans, seed 998", R["confirm_soup"]),
        set_("60 scans, seed 997", ctx["997x10"]["network"])]
step = lambda name, r30, r60=None, half=False: dict(name=name, scans30=r30["metrics_at_half" if half else "metrics"],
                                                    scans60=r60["metrics"] if r60 else None)
additions = [step("the pair term; one pass, closure at 0.5", R["train_tta1_closure"]),
             step("+ four test-time turns", R["train"], half=True),
             step("+ average linkage, threshold chosen on training scans", R["train"], R["eval60_base"]),
             step("+ the patch term, trained alone", R["train_patch"], R["eval60_patch"]),
             step("+ the whole network fine-tuned", R["train_joint3"], R["eval60_joint3"]),
             step("+ the mean of three longer runs (shipped)", R["train_soup"], R["eval60_soup"])]
pool = lambda k, key: [x for s in ("999x10", "998x10", "997x10") for x in ctx[s][k]["per_scan"][key]]
mean = lambda x: sum(x) / len(x)
pc = {k: dict(aff_f1=mean(pool(k, "aff_f1")), f1=mean(pool(k, "f1")), nmi=mean(pool(k, "nmi")),
              point_f1=mean([ctx[s][k]["metrics"]["point_f1"] for s in ctx])) for k in ("network", "with context")}
four = lambda m: {k: m[k] for k in ("aff_f1", "f1", "nmi", "point_f1")}
off = lambda name, scans, w, o: {"name": name, "scans": scans, "without": four(w), "with": four(o)}
options = [off("seeds off the junctions", 30, R["train"]["metrics"], R["train_jseeds_noretrain"]["metrics"]),
           off("seeds off the junctions", 60, R["eval60_base"]["metrics"], R["eval60_jseeds"]["metrics"]),
           off("seeds off the junctions, trained so", 60, R["eval60_base"]["metrics"], R["eval60_ft"]["metrics"]),
           off("all 8,192 points, trained so", 60, R["eval60_base"]["metrics"], R["eval60_8k"]["metrics"]),
           off("a pair context", 180, pc["network"], pc["with context"])]
E = R["errors_soup"]
out = dict(command="python scripts/partnet_results.py" + (f" --at {at}" if at else ""), commit=at or commit(),
           shipped={k: R["train_soup"][k] for k in ("metrics", "metrics_at_half", "threshold", "linkage", "tta")},
           held_out=held, additions=additions, options_off=options,
           errors={k: E[k] for k in ("scans", "affinity_f1", "lone_seed_share", "by_smaller_part_seeds")},
           clustering=read("reconstruct.json")["clustering"], ablation=R["ablation"],
           sources={f"partnet_{f}.json": dict(command=r.get("command"), commit=r.get("commit")) for f, r in R.items()})
(ROOT / "results").mkdir(exist_ok=True)
open(a.out, "w").write(json.dumps(out, indent=1) + "\n")
print(f"wrote {a.out}")
