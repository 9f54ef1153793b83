"""Tree measurements (wood volume, DBH, total length) against the truth of procedural trees, beside PyTLidar.

Usage: python benchmarks/qsm.py [--per-species 1] [--conditions clean,noisy,...] [--methods treebook,pytlidar]
                                [--real] [--work tmp/qsm_bench] [--out results/qsm.json]

Scans: procedural trees of all six species at their preset's size, scaled to the species' height in metres, every
radius scaled so that the stem's base is 1/80 of the height (as grown trees; the procedural ones are thinner), scanned
from a mesh of 24 sides a ring (8 would make a stem an octagon, 4 % thinner than its radius on average) in the
conditions of CONDITIONS. The truth: the reference tree's frustum volume, its total length, and twice its trunk's radius
at 1.3 m (`treebook.qsm`). treebook runs `treebook.qsm.qsm` in this process (`foliage=True` on leafy scans); PyTLidar
runs through benchmarks/pytlidar_peer.py (benchmark-only; `pip install --no-deps pytlidar==1.1.2 numba plyfile laszip`).
With --real, the shared real scans are measured by both (no truth: the two side by side). Per-run rows are kept in
--work, so an interrupted run resumes.
"""
import argparse, json, os, platform, sys, time, warnings
from pathlib import Path

import numpy as np
from tqdm.auto import tqdm

root = Path(__file__).resolve().parent
sys.path.insert(0, str(root)); sys.path.insert(0, str(root.parent / "scripts")); sys.path.insert(0, str(root.parent))
import provenance  # noqa: E402
from peer import SHARED, make_scan  # noqa: E402

from treebook.botany import SPECIES  # noqa: E402
from treebook.tree import Tree, _atomic_write  # noqa: E402
from treebook.qsm import qsm, segment_volumes, trunk_radius_at  # noqa: E402

# n: points (a range drawn per scan); views: scanner stations; noise: Gaussian, of the tree's size; move: (share of
# points, largest move as a fraction of the diagonal); holes: (least, most) share removed in patches; thick: the stem's
# radius at the base as a fraction of the height
CONDITIONS = dict(
    clean=dict(n=(60000, 100000), views=3, noise=0.0002, thick=1 / 80),
    noisy=dict(n=(60000, 100000), views=3, noise=0.001, move=(0.1, 0.01), thick=1 / 80),
    holes=dict(n=(60000, 100000), views=3, noise=0.0002, holes=(0.05, 0.15), thick=1 / 80),
    leafy=dict(n=(80000, 120000), views=3, noise=0.0002, leaves=True, thick=1 / 80),
    sparse=dict(n=(8000, 15000), views=3, noise=0.0003, thick=1 / 80),
    dense=dict(n=(200000, 300000), views=4, noise=0.0002, thick=1 / 80),
)
MEASURES = ("volume", "dbh", "length")


def truth(t: Tree) -> dict:
    return dict(volume=float(segment_volumes(t).sum()), length=float(t.lengths.sum()),
                dbh=2 * trunk_radius_at(t, 1.3))


def prepare(work, c, sp, i):
    "Write (once) the scan (.npy, metres), its wood mask and the reference tree of one job; their paths."
    d = work / "scans"; d.mkdir(parents=True, exist_ok=True)
    name = f"{c}_{sp}_{i}"
    pts, ref, wood = d / f"{name}.npy", d / f"{name}_ref.npz", d / f"{name}_wood.npy"
    if not (pts.exists() and ref.exists() and wood.exists()):
        seed = 9100 + 97 * list(SPECIES).index(sp) + i + 1000 * list(CONDITIONS).index(c)
        p, w, t = make_scan(sp, i, c, seed, conditions=CONDITIONS, sides=24)
        np.save(wood, w)
        np.savez(ref, start=t.start, end=t.end, parent=t.parent)
        _atomic_write(pts, lambda f: np.save(f, p))
    return name, pts, ref


def run_treebook(pts, cond):
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        s = qsm(np.load(pts), foliage=cond == "leafy").summary
    return dict(volume=s["total_volume"], dbh=s["dbh"], length=s["total_length"], height=s["height"],
                branches=s["branches"], cylinders=s["cylinders"], seconds=time.perf_counter() - t0)


