"""HourglassTree Tables 1 (orders, arch Full) and 2 (archs, order DFS) at CPU scale, scored by metrics.sample_scores; each
run in its own process, kept in runs/ablation/<name>/result.json. Writes results/ablation_{orders,archs}.json and
ablation_samples.png. Usage: python scripts/ablation.py [--steps 300] [--only dfs-full,...] [--lr-sweep]
Table 3 (more trees, same model): --sizes 9000,25000 grows <data>_<n> (same seed: a superset of <data>, with the same
held-out trees) and trains DFS / Full on each, scored against <data>'s held-out trees; writes results/ablation_data.json."""
import argparse, json, os, platform, resource, subprocess, sys, time
from pathlib import Path
import provenance   # scripts/provenance.py, beside this script
import numpy as np
ORDER_RUNS, ARCH_RUNS = [(o, "full") for o in ("zyx", "hilbert", "dfs", "bfs")], [("dfs", a) for a in ("pt", "hg1", "hg2", "hg2r", "full")]

def one_run(a, order, arch, lr, out):
    "Train in this process, then score; write out/result.json."
    import torch; torch.set_num_threads(a.threads)
    from treebook.train import train, perplexity, load_pretrained; from treebook.datasets import load_trees
    from treebook.sampling import sample; from treebook.metrics import tree_clouds, sample_scores
    t0 = time.time()
    r = train(a.data, out, order=order, arch=arch, dim=a.dim, depth=a.depth, heads=a.heads, batch_size=a.batch_size, steps=a.steps, lr=lr,
              warmup=a.steps // 10, val_trees=a.val_trees, ckpt_every=min(a.steps, 100), progress=False, resume=(out / "last.pt").exists(), seed=a.seed)
    peak_mb, (model, tok) = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024, load_pretrained(out / "best.pt")
    test, trn = load_trees(a.test_data or a.data, "test"), load_trees(a.data, "train")
    cache = Path(a.runs) / "reference_clouds.npz"  # held-out and (500) training clouds, made once for all runs
    if not cache.exists(): np.savez(cache, R=tree_clouds(test, seed=2, progress=False), T=tree_clouds(trn[:500], seed=3, progress=False))
    with np.load(cache) as z: R, T = z["R"], z["T"]
    seqs, free = (sample(model, a.samples, tok=tok, temperature=1.0, structure=s, min_len=24, seed=a.seed + i) for i, s in ((0, True), (1, False)))
    sc = sample_scores(seqs, free, tok, R, T); s = sc["scores"]
    res = {"order": order, "arch": arch, "lr": lr, "steps": r["step"], "n_params": r["n_params"], "train_seconds": r["seconds"],
           "seconds_per_epoch": r["seconds"] / r["step"] * (len(trn) // a.batch_size), "peak_rss_mb": peak_mb,
           "PPL": perplexity(model, tok.encode_batch(test, order), batch_size=16)["ppl"], "Connect": sc["Connect_free"]["Connect"],
           "Connect_structure": sc["Connect_structure"]["Connect"], "FPD": s["FPD"],
           **{k: s[k] for k in ("MMD-CD", "COV-CD", "1-NNA", "JSD", "Unique", "Novel")}, "samples": len(sc["trees"]), "wall_seconds": time.time() - t0}
    for i, g in enumerate(sc["trees"][:4]): g.save(out / f"sample_{i}.npz")
    (out / "result.json").write_text(json.dumps(res, indent=1)); print(json.dumps(res))

def meta(a):
    "Provenance of a table: the command, commit, time, machine and setup."
    note = "2 CPU cores shared with other jobs (other training runs at the same time): times are comparable within a table only roughly"
    return {"command": "python scripts/ablation.py " + " ".join(sys.argv[1:]), "commit": provenance.commit(), "time": time.strftime("%Y-%m-%d %H:%M:%S"),
            "machine": {"platform": platform.platform(), "cpus": os.cpu_count(), "threads_per_run": a.threads, "note": note},
            "setup": {k: v for k, v in vars(a).items() if k not in ("_one", "only")}}

def run(a, order, arch, lr, data=None, runs=None) -> dict:
    "One row, trained on `data` and scored against a's held-out trees in its own process, unless its result.json exists."
    data, runs = data or a.data, runs or a.runs
    if not (out := Path(runs) / f"{order}-{arch}-{lr}" / "result.json").exists():
        args = [f"--{k.replace('_', '-')}={v}" for k, v in vars(a).items() if k not in ("only", "lr_sweep", "_one", "sizes", "test_data") and v is not None]
        print(f"== {data}: {order} / {arch} / lr {lr}", flush=True)
        subprocess.run([sys.executable, __file__, *args, f"--data={data}", f"--runs={runs}", f"--test-data={a.test_data or a.data}", "--_one", order, arch, str(lr)], check=True)
    return json.loads(out.read_text())

def sizes_table(a):
    "Table 3: DFS / Full trained on a.data and on supersets of it of a.sizes trees, scored against a.data's held-out trees."
    from treebook.datasets import generate_dataset, load_manifest
    rows, base = [], load_manifest(a.data)["config"]
    for n in [None] + [int(x) for x in a.sizes.split(",")]:
        data, runs = (a.data, a.runs) if n is None else (f"{a.data}_{n}", f"{a.runs}/trees{n}")
        if n is not None:  # resumable; a finished set is only checked
            generate_dataset(base["species"], n, data, max_branches=base["max_branches"], workers=2, seed=base["seed"])
        c = load_manifest(data)["counts"]
        rows.append({**run(a, "dfs", "full", a.lr, data, runs), "data": data, "trees": c["trees"], "train_trees": c["train"]})
    (provenance.ROOT / "results" / "ablation_data.json").write_text(json.dumps({**meta(a), "rows": rows}, indent=1))
    print(json.dumps(rows, indent=1))

if __name__ == "__main__":
    p = argparse.ArgumentParser()
    for k, v in dict(data="data/elm48", runs="runs/ablation", steps=300, dim=64, depth=6, heads=4, batch_size=8, lr=2e-3, samples=64,
                     val_trees=64, threads=1, seed=0, only=None, sizes=None, test_data=None).items(): p.add_argument(f"--{k.replace('_', '-')}", type=str if v is None else type(v), default=v)
    p.add_argument("--lr-sweep", action="store_true"); p.add_argument("--_one", nargs=3, default=None, help=argparse.SUPPRESS); a = p.parse_args()
    if a._one: one_run(a, *a._one[:2], float(a._one[2]), Path(a.runs) / "-".join(a._one)); sys.exit()
    if not (Path(a.data) / "manifest.json").exists(): __import__("treebook.datasets").datasets.generate_dataset("elm", 2400, a.data, max_branches=48, workers=1, seed=1)
    if a.sizes: sizes_table(a); sys.exit()
    jobs = [(o, ar, a.lr) for o, ar in ORDER_RUNS + [r for r in ARCH_RUNS if r not in ORDER_RUNS]] + ([("dfs", "full", lr) for lr in (1e-3, 5e-3)] if a.lr_sweep else [])
    jobs = [j for j in jobs if not a.only or f"{j[0]}-{j[1]}" in a.only.split(",")]
    results = {(order, arch, lr): run(a, order, arch, lr) for order, arch, lr in jobs}
    info = meta(a)
    tabs = {"orders": [results[(o, ar, a.lr)] for o, ar in ORDER_RUNS if (o, ar, a.lr) in results], "archs": [results[(o, ar, a.lr)] for o, ar in ARCH_RUNS if (o, ar, a.lr) in results],
            "lr": [results[k] for k in results if k[:2] == ("dfs", "full")]}
    for name, rows in tabs.items():
        if len(rows) == {"orders": len(ORDER_RUNS), "archs": len(ARCH_RUNS), "lr": 3}[name]: (provenance.ROOT / "results" / f"ablation_{name}.json").write_text(json.dumps({**info, "rows": rows}, indent=1))
    if len(tabs["orders"]) == len(ORDER_RUNS):  # the picture, like the tables, only from a whole table
        from treebook.tree import Tree
        from treebook.render import render, image_grid
        got = [(f, f"{o} #{i}") for o, _ in ORDER_RUNS for i in range(4) if (f := Path(a.runs) / f"{o}-full-{a.lr}" / f"sample_{i}.npz").exists()]
        if got: image_grid([render(Tree.load(f), size=(200, 200), backend="matplotlib") for f, _ in got], ncols=4, labels=[l for _, l in got]).save(provenance.ROOT / "results" / "ablation_samples.png")
    print(json.dumps({"orders": tabs["orders"], "archs": tabs["archs"]}, indent=1))
