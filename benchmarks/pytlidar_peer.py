"""PyTLidar (the Python port of TreeQSM) as a peer for treebook's tree measurements. Benchmark-only.

Usage: python benchmarks/pytlidar_peer.py SCAN [SCAN...] --work DIR [--seed 0] [--timeout S] [--npd 1 1 1]
                                          [--optimum all_mean_dis]

Prints one JSON line per scan (the cylinder table stays in its CSV). Every scan gets its own folder DIR/<scan stem>,
which caches the result: a second run reads result.json back (failures are cached too; delete the folder to retry).

PyTLidar is GPL-3.0 and pins numba==0.61.2 (numpy<2.3), so it is installed into .venv only for benchmarks, with
`pip install --no-deps pytlidar==1.1.2` plus numba, plyfile and laszip; it is never a dependency of treebook.

What runs: `PyTLidar.pipeline.build_inputs` (TreeQSM's define_input: PatchDiam1 = Rstem/3, PatchDiam2Min =
Rstem/6*min(1, 20/height), PatchDiam2Max = Rstem/2.5, BallRad from them and the point spacing, with Rstem the median
stem radius 2-10 % up the tree) and `run_qsm` (treeqsm), as `pytlidar-qsm SCAN` does: one model by default; with
npd=(a, b, c) it makes a*b*c models and keeps the best by `optimum` (default 'all_mean_dis', TreeQSM's usual choice).
Each scan runs in a child process (a timeout can stop it, a crash does not take the caller down; matplotlib on Agg:
treeqsm's tree_data draws figures whatever `plot` says). The cloud is shifted by its minimum before, and the cylinder
starts shifted back after, so map coordinates are fine. Both numpy's global RNG (cover_sets' random permutations) and
numba's separate one (np.random.rand in the jitted orthonormal_vectors) are seeded with `seed`, which makes a run
repeatable; seeding numpy alone is not enough (the volume then varies by several %).

Units of the returned dict (SI): volumes m^3 (TreeQSM's TotalVolume etc. are litres: divided by 1000), lengths and
DBH m. `dbh` is TreeQSM's DBHqsm: the diameter of the trunk cylinder where the cumulative trunk length reaches 1.3 m;
`dbh_cyl` is its DBHcyl, a cylinder least-squares fitted to the trunk points 1.1-1.5 m along the first cylinder's axis
(DBHqsm when that fit fails its checks).

Measured (PyTLidar 1.1.2, numba 0.68.1, 2 cores): the first run ever compiles numba's cache (~35 s more). tulip 0 tls
seed 1 of peer.make_scan (68k points): 15-20 s, volume 6.8/7.1/8.4 m^3 for seeds 0/1/2 (truth 7.90), DBH 0.588 (truth
0.623), length 427 m (444). pytlidar_tree_1.las (90k points, 12.9 m): 101 s, 0.8 GB, 1.81 m^3, DBH 0.360 m, 2221
branches. tree13.xyz (7k points, sparse): treeqsm fails (IndexError in correct_segments) with every seed tried.
"""
import argparse, json, os, subprocess, sys, time
from pathlib import Path

import numpy as np

CSV_COLUMNS = ["radius", "length", "start_x", "start_y", "start_z", "axis_x", "axis_y", "axis_z", "parent",
               "extension", "branch", "branch_order", "position_in_branch", "mad", "surf_cov", "added",
               "unmod_radius"]


def load_points(path) -> np.ndarray:
    "(n, 3) float64 points of a .xyz/.txt/.csv (first three columns), .npy, or .las/.laz file."
    path = Path(path)
    ext = path.suffix.lower()
    if ext in (".las", ".laz"):
        import laspy
        las = laspy.read(str(path))
        return np.column_stack([np.asarray(las.x), np.asarray(las.y), np.asarray(las.z)]).astype(np.float64)
    if ext == ".npy":
        return np.asarray(np.load(path), np.float64)[:, :3]
    delim = "," if ext == ".csv" else None
    return np.atleast_2d(np.loadtxt(path, delimiter=delim, usecols=(0, 1, 2), ndmin=2)).astype(np.float64)