def run_pytlidar(pts, work):
    from pytlidar_peer import run_pytlidar as run
    r = run(np.load(pts), work, timeout=900)
    if r.get("error"): return dict(error=r["error"], seconds=r.get("seconds", 0.0))
    return dict(volume=r["volume"], dbh=r["dbh"], length=r["length"], height=r["height"], branches=r["branches"],
                cylinders=r["cylinders"], seconds=r["seconds"])


def summary(rows):
    "Per condition and method: mean |error| of each measure, and its worst; per species in the rows."
    out = {}
    for key in sorted({(r["condition"], r["method"]) for r in rows}):
        rs = [r for r in rows if (r["condition"], r["method"]) == key]
        ok = [r for r in rs if "error" not in r]
        s = dict(scans=len(rs), failed=len(rs) - len(ok), seconds=round(float(np.mean([r["seconds"] for r in rs])), 1))
        for m in MEASURES:
            e = [abs(r[f"{m}_error"]) for r in ok if np.isfinite(r.get(f"{m}_error", np.nan))]
            if e: s[f"{m}_mean_abs_error"], s[f"{m}_worst"] = round(float(np.mean(e)), 3), round(float(max(e)), 3)
            s[f"{m}_measured"] = len(e)
        out[f"{key[0]}/{key[1]}"] = s
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--per-species", type=int, default=1)
    ap.add_argument("--conditions", default=",".join(CONDITIONS))
    ap.add_argument("--methods", default="treebook,pytlidar")
    ap.add_argument("--real", action="store_true", help="also the real scans of ../shared/data/scans")
    ap.add_argument("--work", default=str(root.parent / "tmp" / "qsm_bench"))
    ap.add_argument("--tag", default="", help="a name for this run's treebook rows in --work (a variant under test)")
    ap.add_argument("--out", default="")
    a = ap.parse_args()
    conds = [c for c in a.conditions.split(",") if c]
    if bad := sorted(set(conds) - set(CONDITIONS)): raise SystemExit(f"unknown conditions {bad}: {list(CONDITIONS)}")
    methods = [m for m in a.methods.split(",") if m]
    work = Path(a.work)
    todo = [prepare(work, c, sp, i) + (c,) for c in conds for sp in SPECIES for i in range(a.per_species)]
    if a.real:
        from treebook.pointio import read_points
        for f in sorted((SHARED / "data" / "scans").glob("*")):
            if f.suffix not in (".xyz", ".las"): continue
            pts = work / "scans" / f"real_{f.stem}.npy"
            if not pts.exists(): _atomic_write(pts, lambda fh: np.save(fh, read_points(f)))
            todo.append((f"real_{f.stem}", pts, None, "real"))
    rows = []
    for name, pts, ref, cond, m in tqdm([(*t, m) for t in todo for m in methods], desc="runs"):
        tag = m + (f"_{a.tag}" if a.tag and m == "treebook" else "")
        rec = work / "rows" / tag / f"{name}.json"
        if rec.exists():
            rows.append(json.loads(rec.read_text())); continue
        try: r = run_treebook(pts, cond) if m == "treebook" else run_pytlidar(pts, work / "pytlidar" / name)
        except Exception as e:  # noqa: BLE001  a failure is a row, not the end of the benchmark
            r = dict(error=f"{type(e).__name__}: {e}", seconds=0.0)
        row = dict(scan=name, condition=cond, method=tag, **r)
        if ref is not None:
            z = np.load(ref)
            tr = truth(Tree(z["start"], z["end"], z["parent"], check=False))
            row.update({f"true_{k}": v for k, v in tr.items()})
            if "error" not in r: row.update({f"{k}_error": r[k] / tr[k] - 1 for k in MEASURES})
        rec.parent.mkdir(parents=True, exist_ok=True); rec.write_text(json.dumps(row))
        rows.append(row)
    summ = summary([r for r in rows if r["condition"] != "real"])
    for k, v in summ.items(): print(k, v)
    if a.out:
        res = dict(command="python benchmarks/qsm.py " + " ".join(sys.argv[1:]), commit=provenance.commit(short=True),
                   machine=f"{platform.machine()}, {os.cpu_count()} cores (shared with other jobs), "
                           f"{platform.python_version()}", conditions=CONDITIONS, summary=summ, rows=rows)
        _atomic_write(Path(a.out), lambda f: f.write(json.dumps(res, indent=1).encode()))
        print("wrote", a.out)


if __name__ == "__main__":
    main()
