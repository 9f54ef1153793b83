"""Give trained TreePartNet weights a pair context (partnet.PairContext): a second look at each scored seed pair, from the seeds' other pairs.

Usage: python scripts/train_pair_context.py [--weights W] [--out tmp/partnet-context/partnet.pt] [--results results/partnet_context.json]

The network runs once on scans of new trees (seed --pool-seed, which no network run trained on): the pair context is fitted to its outputs
on all but the first --fit-scans of them, and the merging (linkage and threshold, for the best mean merged F1, as train_partnet does) is chosen
on those first scans. Then every --tests set (SEED:PER_SPECIES, the held-out trees 1000 * SEED + i) is scored twice from the same network
outputs: as the weights were, at their own merging, and with the pair context, at the new one. Pools and network outputs are cached in --work
(the outputs with a fingerprint of the network, so other weights are run again).
The record also keeps the best merging of the network alone on the same first scans (network_threshold_fit), chosen the same way: the
pair context is worth shipping only if it builds better branches there, not only better pair decisions.
"""
import argparse, hashlib, json, sys, time
from dataclasses import replace
from pathlib import Path

import torch

root = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(root)); sys.path.insert(0, str(root / "scripts"))
import provenance
from train_partnet import LINKAGES, choose_merging, load_or_make_pool, mean_scores, scan_scores, seed_outputs
from treebook.partnet import TreePartNet, load_partnet, network_state, refine_pairs, save_partnet, train_pair_context
from treebook.tree import _atomic_write


def fingerprint(model) -> str:
    "A short hash of the network's config (as it runs: tta included) and weights, without its pair context: what its outputs depend on."
    cfg = {k: v for k, v in model.cfg.to_dict().items() if k not in ("threshold", "linkage", "pair_context")}
    h = hashlib.sha1(json.dumps(cfg, sort_keys=True).encode())
    for k, v in sorted(network_state(model.state_dict()).items()): h.update(k.encode()); h.update(v.detach().cpu().numpy().tobytes())
    return h.hexdigest()[:12]


def outputs(model, pool, n, path: Path, seed=12345):
    "`seed_outputs` of the network alone (no pair context), cached at `path` (a list of dicts of arrays) with the network's fingerprint."
    key = fingerprint(model)
    if path.exists():
        blob = torch.load(path, weights_only=False)
        if isinstance(blob, dict) and blob.get("network") == key: return blob["outs"]   # (older caches: a bare list, run again)
    outs = seed_outputs(model, pool, n, seed=seed)
    _atomic_write(path, lambda f: torch.save(dict(network=key, outs=outs), f))
    return outs


