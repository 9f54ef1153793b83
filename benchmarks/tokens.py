"""Benchmark of treebook.tokens: encode and decode 10,000 elm-like trees of about 200 branches; quantisation error by bin rule.

Usage: python benchmarks/tokens.py [--trees 10000] [--base 250] [--out results/tokens.json]
Writes results/tokens.json (with the command, git commit and machine).
Trees: `--base` elms grown by treebook.botany (max 200 branches; example_tree(6) cut to 200 if botany is missing),
each turned about z to `trees / base` angles (turning keeps the canonical frame).
"""
import argparse, json, os, platform, sys, time
from pathlib import Path
sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "scripts"))
import provenance   # scripts/provenance.py

import numpy as np

root = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(root))
from treebook.tree import example_tree  # noqa: E402
from treebook.tokens import ORDERS, Tokenizer, _AXIS, seq_length  # noqa: E402


def machine():
    cpu = platform.processor() or ""
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"): cpu = line.split(":", 1)[1].strip(); break
    except OSError: pass
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    return {"cpu": cpu, "cores": cores, "platform": platform.platform(), "python": platform.python_version(), "numpy": np.__version__}


def base_trees(n):
    try:
        from treebook import botany
        return [botany.grow_tree("elm", seed=s, max_branches=200) for s in range(n)], "treebook.botany.grow_tree('elm', max_branches=200)"
    except ImportError:
        return [example_tree(6, seed=s).prefix(200) for s in range(n)], "example_tree(6).prefix(200)"


def errors(tok, trees, kind="dfs"):
    "Round-trip error of `trees` through `tok`: per quantity, in canonical units (height 1); parents kept; Connect."
    coord, rad, rel, halfbins, same = [], [], [], [], 0
    for t in trees:
        s = tok.encode(t, kind)
        d = tok.decode(s)
        ref = t.normalize()[0].take(tok.order(t, kind))
        got = np.concatenate([d.start, d.end], 1).astype(np.float64)
        want = np.concatenate([ref.start, ref.end], 1).astype(np.float64)
        child = ref.parent >= 0  # snapped starts: compare children's starts with their parents' ends, as encoded
        want[child, :3] = want[ref.parent[child], 4:7]
        e = np.abs(got - want)
        coord.append(e[:, [0, 1, 2, 4, 5, 6]].ravel()); rad.append(e[:, [3, 7]].ravel())
        rel.append((e[:, [3, 7]] / np.maximum(want[:, [3, 7]], 1e-12)).ravel())
        w = tok.bin_widths[_AXIS[None, :], tok.quantise(ref, normalize=False)]
        halfbins.append((e / (w / 2)).max())
        same += d.parent.tolist() == ref.parent.tolist()
    c, r, rr = np.concatenate(coord), np.concatenate(rad), np.concatenate(rel)
    return {"coord_mean": float(c.mean()), "coord_p99": float(np.quantile(c, .99)), "coord_max": float(c.max()),
            "radius_mean": float(r.mean()), "radius_rel_mean": float(rr.mean()), "radius_rel_max": float(rr.max()),
            "max_error_in_half_bins": float(max(halfbins)), "parents_kept": same / len(trees)}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--trees", type=int, default=10_000)
    ap.add_argument("--base", type=int, default=250)
    ap.add_argument("--out", default=str(root / "results" / "tokens.json"))
    a = ap.parse_args()
    t0 = time.perf_counter()
    base, source = base_trees(a.base)
    turns = -(-a.trees // a.base)
    trees = [t.rotate_z(2 * np.pi * k / turns) for k in range(turns) for t in base][: a.trees]
    grow_s = time.perf_counter() - t0
    n = np.array([t.n for t in trees])
    print(f"{len(trees)} trees from {source}: {n.mean():.1f} branches on average (max {n.max()}), made in {grow_s:.1f}s")

    t0 = time.perf_counter(); tok = Tokenizer.fit(trees); fit_s = time.perf_counter() - t0
    length = seq_length(200)
    timing = {"fit_s": fit_s}
    for kind in ORDERS:
        t0 = time.perf_counter(); B = tok.encode_batch(trees, kind, length=length); enc = time.perf_counter() - t0
        t0 = time.perf_counter(); D = tok.decode_batch(B); dec = time.perf_counter() - t0
        assert all(len(d) == t.n for d, t in zip(D, trees))
        conn = [tok.connectivity(s) for s in B[:1000]]
        timing[kind] = {"encode_s": enc, "decode_s": dec, "connect_mean": float(np.mean([c.connect for c in conn])),
                        "connected": float(np.mean([c.connected for c in conn])), "connect_trees": len(conn)}
        print(f"{kind:8s} encode {enc:6.2f}s  decode {dec:6.2f}s  Connect {timing[kind]['connect_mean']:.3f} (first {len(conn)})")

    # bin rules: fit on the first half of the base trees (all turns), measure on the other half (one turn each)
    half = a.base // 2
    train = [t.rotate_z(2 * np.pi * k / 8) for k in range(8) for t in base[:half]]
    test = base[half:]
    rules = {"uniform": dict(rule="uniform", radius_rule=None), "quantile (mix 0.1)": dict(rule="quantile", radius_rule=None),
             "quantile (mix 0.02)": dict(rule="quantile", radius_rule=None, mix=0.02),
             "quantile, log radii": dict(rule="quantile", radius_rule="log"),
             "uniform, log radii, no margin": dict(margin=0.0), "uniform, log radii (default)": {}}
    table = {}
    for name, kw in rules.items():
        table[name] = errors(Tokenizer.fit(train, **kw), test)
        print(f"{name:22s} " + "  ".join(f"{k} {v:.3g}" for k, v in table[name].items()))

    commit = provenance.commit()
    res = {"command": "python " + " ".join(sys.argv), "commit": commit, "machine": machine(), "time": time.strftime("%Y-%m-%d %H:%M:%S"),
           "trees": len(trees), "source": source, "base_trees": a.base, "turns": turns, "branches_mean": float(n.mean()),
           "branches_max": int(n.max()), "sequence_length": length, "timing": timing,
           "bin_rules": {"train_trees": len(train), "test_trees": len(test), "errors": table,
                         "units": "canonical frame (tree height 1); radius_rel = |error| / radius"}}
    out = Path(a.out); out.parent.mkdir(exist_ok=True)
    out.write_text(json.dumps(res, indent=1))
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
