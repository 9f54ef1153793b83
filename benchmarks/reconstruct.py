"""Reconstruction benchmark: speed (16,384 and 1,000,000 points), real scans (also moved to map coordinates), skeleton accuracy, clustering and merging scores.

Usage: python benchmarks/reconstruct.py [--weights PATH] [--trees-per-species 2] [--cluster-scans 12] [--out results/reconstruct.json]
                                      [--only PARTS] [--skip PARTS] [--cluster-rows ROWS] [--merge] [--threads 2]

Writes results/reconstruct.json with the command, commit and machine. Timings are wall-clock on this machine (shared CPU).
With --merge the parts (and, for the clustering table, the rows) computed by this run replace theirs in the existing file and
everything else is kept; the run is recorded under "updates" with its command and commit. For example, the SOM row alone:
  python benchmarks/reconstruct.py --only clustering --cluster-rows som --cluster-scans 6 --merge
"""
import argparse, json, os, platform, subprocess, sys, time
from pathlib import Path
sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "scripts"))
import provenance   # scripts/provenance.py

import numpy as np
from tqdm.auto import tqdm

root = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(root))
from treebook.tree import _atomic_write
from treebook.botany import SPECIES, grow
from treebook.scan import scan
from treebook.mesh import tree_mesh
from treebook.pointio import read_points
from treebook.partnet import (WEIGHTS, load_partnet, segment, cluster_scores, merge_scores, affinity_scores, branch_chains, normalize_points, merge_seeds, predict_seeds,
                              som_clusters)
from treebook.reconstruct import reconstruct, coverage, skeleton_distance, pipe_radii

SCANS = root.parent / "shared" / "data" / "scans"


def timed(f, *a, **k):
    t = time.perf_counter(); r = f(*a, **k); return r, time.perf_counter() - t


def speed(weights, methods):
    out = {}
    t = grow("hickory", seed=4242, stages=1)[-1]
    pts = scan(t, n_points=16384, seed=1).points.astype(np.float64)
    for m in methods:
        reconstruct(pts, method=m, weights=weights)  # warm-up (imports, first torch call)
        (tree, mesh), s = timed(lambda: (lambda tr: (tr, tree_mesh(tr, sides=12)))(reconstruct(pts, method=m, weights=weights)))
        out[f"16384_{m}_seconds"] = round(s, 2)
    # 1,000,000 points: the largest real scan, repeated with jitter, in a fresh process for an honest peak memory
    tmp = root / "tmp" / "bench_1m.npy"; tmp.parent.mkdir(exist_ok=True)
    base = read_points(SCANS / "pytlidar_tree_1.las") if (SCANS / "pytlidar_tree_1.las").exists() else pts
    rng = np.random.default_rng(0)
    big = base[rng.integers(len(base), size=1_000_000)] + rng.normal(0, 0.003, (1_000_000, 3))
    np.save(tmp, big)
    for m in methods:
        code = ("import time,resource,sys; t=time.perf_counter(); from treebook.reconstruct import reconstruct; from treebook.mesh import tree_mesh;"
                f"tr=reconstruct({str(tmp)!r}, method={m!r}, weights={str(weights)!r}); tree_mesh(tr, sides=12);"
                "print(time.perf_counter()-t, resource.getrusage(resource.RUSAGE_SELF).ru_maxrss/1e6, tr.n)")
        r = subprocess.run([sys.executable, "-c", code], cwd=root, capture_output=True, text=True)
        if r.returncode: raise SystemExit(r.stderr)
        s, gb, n = r.stdout.split()[-3:]
        out[f"1M_{m}_seconds"] = round(float(s), 1); out[f"1M_{m}_peak_GB"] = round(float(gb), 2); out[f"1M_{m}_branches"] = int(n)
    tmp.unlink()
    return out


MAP_OFFSET = np.array([451234.5, 5432109.25, 301.0])  # each real scan is also reconstructed moved here, as if in UTM metres


def real_scans(weights, methods):
    rows = []
    for f in sorted(SCANS.glob("*")):
        if f.suffix not in (".xyz", ".las", ".ply", ".pcd", ".npy"): continue
        p = read_points(f)
        for m in methods:
            tree, s = timed(reconstruct, p, method=m, weights=weights)
            mesh = tree_mesh(tree, sides=12).apply_translation(tree.origin)  # in the scan's coordinates
            rows.append(dict(scan=f.name, points=len(p), method=m, seconds=round(s, 2), branches=tree.n, roots=int((tree.parent == -1).sum()),
                             coverage_1pct=round(coverage(p, mesh), 3), watertight=bool(mesh.is_watertight),
                             coverage_1pct_pipe=round(coverage(p, tree_mesh(pipe_radii(tree), sides=12).apply_translation(tree.origin)), 3)))  # the same tree with radii="pipe"
            far = reconstruct(p + MAP_OFFSET, method=m, weights=weights)  # the scan moved to map coordinates (UTM metres)
            rows[-1]["coverage_1pct_map"] = round(coverage(p + MAP_OFFSET, tree_mesh(far, sides=12).apply_translation(far.origin)), 3)
    return rows


