"""Reconstruction side by side with AdTree, on scans like those users bring, scored by the yardstick.

Usage: python benchmarks/peer.py [--per-species 2] [--conditions sparse,noisy,...] [--methods classic,partnet]
                                 [--no-adtree] [--cli] [--real] [--work tmp/peer] [--out results/reconstruct_peer.json]

Scans: procedural trees of all six species at two sizes (the preset's branch count and a third of it), scaled to the
species' height in metres, scanned in the conditions of CONDITIONS; plus the real scans in ../shared/data/scans (surface
columns only). Each is reconstructed by treebook (every --methods) and by ../shared/tools/adtree, and scored by
../shared/tools/score/metrics.py (F1 at 0.5 % of the diagonal, Chamfer %, length ratio, components; share of scan points
within 1 % of the diagonal of the mesh). The row `truth` scores the reference tree's own mesh: on noisy scans
even it leaves the moved points uncovered, so a mesh that covers more is modelling the noise. With --cli every run is a whole `treebook reconstruct` process, timed as AdTree is;
without, treebook runs in this process (faster, for development) and its time leaves out the start-up.
Per-run results are kept in --work, so an interrupted run resumes. AdTree and the yardstick are benchmark-only.
"""
import argparse, json, os, platform, subprocess, sys, time
from pathlib import Path

import numpy as np
from tqdm.auto import tqdm

root = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(root / "scripts")); sys.path.insert(0, str(root))
import provenance  # noqa: E402
SHARED = root.parent / "shared"
sys.path.insert(0, str(SHARED / "tools" / "score"))
ADTREE = SHARED / "tools" / "adtree" / "adtree"

from treebook.botany import SPECIES, grow  # noqa: E402
from treebook.scan import scan  # noqa: E402
from treebook.tree import Tree, _atomic_write  # noqa: E402

# n: points (a range drawn per scan); views: scanner stations; noise: Gaussian, of the tree's size;
# move: (share of points, largest move as a fraction of the diagonal); holes: (least, most) share removed in patches;
# thick: the stem's radius at the base as a fraction of the height (about 1/80, as grown trees; the procedural ones are
# thinner), every radius scaled by the same factor: stems many point spacings wide, seen from two stations, as in TLS
CONDITIONS = dict(
    sparse=dict(n=(2000, 3000), views=3, noise=0.001),
    noisy=dict(n=(2000, 3000), views=3, noise=0.001, move=(1 / 3, 0.025)),
    holes=dict(n=(2000, 3000), views=3, noise=0.001, holes=(0.01, 0.07)),
    dense=dict(n=(15000, 120000), views=6, noise=0.0005),
    leafy=dict(n=(20000, 30000), views=3, noise=0.001, leaves=True),
    station=dict(n=(8000, 15000), views=1, noise=0.001),
    tls=dict(n=(40000, 100000), views=2, noise=0.0003, thick=0.012),
)