def _public(r: dict) -> dict:
    return {k: v for k, v in r.items() if not k.startswith("_")}


def run_pytlidar(points_or_path, workdir, seed: int = 0, timeout=None, npd=(1, 1, 1),
                 optimum: str = "all_mean_dis") -> dict:
    """PyTLidar's QSM of one scan, in SI units (see the module doc); `error` instead of the numbers if it failed.

    points_or_path: (n, 3) array or a scan file. workdir: this scan's folder, which caches the result (result.json) and
    holds the cylinder CSV, the input and PyTLidar's log. timeout: seconds for the child process (None: no limit)."""
    work = Path(workdir)
    res_path = work / "result.json"
    if res_path.exists():
        return json.loads(res_path.read_text())
    work.mkdir(parents=True, exist_ok=True)
    src = str(points_or_path) if isinstance(points_or_path, (str, Path)) else "array"
    t0 = time.perf_counter()
    try:
        P = load_points(points_or_path) if isinstance(points_or_path, (str, Path)) else \
            np.asarray(points_or_path, np.float64)[:, :3]
    except Exception as e:
        return _finish(work, dict(source=src, error=f"cannot read the scan: {type(e).__name__}: {e}"))
    P = P[np.all(np.isfinite(P), axis=1)]
    if len(P) == 0:
        return _finish(work, dict(source=src, n_points=0, error="no points"))
    offset = P.min(0)
    np.save(work / "input.npy", P - offset)
    job = dict(seed=int(seed), offset=offset.tolist(), npd=[int(v) for v in npd], optimum=optimum, source=src)
    (work / "job.json").write_text(json.dumps(job))
    env = dict(os.environ, MPLBACKEND="Agg", PYTHONWARNINGS="ignore")
    log = work / "log.txt"
    with open(log, "w") as f:
        try:
            rc = subprocess.run([sys.executable, str(Path(__file__).resolve()), "--child", str(work)],
                                stdout=f, stderr=subprocess.STDOUT, env=env, timeout=timeout).returncode
        except subprocess.TimeoutExpired:
            rc = "timeout"
    wall = time.perf_counter() - t0
    out = work / "child.json"
    if out.exists():
        r = json.loads(out.read_text())
        out.unlink()
        lines = [l for l in log.read_text(errors="replace").splitlines() if l.strip()]
        if "error" in r and any("Traceback" in l for l in lines):
            r["error"] += " (" + lines[-1].strip() + ")"   # treeqsm prints its traceback and returns "ERROR"
    else:
        tail = log.read_text(errors="replace").strip().splitlines()[-3:]
        r = dict(error=f"timed out after {timeout} s" if rc == "timeout" else
                 f"PyTLidar exited with {rc}: " + " | ".join(tail))
    r.update(source=src, n_points=int(len(P)), seed=int(seed), seconds_process=round(wall, 2))
    return _finish(work, r)


def _finish(work: Path, r: dict) -> dict:
    tmp = work / "result.json.tmp"
    tmp.write_text(json.dumps(r, indent=1))
    tmp.replace(work / "result.json")
    return r


