"""Benchmark and distributions for chapter 02 (botany): growth speed, the 10,000-tree elm set, scan speed, per-species stats.

Usage: python benchmarks/botany.py [--n-elm 10000] [--workers 2] [--stats-n 40] [--out results/botany.json]
Writes results/botany.json (with the command, git commit and machine) and results/botany_distributions.png.
"""
import argparse, json, os, platform, shutil, sys, tempfile, time
from pathlib import Path
sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "scripts"))
import provenance   # scripts/provenance.py

import numpy as np

from treebook.botany import SPECIES, grow_tree, tree_stats
from treebook.datasets import generate_dataset
from treebook.scan import scan, silhouette, sketch
from treebook.tree import _atomic_write


def machine():
    cpu = ""
    try: cpu = next(l.split(":", 1)[1].strip() for l in open("/proc/cpuinfo") if l.startswith("model name"))
    except Exception: pass
    return {"platform": platform.platform(), "python": platform.python_version(), "cpu": cpu, "cpus": os.cpu_count(),
            "cpus_allowed": len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else None}


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--n-elm", type=int, default=10000)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--stats-n", type=int, default=40)
    ap.add_argument("--scan-n", type=int, default=20)
    ap.add_argument("--out", default="results/botany.json")
    a = ap.parse_args()
    root = Path(__file__).resolve().parents[1]
    commit = provenance.commit()
    res = {"command": "python " + " ".join(sys.argv), "commit": commit, "machine": machine(), "time": time.strftime("%Y-%m-%d %H:%M:%S")}

    # growth, one process: seconds per tree for every species at its preset cap
    growth = {}
    for name in SPECIES:
        grow_tree(name, seed=10**6)  # warm up
        t0 = time.perf_counter(); ns = [grow_tree(name, seed=s).n for s in range(a.stats_n)]; dt = time.perf_counter() - t0
        growth[name] = {"trees_per_s_1proc": a.stats_n / dt, "ms_per_tree": 1000 * dt / a.stats_n, "mean_branches": float(np.mean(ns)),
                        "cap": SPECIES[name].max_branches}
        print(name, growth[name], flush=True)
    res["growth"] = growth

    # the elm set: n trees, 200-branch cap, workers processes, end to end through generate_dataset
    tmp = Path(tempfile.mkdtemp())
    t0 = time.perf_counter()
    m = generate_dataset("elm", a.n_elm, tmp / "elm", max_branches=200, workers=a.workers, seed=0)
    dt = time.perf_counter() - t0
    res["elm_dataset"] = {"n": a.n_elm, "workers": a.workers, "seconds": dt, "trees_per_s": a.n_elm / dt,
                          "projected_10000_s": 10000 / (a.n_elm / dt), "branches_mean": m["counts"]["branches"] / a.n_elm,
                          "target": "10,000 trees in <= 600 s on 2 cores"}
    print(res["elm_dataset"], flush=True)
    shutil.rmtree(tmp)

    # scanning at 16,384 points (mesh + ray casting + labels), and the images
    st, si = [], []
    for k in range(a.scan_n):
        t = grow_tree(list(SPECIES)[k % len(SPECIES)], seed=k)
        t0 = time.perf_counter(); scan(t, n_points=16384, seed=k); st.append(time.perf_counter() - t0)
        t0 = time.perf_counter(); silhouette(t); sketch(t); si.append(time.perf_counter() - t0)
    res["scan"] = {"n_points": 16384, "trees": a.scan_n, "mean_s": float(np.mean(st[1:])), "max_s": float(np.max(st[1:])),
                   "images_mean_s": float(np.mean(si)), "target": "<= 0.5 s per scan"}
    print(res["scan"], flush=True)

    # per-species distributions
    res["stats"] = {name: [tree_stats(grow_tree(name, seed=s)) for s in range(a.stats_n)] for name in SPECIES}
    res["stats_summary"] = {name: {k: float(np.mean([s[k] for s in v])) for k in v[0]} for name, v in res["stats"].items()}
    out = root / a.out
    out.parent.mkdir(exist_ok=True)
    _atomic_write(out, lambda f: f.write(json.dumps(res, indent=1).encode()))
    import matplotlib; matplotlib.use("Agg"); import matplotlib.pyplot as plt
    fig, axs = plt.subplots(1, 4, figsize=(16, 3.2))
    for ax, key in zip(axs, ["branches", "height_width", "depth", "branch_angle"]):
        ax.boxplot([[s[key] for s in res["stats"][n]] for n in SPECIES], tick_labels=list(SPECIES)); ax.set_title(key)
        ax.tick_params(axis="x", rotation=45)
    plt.tight_layout(); fig.savefig(out.with_name("botany_distributions.png"), dpi=80)
    print(json.dumps(res["stats_summary"], indent=1))


if __name__ == "__main__":
    main()