def make_scan(sp, i, cond, seed, conditions=CONDITIONS, sides=8):
    """(points (n, 3) in metres, wood mask, reference Tree in metres) of tree `i` of species `sp` in condition `cond`
    of `conditions`, its mesh of `sides` sides a ring."""
    kw = conditions[cond]
    rng = np.random.default_rng(seed)
    cap = SPECIES[sp].max_branches if i % 2 == 0 else max(30, SPECIES[sp].max_branches // 3)
    t = grow(sp, seed=seed, stages=1, max_branches=cap)[-1]
    h = float(SPECIES[sp].height)
    truth = Tree(t.start * h, t.end * h, t.parent, check=False)   # metres: radius scales with the positions
    if "thick" in kw:
        f = max(1.0, kw["thick"] * h / float(truth.start[truth.parent < 0, 3].max()))
        s_, e_ = truth.start.copy(), truth.end.copy(); s_[:, 3] *= f; e_[:, 3] *= f
        truth = Tree(s_, e_, truth.parent, check=False)
    n = int(rng.integers(kw["n"][0], kw["n"][1] + 1))
    sc = scan(truth, n_points=n, views=kw["views"], noise=kw["noise"], outliers=0.0, leaves=kw.get("leaves", False), seed=seed,
              sides=sides)
    p, wood = sc.points.astype(np.float64), ~sc.foliage
    diag = float(np.linalg.norm(np.ptp(p, 0)))
    if "move" in kw:   # a share of the points moved in random directions by up to a fraction of the diagonal
        share, most = kw["move"]
        m = rng.random(len(p)) < share
        d = rng.normal(size=(m.sum(), 3)); d /= np.linalg.norm(d, axis=1, keepdims=True)
        p[m] += d * rng.uniform(0, most * diag, (m.sum(), 1))
    if "holes" in kw:  # patches around random points removed until the drawn share is gone
        from scipy.spatial import cKDTree
        goal = int(rng.uniform(*kw["holes"]) * len(p))
        k = int(rng.integers(3, 7))
        centres = rng.choice(len(p), k, replace=False)
        nb = cKDTree(p).query(p[centres], max(1, goal // k))[1].reshape(k, -1)
        keep = np.ones(len(p), bool); keep[nb.ravel()] = False
        p, wood = p[keep], wood[keep]
    off = rng.uniform(-50, 50, 3) * [1, 1, 0.1]   # not centred, as real files are not
    return p + off, wood, truth.translate(off)


def jobs(per_species, conds):
    return [(c, sp, i) for c in conds for sp in SPECIES for i in range(per_species)]


def prepare(work, c, sp, i):
    "Write (once) the scan .xyz, its wood mask and the reference .npz of one job; return their paths."
    d = work / "scans"; d.mkdir(parents=True, exist_ok=True)
    name = f"{c}_{sp}_{i}"
    xyz, ref, wood = d / f"{name}.xyz", d / f"{name}_ref.npz", d / f"{name}_wood.npy"
    if not (xyz.exists() and ref.exists() and wood.exists()):
        seed = 8100 + 97 * list(SPECIES).index(sp) + i + 1000 * list(CONDITIONS).index(c)
        p, w, truth = make_scan(sp, i, c, seed)
        np.save(wood, w)
        np.savez(ref, start=truth.start, end=truth.end, parent=truth.parent)
        _atomic_write(xyz, lambda f: np.savetxt(f, p, fmt="%.4f"))
    return name, xyz, ref, wood


def run_adtree(xyz, out):
    out.mkdir(parents=True, exist_ok=True)
    t = time.perf_counter()
    r = subprocess.run([str(ADTREE), str(xyz), str(out)], capture_output=True, text=True)
    s = time.perf_counter() - t
    stem = xyz.stem
    skel, mesh = out / f"{stem}_skeleton.ply", out / f"{stem}_branches.obj"
    return (skel, mesh, s) if r.returncode == 0 and skel.exists() else (None, None, s)


def run_truth(ref, out):
    "The reference tree itself, meshed as treebook meshes: what a perfect skeleton and radii would score."
    from treebook.mesh import tree_mesh, export_mesh
    out.mkdir(parents=True, exist_ok=True)
    z = np.load(ref)
    obj = out / f"{Path(ref).stem}.obj"
    export_mesh(tree_mesh(Tree(z["start"], z["end"], z["parent"], check=False), sides=12), obj)
    return ref, obj, 0.0


def run_treebook(xyz, out, method, cli):
    out.mkdir(parents=True, exist_ok=True)
    npz, obj = out / f"{xyz.stem}.npz", out / f"{xyz.stem}.obj"
    t = time.perf_counter()
    if cli:
        r = subprocess.run([str(Path(sys.executable).parent / "treebook"), "reconstruct", str(xyz), "--out", str(npz),
                            "--mesh", str(obj), "--method", method], capture_output=True, text=True)
        ok = r.returncode == 0
    else:
        from treebook.reconstruct import reconstruct
        from treebook.mesh import export_mesh
        try:
            tree = reconstruct(str(xyz), method=method)
            tree.with_origin().save(npz); export_mesh(tree, obj, sides=12); ok = True
        except Exception as e:  # noqa: BLE001  a failure is a row, not the end of the benchmark
            print(f"{xyz.name} {method}: {e}", file=sys.stderr); ok = False
    s = time.perf_counter() - t
    return (npz, obj, s) if ok else (None, None, s)


def score(skel, mesh, ref, xyz, wood):
    import metrics  # the yardstick
    P = np.loadtxt(xyz)
    if wood is not None: P = P[np.load(wood)]   # the mesh is scored against the wood points (leaves are not modelled)
    out = {}
    pred = metrics.load_skeleton(str(skel))
    if ref is not None:
        m = metrics.skeleton_metrics(pred, metrics.load_skeleton(str(ref)))
        out.update({k: float(m[k]) for k in ("f1_tight", "f1", "chamfer_pct", "len_ratio", "n_comp")})
    else:
        out["n_comp"] = metrics.n_components(pred, 1e-4 * metrics.bbox_diag(P))
    out.update({k: float(v) for k, v in metrics.surface_metrics(str(mesh), P).items() if k in ("surf_within", "surf_mean_pct")})
    return out


def summary(rows):
    out = {}
    for key in sorted({(r["condition"], r["method"]) for r in rows}):
        rs = [r for r in rows if (r["condition"], r["method"]) == key]
        ok = [r for r in rs if r.get("ok")]
        s = dict(scans=len(rs), failed=len(rs) - len(ok), seconds=round(float(np.mean([r["seconds"] for r in rs])), 2))
        for m in ("f1_tight", "f1", "chamfer_pct", "len_ratio", "surf_within"):
            v = [r[m] if r.get("ok") else (0.0 if m in ("f1_tight", "f1", "surf_within") else np.nan) for r in rs if m in r or not r.get("ok")]
            v = [x for x in v if np.isfinite(x)]
            if v: s[m] = round(float(np.mean(v)), 3)
        s["one_component"] = round(float(np.mean([r.get("n_comp") == 1 for r in rs])), 3)
        out[f"{key[0]}/{key[1]}"] = s
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--per-species", type=int, default=2)
    ap.add_argument("--conditions", default=",".join(CONDITIONS))
    ap.add_argument("--methods", default="classic,partnet")
    ap.add_argument("--no-adtree", action="store_true")
    ap.add_argument("--cli", action="store_true", help="time treebook as whole processes (`treebook reconstruct`)")
    ap.add_argument("--real", action="store_true", help="also the real scans of ../shared/data/scans (surface columns)")
    ap.add_argument("--work", default=str(root / "tmp" / "peer"))
    ap.add_argument("--tag", default="", help="a name for this run's treebook outputs in --work (a variant under test)")
    ap.add_argument("--out", default="")
    a = ap.parse_args()
    conds = [c for c in a.conditions.split(",") if c]
    if bad := sorted(set(conds) - set(CONDITIONS)): raise SystemExit(f"unknown conditions {bad}: choose from {list(CONDITIONS)}")
    methods = [m for m in a.methods.split(",") if m] + ([] if a.no_adtree else ["adtree"]) + ["truth"]
    if "adtree" in methods and not ADTREE.exists(): raise SystemExit(f"AdTree not found at {ADTREE} (use --no-adtree)")
    work = Path(a.work)
    todo = [prepare(work, *j) + (j[0],) for j in tqdm(jobs(a.per_species, conds), desc="scans")]
    if a.real:
        for f in sorted((SHARED / "data" / "scans").glob("*")):
            if f.suffix not in (".xyz", ".las"): continue
            xyz = work / "scans" / f"real_{f.stem}.xyz"
            if not xyz.exists():
                from treebook.pointio import read_points
                _atomic_write(xyz, lambda fh: np.savetxt(fh, read_points(f), fmt="%.4f"))
            todo.append((f"real_{f.stem}", xyz, None, None, "real"))
    rows = []
    runs = [(*t, m) for t in todo for m in methods]
    for name, xyz, ref, wood, cond, m in tqdm(runs, desc="runs"):
        tag = m if m in ("adtree", "truth") else f"{m}{'_cli' if a.cli else ''}{'_' + a.tag if a.tag else ''}"
        rec = work / "rows" / tag / f"{name}.json"
        if rec.exists():
            rows.append(json.loads(rec.read_text())); continue
        out = work / "out" / tag
        if m == "truth" and ref is None: continue
        if m == "truth": skel, mesh, s = run_truth(ref, out)
        else: skel, mesh, s = run_adtree(xyz, out / name) if m == "adtree" else run_treebook(xyz, out, m, a.cli)
        row = dict(scan=name, condition=cond, method=tag, points=sum(1 for _ in open(xyz)), seconds=round(s, 3), ok=skel is not None)
        if skel is not None: row.update(score(skel, mesh, ref, xyz, wood))
        rec.parent.mkdir(parents=True, exist_ok=True); rec.write_text(json.dumps(row))
        rows.append(row)
    summ = summary(rows)
    for k, v in summ.items(): print(k, v)
    if a.out:
        res = dict(command="python benchmarks/peer.py " + " ".join(sys.argv[1:]), commit=provenance.commit(short=True),
                   machine=f"{platform.machine()}, {os.cpu_count()} cores (shared with other jobs), {platform.python_version()}",
                   conditions=CONDITIONS, summary=summ, rows=rows)
        _atomic_write(Path(a.out), lambda f: f.write(json.dumps(res, indent=1).encode()))
        print("wrote", a.out)


if __name__ == "__main__":
    main()
