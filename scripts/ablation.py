"""HourglassTree Tables 1 and 2 at CPU scale: the same tiny model, the same steps, the same elm set, varying the branch
order (zyx, Hilbert, DFS, BFS; arch Full) and the architecture (PT, HG1, HG2, HG2+R, Full; order DFS).

Usage: python scripts/ablation.py [--steps 300] [--threads 1] [--only dfs-full,...] [--lr-sweep]
Each run trains in its own process (for an honest peak memory), then is sampled and scored; finished runs are kept in
runs/ablation/<name>/result.json and skipped when the script runs again. Writes results/ablation_orders.json,
results/ablation_archs.json (command, commit, machine) and results/ablation_samples.png.
The data: `generate_dataset('elm', 2400, 'data/elm48', max_branches=48, workers=1, seed=1)` (made here if missing): elms
capped at 48 branches, so that a sequence is 400 tokens and nine runs fit in an hour on two shared cores.
"""
import argparse, json, os, platform, resource, subprocess, sys, time
from pathlib import Path
import provenance   # scripts/provenance.py, beside this script
import numpy as np

root = Path(__file__).resolve().parent.parent
ORDER_RUNS = [("zyx", "full"), ("hilbert", "full"), ("dfs", "full"), ("bfs", "full")]
ARCH_RUNS = [("dfs", "pt"), ("dfs", "hg1"), ("dfs", "hg2"), ("dfs", "hg2r"), ("dfs", "full")]