def _child(work: Path):
    "Runs in the child process: model input.npy, write the cylinder CSV and child.json."
    import warnings
    warnings.filterwarnings("ignore")
    import logging
    logging.getLogger("matplotlib").setLevel(logging.ERROR)
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    job = json.loads((work / "job.json").read_text())
    P = np.load(work / "input.npy")
    offset = np.array(job["offset"])
    np.random.seed(job["seed"])   # numpy's global RNG: cover_sets' random permutations
    import numba

    @numba.njit
    def _seed_numba(s): np.random.seed(s)   # numba's own RNG: np.random.rand inside jitted orthonormal_vectors
    _seed_numba(job["seed"])
    from PyTLidar.pipeline import build_inputs, run_qsm, calculate_optimal
    t0 = time.perf_counter()
    try:
        inputs = build_inputs(P, n_patchdiam=tuple(job["npd"]), names=["tree"], savemat=0, savetxt=0, plot=0,
                              disp=0, savepdf=0)[0]
        models, _ = run_qsm(P, inputs, results_dir=str(work))
        if not models:
            raise RuntimeError("no model: no cylinders were fitted")
        best = calculate_optimal(models, job["optimum"])[0] if len(models) > 1 else 0
    except Exception as e:
        r = dict(error=f"{type(e).__name__}: {e}", seconds=round(time.perf_counter() - t0, 2))
        (work / "child.json").write_text(json.dumps(r))
        return
    seconds = time.perf_counter() - t0
    plt.close("all")
    m = models[best]
    c, td = m["cylinder"], m["treedata"]
    start = np.asarray(c["start"], np.float64) + offset
    cols = [c["radius"], c["length"], *start.T, *np.asarray(c["axis"]).T, c["parent"], c["extension"], c["branch"],
            c["BranchOrder"], c["PositionInBranch"], c["mad"], c["SurfCov"], c["added"], c["UnmodRadius"]]
    table = np.column_stack([np.asarray(v, np.float64).ravel() for v in cols])
    csv = work / "cylinders.csv"
    fmt = ["%.6f"] * 8 + ["%d"] * 5 + ["%.6f", "%.4f", "%d", "%.6f"]
    np.savetxt(csv, table, delimiter=",", header=",".join(CSV_COLUMNS), comments="", fmt=fmt)
    f = lambda k: float(td[k])  # noqa: E731
    r = dict(volume=f("TotalVolume") / 1000, trunk_volume=f("TrunkVolume") / 1000,
             branch_volume=f("BranchVolume") / 1000, dbh=f("DBHqsm"), dbh_cyl=f("DBHcyl"), height=f("TreeHeight"),
             length=f("TotalLength"), trunk_length=f("TrunkLength"), branches=int(td["NumberBranches"]),
             max_branch_order=int(td["MaxBranchOrder"]), cylinders=int(len(c["radius"])),
             seconds=round(seconds, 2), cylinder_table=str(csv.resolve()), models=len(models),
             params=dict(PatchDiam1=float(m["PatchDiam1"]), PatchDiam2Min=float(m["PatchDiam2Min"]),
                         PatchDiam2Max=float(m["PatchDiam2Max"]), BallRad1=float(np.ravel(inputs["BallRad1"])[0]),
                         BallRad2=float(np.ravel(inputs["BallRad2"])[0])))
    pmd = m.get("pmdistance") or {}
    for k in ("TrunkMean", "BranchMean"):   # mean point-to-cylinder distance, m
        if k in pmd: r[k[0].lower() + k[1:].replace("Mean", "_mean_distance")] = float(pmd[k])
    (work / "child.json").write_text(json.dumps(r))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("scans", nargs="*")
    ap.add_argument("--work", default="tmp/pytlidar")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--timeout", type=float, default=None)
    ap.add_argument("--npd", type=int, nargs=3, default=(1, 1, 1), metavar=("PD1", "PD2MIN", "PD2MAX"))
    ap.add_argument("--optimum", default="all_mean_dis")
    ap.add_argument("--child", help=argparse.SUPPRESS)
    a = ap.parse_args(argv)
    if a.child:
        return _child(Path(a.child))
    if not a.scans: ap.error("give at least one scan")
    for s in a.scans:
        r = run_pytlidar(s, Path(a.work) / Path(s).stem, seed=a.seed, timeout=a.timeout, npd=a.npd,
                         optimum=a.optimum)
        print(json.dumps(dict(scan=s, **r)), flush=True)


if __name__ == "__main__":
    main()
