"""Whole-process time of one scan, treebook beside AdTree, on the scans of benchmarks/peer.py (run it first).

Usage: python benchmarks/reconstruct_speed.py [--work tmp/peer] [--conditions sparse,...] [--out results/reconstruct_speed.json]

For each condition: AdTree (`adtree SCAN OUT`) and `treebook reconstruct SCAN --out T.npz --mesh T.obj` as one process per
scan, and `treebook reconstruct SCAN... --out DIR --mesh obj` as one process for all the condition's scans (the start-up
paid once), its time divided by the number of scans; and the time a process takes to import numpy and scipy, the
floor under any one-scan run. Wall-clock seconds; the load average at the start is recorded. Python runs as it does
on a user's machine, caching the bytecode of what it imports (PYTHONDONTWRITEBYTECODE, if set here, is dropped for the
runs timed, and one untimed run writes the cache first).
"""
import argparse, json, os, subprocess, sys, tempfile, time
from pathlib import Path

import numpy as np

root = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(root / "scripts")); sys.path.insert(0, str(root / "benchmarks"))
import provenance  # noqa: E402
from peer import ADTREE, CONDITIONS  # noqa: E402

TREEBOOK = str(Path(sys.executable).parent / "treebook")


ENV = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}


def wall(cmd) -> float:
    t = time.perf_counter()
    r = subprocess.run([str(c) for c in cmd], capture_output=True, text=True, env=ENV)
    if r.returncode: raise SystemExit(f"{' '.join(map(str, cmd))} failed: {r.stderr.strip()[-300:]}")
    return time.perf_counter() - t


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--work", default=str(root / "tmp" / "peer"))
    ap.add_argument("--conditions", default=",".join(CONDITIONS))
    ap.add_argument("--out", default="")
    a = ap.parse_args()
    res, load = {}, os.getloadavg()[0]
    with tempfile.TemporaryDirectory() as d:   # untimed: Python writes the bytecode of what treebook imports
        s = next(Path(a.work, "scans").glob("sparse_*[0-9].xyz"))
        wall([TREEBOOK, "reconstruct", s, "--out", Path(d, "t.npz"), "--mesh", Path(d, "t.obj")])
    floor = float(np.median([wall([sys.executable, "-c", "import numpy, scipy.sparse.csgraph, scipy.spatial"])
                             for _ in range(5)]))   # what any process that uses numpy and scipy pays first
    for c in a.conditions.split(","):
        scans = sorted(Path(a.work, "scans").glob(f"{c}_*[0-9].xyz"))
        if not scans: raise SystemExit(f"no scans of {c} in {a.work}/scans: run benchmarks/peer.py first")
        with tempfile.TemporaryDirectory() as d:
            ad = [wall([ADTREE, s, Path(d, "ad", s.stem)]) for s in scans]
            one = [wall([TREEBOOK, "reconstruct", s, "--out", Path(d, f"{s.stem}.npz"), "--mesh", Path(d, f"{s.stem}.obj")])
                   for s in scans]
            batch = wall([TREEBOOK, "reconstruct", *scans, "--out", Path(d, "batch"), "--mesh", "obj"]) / len(scans)
        res[c] = dict(scans=len(scans), points=int(np.mean([sum(1 for _ in open(s)) for s in scans])),
                      adtree=round(float(np.mean(ad)), 3), treebook=round(float(np.mean(one)), 3),
                      treebook_batch=round(batch, 3))
        print(c, res[c], flush=True)
    if a.out: provenance.record("benchmarks/reconstruct_speed.py", dict(load_at_start=round(load, 2),
                                                                     import_floor=round(floor, 3), seconds=res), a.out)


if __name__ == "__main__":
    main()