CONDITIONS = dict(clean=dict(noise=0.0, outliers=0.0, missing=0), noisy=dict(noise=0.004, outliers=0.02, missing=0),
                  incomplete=dict(noise=0.002, outliers=0.0, missing=3, missing_radius=0.08))


def skeletons(weights, methods, per_species):
    rows = []
    jobs = [(sp, 7000 + i) for sp in SPECIES for i in range(per_species)]
    for sp, s in tqdm(jobs, desc="skeletons"):
        truth = grow(sp, seed=s, stages=1)[-1]
        for cond, kw in CONDITIONS.items():
            pts = scan(truth, n_points=16384, seed=s, **kw).points.astype(np.float64)
            for m in methods:
                d = skeleton_distance(reconstruct(pts, method=m, weights=weights, seed=0), truth)
                rows.append(dict(species=sp, seed=s, condition=cond, method=m, **{k: round(v, 3) for k, v in d.items()}))
    summary = {}
    for cond in CONDITIONS:
        for m in methods:
            r = [x for x in rows if x["condition"] == cond and x["method"] == m]
            summary[f"{cond}_{m}"] = dict(chamfer=round(float(np.mean([x["chamfer"] for x in r])), 3), hausdorff=round(float(np.mean([x["hausdorff"] for x in r])), 3))
    return dict(summary=summary, rows=rows)


CLUSTER_ROWS = ("ours", "ours_fine", "mean_shift", "spectral", "dbscan", "som")


def clustering(weights, n_scans, rows=CLUSTER_ROWS):
    "RI / NMI of ours and classic baselines (scikit-learn, minisom) on held-out procedural scans of 4,096 points (paper Table 3), and merging scores."
    from sklearn.cluster import MeanShift, SpectralClustering, DBSCAN, estimate_bandwidth
    model = load_partnet(weights)
    n = model.cfg.n_points
    res = {k: [] for k in rows}
    merge, ks = [], []
    jobs = [(sp, 9000 + i) for i in range(n_scans) for sp in SPECIES][:n_scans]
    for sp, s in tqdm(jobs, desc="clustering"):
        t = grow(sp, seed=s, stages=1)[-1]
        sc = scan(t, n_points=n, seed=s, noise=0.002, outliers=0.01)
        chain = branch_chains(t)
        part = np.where(sc.branch >= 0, chain[np.maximum(sc.branch, 0)], -1)
        p = sc.points.astype(np.float64)
        q, _, _ = normalize_points(p)
        k = int(len(np.unique(part[part >= 0]))); ks.append(k)
        if "ours" in rows or "ours_fine" in rows:
            seg = segment(model, p, seed=0)
            if "ours" in rows: res["ours"].append(cluster_scores(seg["branch"], part))
            if "ours_fine" in rows: res["ours_fine"].append(cluster_scores(seg["fine"], part))
        if "ours" in rows:  # merging scores on the seeds of this run
            o = predict_seeds(model, q, seed=0, tta=model.cfg.tta)
            pairs, prob, sp = o["pairs"], o["prob"], part[o["seed_idx"]]
            th = model.cfg.threshold  # the threshold and linkage segment merges with
            merge.append(merge_scores(merge_seeds(prob, th, linkage=model.cfg.linkage, pairs=pairs), sp)
                         | {f"affinity_{k}": v for k, v in affinity_scores(prob, sp, th, pairs=pairs).items()})
        if "mean_shift" in rows:
            res["mean_shift"].append(cluster_scores(MeanShift(bandwidth=estimate_bandwidth(q, quantile=0.02, random_state=0), bin_seeding=True).fit_predict(q), part))
        if "spectral" in rows:
            res["spectral"].append(cluster_scores(SpectralClustering(n_clusters=min(k, 256), affinity="nearest_neighbors", n_neighbors=10, random_state=0,
                                                                     assign_labels="cluster_qr").fit_predict(q), part))
        if "dbscan" in rows:
            eps = float(np.median(np.sort(np.linalg.norm(q[:, None] - q[np.random.default_rng(0).choice(n, 256)][None], axis=2), 0)[5]))
            res["dbscan"].append(cluster_scores(DBSCAN(eps=eps, min_samples=5).fit_predict(q), part))
        if "som" in rows:  # given the true number of parts, as spectral clustering is
            res["som"].append(cluster_scores(som_clusters(q, min(k, n), seed=0), part))
    table = {k: {m: round(float(np.mean([r[m] for r in v])), 3) for m in ("ri", "nmi", "clusters")} for k, v in res.items()}
    table["true_parts"] = round(float(np.mean(ks)), 1)
    out = dict(table=table, scans=len(jobs), points=n)
    if merge: out["merging_full"] = {m: round(float(np.mean([r[m] for r in merge])), 3) for m in merge[0]}
    return out


