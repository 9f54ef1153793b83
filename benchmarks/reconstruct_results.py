"""The one results file chapter 09b reads, results/reconstruction.json: `python benchmarks/reconstruct_results.py`.

Takes from the benchmark records what the chapter shows: speed, real scans and skeletons of results/reconstruct.json,
the AdTree table of results/reconstruct_peer.json, results/reconstruct_trees.json (find_trees),
results/reconstruct_voxel.json (VOXEL) and results/reconstruct_speed.json (whole processes). Each part keeps the
command, commit and machine of the run that made it. Run it again whenever one of those records changes; with --at REV
the records are read as they were at that commit."""
import argparse, json, subprocess, sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "scripts"))
from provenance import commit  # noqa: E402

ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
ap.add_argument("--at", help="read the records at this commit instead of the working tree")
ap.add_argument("--out", default=str(ROOT / "results" / "reconstruction.json"))
a = ap.parse_args()
git = lambda *args: subprocess.run(["git", *args], cwd=ROOT, check=True, capture_output=True, text=True).stdout
at = git("rev-parse", a.at).strip() if a.at else None
read = lambda f: json.loads(git("show", f"{at}:results/{f}") if at else (ROOT / "results" / f).read_text())
source = lambda r, *extra: {k: r[k] for k in ("command", "commit", "machine", *extra) if k in r}

B = read("reconstruct.json")   # its parts were refreshed by later runs (`updates`): each part names its latest


def part(name):
    last = [u for u in B.get("updates", []) if name in u["parts"]]
    return dict(source(last[-1] if last else B), record="results/reconstruct.json")


P = read("reconstruct_peer.json")
CONDS, METHODS = ["sparse", "noisy", "holes", "dense", "leafy", "station", "tls", "real"], ["paths", "classic", "partnet",
                                                                                   "adtree", "truth"]
COLS = ["f1_tight", "surf_within", "len_ratio", "one_component", "seconds"]
S = {k.replace("_cli", ""): v for k, v in P["summary"].items()}   # --cli runs tag treebook's methods `_cli`
table = {c: {m: {k: S[f"{c}/{m}"][k] for k in COLS if k in S[f"{c}/{m}"]} for m in METHODS if f"{c}/{m}" in S}
         for c in CONDS if f"{c}/adtree" in S}
ahead = [c for c, t in table.items() if "f1_tight" in t.get("paths", {}) and "f1_tight" in t["adtree"]
         and t["paths"]["f1_tight"] >= t["adtree"]["f1_tight"]]
T, V, W = read("reconstruct_trees.json"), read("reconstruct_voxel.json"), read("reconstruct_speed.json")
cell = lambda x: {k: x[k] for k in ("chamfer", "coverage")}
out = dict(command="python benchmarks/reconstruct_results.py" + (f" --at {at}" if at else ""), commit=at or commit(),
           speed=dict(B["speed"], source=part("speed")),
           real_scans=dict(rows=B["real_scans"], source=part("real_scans")),
           skeletons=dict(summary=B["skeletons"]["summary"], source=part("skeletons")),
           peer=dict(columns=COLS, table=table, paths_f1_at_least_adtree=ahead,
                     source=dict(source(P), record="results/reconstruct_peer.json")),
           process=dict(W["seconds"], load_at_start=W["load_at_start"], import_floor=W["import_floor"],
                        source=dict(source(W), record="results/reconstruct_speed.json")),
           trees=dict(summary=T["summary"], source=dict(source(T, "minutes"), record="results/reconstruct_trees.json")),
           voxel=dict({k: V[k] for k in ("trees", "kinds", "fractions", "mean_chamfer", "chosen")},
                      table={k: cell(v) for k, v in V["table"].items()},
                      source=dict(source(V, "minutes"), record="results/reconstruct_voxel.json")))
tmp = Path(a.out).with_name(f".{Path(a.out).name}.part")
tmp.write_text(json.dumps(out, indent=1) + "\n"); tmp.replace(a.out)
print(f"wrote {a.out}")