def one_run(a, order, arch, lr, out):
    "Train in this process, then score; write out/result.json."
    import torch
    torch.set_num_threads(a.threads)
    from treebook.train import train, perplexity
    from treebook.datasets import load_trees
    from treebook.sampling import sample
    from treebook.metrics import tree_clouds, evaluate, connect_rate, fpd
    t0 = time.time()
    r = train(a.data, out, order=order, arch=arch, dim=a.dim, depth=a.depth, heads=a.heads, batch_size=a.batch_size,
              steps=a.steps, lr=lr, warmup=a.steps // 10, val_trees=a.val_trees, ckpt_every=a.steps, progress=False,
              resume=(out / "last.pt").exists(), seed=a.seed)
    train_s = r["seconds"]
    peak_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    model = r["model"]
    from treebook.hourglass import TreeTransformer
    from treebook.tokens import Tokenizer
    model = TreeTransformer.load(out / "best.pt"); tok = Tokenizer.load(out / "tokenizer.json")
    test, trn = load_trees(a.data, "test"), load_trees(a.data, "train")
    ppl = perplexity(model, tok.encode_batch(test, order), batch_size=16)
    seqs = sample(model, a.samples, tok=tok, temperature=1.0, structure=True, min_len=24, seed=a.seed)
    free = sample(model, a.samples, tok=tok, temperature=1.0, structure=False, min_len=24, seed=a.seed + 1)
    gen = [g for g in (tok.decode(s) for s in seqs) if g.n]
    cache = Path(a.runs) / "reference_clouds.npz"  # held-out and (500) training clouds, made once for all runs
    if not cache.exists():
        R, T = tree_clouds(test, seed=2, progress=False), tree_clouds(trn[:500], seed=3, progress=False)
        np.savez(cache, R=R, T=T)
    with np.load(cache) as z: R, T = z["R"], z["T"]
    G = tree_clouds(gen, seed=1, progress=False)
    s = evaluate(G, R, train=T)
    per_epoch = len(trn) // a.batch_size
    res = {"order": order, "arch": arch, "lr": lr, "steps": r["step"], "n_params": r["n_params"], "train_seconds": train_s,
           "seconds_per_epoch": train_s / r["step"] * per_epoch, "peak_rss_mb": peak_mb, "PPL": ppl["ppl"],
           "Connect": connect_rate(free, tok)["Connect"], "Connect_structure": connect_rate(seqs, tok)["Connect"],
           "FPD": fpd(G, R), **{k: s[k] for k in ("MMD-CD", "COV-CD", "1-NNA", "JSD", "Unique", "Novel")},
           "samples": len(gen), "wall_seconds": time.time() - t0}
    for i, g in enumerate(gen[:4]): g.save(out / f"sample_{i}.npz")
    (out / "result.json").write_text(json.dumps(res, indent=1))
    print(json.dumps(res))


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--data", default="data/elm48"); p.add_argument("--runs", default="runs/ablation")
    p.add_argument("--steps", type=int, default=300); p.add_argument("--dim", type=int, default=64)
    p.add_argument("--depth", type=int, default=6); p.add_argument("--heads", type=int, default=4)
    p.add_argument("--batch-size", type=int, default=8); p.add_argument("--lr", type=float, default=2e-3)
    p.add_argument("--samples", type=int, default=64); p.add_argument("--val-trees", type=int, default=64)
    p.add_argument("--threads", type=int, default=1); p.add_argument("--seed", type=int, default=0)
    p.add_argument("--only", default=None); p.add_argument("--lr-sweep", action="store_true")
    p.add_argument("--_one", nargs=3, default=None, help=argparse.SUPPRESS)
    a = p.parse_args()
    if a._one:
        order, arch, lr = a._one
        return one_run(a, order, arch, float(lr), Path(a.runs) / f"{order}-{arch}-{lr}")
    if not (Path(a.data) / "manifest.json").exists():
        from treebook.datasets import generate_dataset
        generate_dataset("elm", 2400, a.data, max_branches=48, workers=1, seed=1)
    runs = ORDER_RUNS + [r for r in ARCH_RUNS if r not in ORDER_RUNS]
    jobs = [(o, ar, a.lr) for o, ar in runs] + ([("dfs", "full", lr) for lr in (1e-3, 5e-3)] if a.lr_sweep else [])
    if a.only: jobs = [j for j in jobs if f"{j[0]}-{j[1]}" in a.only.split(",")]
    passthrough = [f"--{k.replace('_', '-')}={v}" for k, v in vars(a).items() if k not in ("only", "lr_sweep", "_one") and v is not None]
    results = {}
    for order, arch, lr in jobs:
        out = Path(a.runs) / f"{order}-{arch}-{lr}"
        if not (out / "result.json").exists():
            print(f"== {order} / {arch} / lr {lr}", flush=True)
            subprocess.run([sys.executable, __file__, *passthrough, "--_one", order, arch, str(lr)], check=True)
        results[(order, arch, lr)] = json.loads((out / "result.json").read_text())
    meta = {"command": "python scripts/ablation.py " + " ".join(sys.argv[1:]),
            "commit": provenance.commit(),
            "time": time.strftime("%Y-%m-%d %H:%M:%S"),
            "machine": {"platform": platform.platform(), "cpus": os.cpu_count(), "threads_per_run": a.threads,
                        "note": "2 CPU cores shared with other jobs (the shipped model trained at the same time): times are comparable within a table only roughly"},
            "setup": {k: v for k, v in vars(a).items() if k not in ("_one", "only")}}
    (root / "results").mkdir(exist_ok=True)
    tab1 = [results[(o, "full", a.lr)] for o, _ in ORDER_RUNS if (o, "full", a.lr) in results]
    tab2 = [results[(o, ar, a.lr)] for o, ar in ARCH_RUNS if (o, ar, a.lr) in results]
    if tab1: (root / "results" / "ablation_orders.json").write_text(json.dumps({**meta, "rows": tab1}, indent=1))
    if tab2: (root / "results" / "ablation_archs.json").write_text(json.dumps({**meta, "rows": tab2}, indent=1))
    sweep = [results[k] for k in results if k[:2] == ("dfs", "full")]
    if len(sweep) > 1: (root / "results" / "ablation_lr.json").write_text(json.dumps({**meta, "rows": sweep}, indent=1))
    if tab1:
        from treebook.tree import Tree
        from treebook.render import render, image_grid
        ims, labels = [], []
        for o, _ in ORDER_RUNS:
            d = Path(a.runs) / f"{o}-full-{a.lr}"
            for i in range(4):
                f = d / f"sample_{i}.npz"
                if f.exists(): ims.append(render(Tree.load(f), size=(200, 200), backend="matplotlib")); labels.append(f"{o} #{i}")
        if ims: image_grid(ims, ncols=4, labels=labels).save(root / "results" / "ablation_samples.png")
    print(json.dumps({"orders": tab1, "archs": tab2}, indent=1))


if __name__ == "__main__":
    main()