PARTS = ("speed", "real", "skeletons", "clustering")


def merged(old: dict, new: dict, meta: dict) -> dict:
    "`old` results with the parts of `new` put in; a clustering table is merged row by row; the run noted under 'updates'."
    out = dict(old)
    for k, v in new.items():
        if k == "clustering" and "clustering" in old:
            if (v["scans"], v["points"]) != (old["clustering"].get("scans"), old["clustering"].get("points")):
                raise SystemExit(f"refusing to merge clustering rows over {v['scans']} scans into a table over {old['clustering'].get('scans')}: "
                                 "use the same --cluster-scans")
            c = dict(old["clustering"]); c.update({kk: vv for kk, vv in v.items() if kk != "table"})
            c["table"] = dict(old["clustering"]["table"], **v["table"])
            out["clustering"] = c
        else: out[k] = v
    out["updates"] = old.get("updates", []) + [dict(meta, parts={k: sorted(v["table"]) if k == "clustering" else "all" for k, v in new.items()})]
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--weights", default=str(WEIGHTS))
    ap.add_argument("--trees-per-species", type=int, default=2)
    ap.add_argument("--cluster-scans", type=int, default=12)
    ap.add_argument("--skip", default="", help="comma list of parts to skip: speed,real,skeletons,clustering")
    ap.add_argument("--only", default="", help="comma list of the only parts to run (overrides --skip)")
    ap.add_argument("--cluster-rows", default=",".join(CLUSTER_ROWS), help="comma list of clustering rows: " + ",".join(CLUSTER_ROWS))
    ap.add_argument("--merge", action="store_true", help="merge the computed parts (and clustering rows) into the existing --out file")
    ap.add_argument("--threads", type=int, default=2, help="torch threads")
    ap.add_argument("--out", default=str(root / "results" / "reconstruct.json"))
    a = ap.parse_args()
    import torch; torch.set_num_threads(a.threads)
    methods = ["paths", "classic"] + (["partnet"] if Path(a.weights).exists() else [])
    skip = set(a.skip.split(","))
    if a.only: skip = set(PARTS) - set(a.only.split(","))
    rows = tuple(r for r in a.cluster_rows.split(",") if r)
    if bad := sorted(set(skip | set(a.only.split(",") if a.only else ())) - set(PARTS) - {""}): raise SystemExit(f"unknown parts {bad}: choose from {PARTS}")
    if bad := sorted(set(rows) - set(CLUSTER_ROWS)): raise SystemExit(f"unknown clustering rows {bad}: choose from {CLUSTER_ROWS}")
    res = {}
    if "speed" not in skip: res["speed"] = speed(a.weights, methods); print(json.dumps(res["speed"]))
    if "real" not in skip: res["real_scans"] = real_scans(a.weights, methods); print(json.dumps(res["real_scans"], indent=0))
    if "skeletons" not in skip: res["skeletons"] = skeletons(a.weights, methods, a.trees_per_species); print(json.dumps(res["skeletons"]["summary"]))
    if "clustering" not in skip and "partnet" in methods: res["clustering"] = clustering(a.weights, a.cluster_scans, rows); print(json.dumps(res["clustering"]))
    commit = provenance.commit(short=True)
    meta = dict(command="python benchmarks/reconstruct.py " + " ".join(sys.argv[1:]), commit=commit,
                machine=f"{platform.machine()}, {os.cpu_count()} cores (shared with other jobs), {platform.python_version()}")
    if a.merge and Path(a.out).exists(): res = merged(json.loads(Path(a.out).read_text()), res, meta)
    else: res = dict(meta, **res)
    _atomic_write(Path(a.out), lambda f: f.write(json.dumps(res, indent=1).encode()))
    print("wrote", a.out)


if __name__ == "__main__":
    main()