def tests_arg(s):
    try: sets = [tuple(int(v) for v in t.split(":")) for t in s.split(",")]
    except ValueError: sets = None
    if not sets or any(len(t) != 2 or t[1] < 1 for t in sets): raise argparse.ArgumentTypeError(f"--tests wants SEED:PER_SPECIES,... with PER_SPECIES >= 1, got {s!r}")
    return sets


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--weights", default=None, help="the trained network (default: the shipped weights; a pair context they hold is replaced)")
    ap.add_argument("--out", default=str(root / "tmp" / "partnet-context" / "partnet.pt"))
    ap.add_argument("--results", default=str(root / "results" / "partnet_context.json"))
    ap.add_argument("--work", default=str(root / "tmp" / "partnet-context"))
    ap.add_argument("--pool-seed", type=int, default=4, help="the trees the pair context learns from: 1000 * this + i")
    ap.add_argument("--per-species", type=int, default=40)
    ap.add_argument("--fit-scans", type=int, default=60, help="the first scans of that pool, kept for choosing the merging")
    ap.add_argument("--tests", type=tests_arg, default=tests_arg("999:10,998:10,997:10"))
    ap.add_argument("--epochs", type=int, default=40)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--threads", type=int, default=2)
    a = ap.parse_args()
    if min(a.per_species, a.epochs, a.fit_scans) < 1: ap.error("--per-species, --epochs and --fit-scans must be at least 1")
    torch.set_num_threads(a.threads)
    work = Path(a.work); work.mkdir(parents=True, exist_ok=True)
    net = load_partnet(a.weights)
    base = replace(net.cfg, pair_context=False)
    if net.cfg.pair_context:
        plain = TreePartNet(base); plain.load_state_dict(network_state(net.state_dict())); net = plain.eval()
    n, pool_points = base.n_points, 2 * base.n_points
    pool = load_or_make_pool(work / f"pool_{a.pool_seed}_{a.per_species}.npz", n_per_species=a.per_species, seed=a.pool_seed, n_points=pool_points, desc="new trees")
    if a.fit_scans >= len(pool): ap.error(f"--fit-scans {a.fit_scans} leaves none of the {len(pool)} scans to learn from")
    t0 = time.time()
    outs = outputs(net, pool, n, work / f"outs_{a.pool_seed}_{a.per_species}.pt")
    t1 = time.time()
    ctx, learnt = train_pair_context(outs[a.fit_scans:], epochs=a.epochs, seed=a.seed)   # seed_outputs' dicts are what it reads
    context_seconds = time.time() - t1
    refine = lambda os: [refine_pairs(ctx, o) for o in os]
    linkage, threshold, fit = choose_merging(refine(outs[:a.fit_scans]), LINKAGES)
    net_fit = choose_merging(outs[:a.fit_scans], LINKAGES)[2]   # the network alone, chosen the same way: is the context worth having?
    best = lambda f: max(f.values())
    print(f"merging with the pair context: {linkage} at {threshold}; best mean merged F1 on the {a.fit_scans} new scans {best(fit):.4f} with it, {best(net_fit):.4f} without")
    tests = {}
    for seed, per in a.tests:
        test = load_or_make_pool(work / f"test_{seed}_{per}.npz", n_per_species=per, seed=seed, n_points=pool_points, desc=f"test trees {seed}")
        o = outputs(net, test, n, work / f"test_outs_{seed}_{per}.pt")
        rows = {"network": scan_scores(o, base.threshold, base.linkage), "with context": scan_scores(refine(o), threshold, linkage)}
        t = tests[f"{seed}x{per}"] = {k: dict(metrics=mean_scores(r), per_scan={s: [round(x[s], 5) for x in r] for s in ("aff_f1", "f1", "nmi")})
                                      for k, r in rows.items()}
        print(f"{seed}x{per}: affinity F1 {t['network']['metrics']['aff_f1']:.4f} -> {t['with context']['metrics']['aff_f1']:.4f}")
    model = TreePartNet(replace(base, pair_context=True, threshold=threshold, linkage=linkage))
    model.load_state_dict({**net.state_dict(), **{f"context.{k}": v for k, v in ctx.state_dict().items()}})
    commit = provenance.commit(short=True)
    command = "python scripts/train_pair_context.py " + " ".join(sys.argv[1:])
    meta = dict(weights=a.weights or "shipped", pool_seed=a.pool_seed, scans=len(pool), fit_scans=a.fit_scans, epochs=a.epochs, **learnt,
                context_seconds=round(context_seconds, 1), context_weights=sum(p.numel() for p in ctx.parameters()), network=fingerprint(net),
                threshold_fit=fit, network_threshold_fit=net_fit, threshold=threshold, linkage=linkage, network_threshold=base.threshold, network_linkage=base.linkage,
                minutes=round((time.time() - t0) / 60, 1), command=command, commit=commit, torch=str(torch.__version__))
    save_partnet(model.eval(), a.out, **meta)
    res = Path(a.results); res.parent.mkdir(exist_ok=True)
    _atomic_write(res, lambda f: f.write(json.dumps(dict(**meta, tests=tests), indent=1).encode()))
    print(f"wrote {a.out} and {res}")


if __name__ == "__main__":
    main()
