"""Where does the shipped TreePartNet's affinity go wrong? An error analysis on the held-out scans of train_partnet.py.

Usage: python scripts/partnet_errors.py [--work tmp/partnet5] [--refine] [--weights W --out results/X.json]   (needs the scan pools that train_partnet.py cached in --work)

For each held-out scan: the network's seed affinities (the shipped tta and threshold), the true part of each seed (the part of
the seed point itself, as in training and in the F1 of the notebook), and the majority part of the points the network
assigns to the seed (its fine cluster). A seed whose own part differs from its cluster's majority is "mixed": it sits where
two branches meet, and its label says one branch while its points say another. Reported: the share of mixed seeds, how many
false positives and false negatives involve one, and the affinity F1 of an oracle that calls a pair "one branch" exactly when
the two clusters' majority parts agree (a bound on what any rule reading the clusters' points can reach against these labels).
It also splits the scored pairs by the number of seeds on the smaller of the two parts (1, 2, 3 or more, and all), with the
errors and the pooled precision, recall and F1 of each group, and gives the share of seeds that are alone on their part.
With --refine: a gradient-boosted classifier (scikit-learn) on per-pair features (the network's affinity, distances,
principal axes of the two clusters, junction scores, shared neighbours), fitted on training scans, scored on the held-out ones.
Writes results/partnet_errors.json (or --out); --weights analyses other weights than the shipped ones.
"""
import argparse, json, sys, time
from pathlib import Path
import numpy as np, torch

root = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(root)); sys.path.insert(0, str(root / "scripts"))
import provenance
from train_partnet import load_or_make_pool, seed_outputs
from treebook.partnet import load_partnet, affinity_scores

ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
ap.add_argument("--work", default=str(root / "tmp" / "partnet5")); ap.add_argument("--threads", type=int, default=2)
ap.add_argument("--refine", action="store_true"); ap.add_argument("--refine-scans", type=int, default=300)
ap.add_argument("--weights", default=None, help="TreePartNet weights to analyse (default: the shipped ones)")
ap.add_argument("--out", default=str(root / "results" / "partnet_errors.json"), help="where to write the record")
a = ap.parse_args()
torch.set_num_threads(a.threads)
work = Path(a.work)
if not (work / "test_pool.npz").exists(): sys.exit(f"no scan pools in {work}: run scripts/train_partnet.py with --work {work} first")
model = load_partnet(a.weights); n, th = model.cfg.n_points, model.cfg.threshold


def majority(o):
    S = len(o["seed_xyz"]); maj = np.full(S, -1)
    for s in range(S):
        m = (o["fine"] == s) & (o["part"] >= 0)
        if m.any(): v, c = np.unique(o["part"][m], return_counts=True); maj[s] = v[c.argmax()]
    return maj


test = load_or_make_pool(work / "test_pool.npz")
outs = seed_outputs(model, test, n)   # exactly train_partnet.py's evaluation of the held-out scans
mixed, oracle, net, fp, fn, fp_mixed, fn_mixed = [], [], [], 0, 0, 0, 0
SIZES = ("1", "2", "3+")   # the seeds of the smaller part of a pair: a part of one seed can only have negative pairs
by_size, lone = {k: dict(pairs=0, tp=0, fp=0, fn=0) for k in SIZES}, []
for o in outs:
    sp, maj = o["seed_part"], majority(o)
    ok = sp >= 0
    mixed.append(float(np.mean(maj[ok] != sp[ok])))
    oracle.append(affinity_scores((maj[:, None] == maj[None]).astype(float), sp, 0.5, pairs=o["pairs"])["f1"])
    net.append(affinity_scores(o["prob"], sp, th, pairs=o["pairs"])["f1"])
    i, j = np.triu_indices(len(sp), 1)
    keep = (o["pairs"] | o["pairs"].T)[i, j] & (sp[i] >= 0) & (sp[j] >= 0)
    i, j = i[keep], j[keep]
    a_ = (o["affinity"] + o["affinity"].T) / 2
    y, p = sp[i] == sp[j], a_[i, j] > th
    mx = (maj[i] != sp[i]) | (maj[j] != sp[j])
    fp += int((p & ~y).sum()); fn += int((~p & y).sum()); fp_mixed += int((p & ~y & mx).sum()); fn_mixed += int((~p & y & mx).sum())
    _, inv, cnt = np.unique(sp, return_inverse=True, return_counts=True)
    seeds_of_part = cnt[inv.ravel()]
    lone.append(float(np.mean(seeds_of_part[ok] == 1)))
    small = np.minimum(seeds_of_part[i], seeds_of_part[j])
    for k, sel in zip(SIZES, (small == 1, small == 2, small >= 3)):
        d = by_size[k]; d["pairs"] += int(sel.sum()); d["tp"] += int((p & y & sel).sum()); d["fp"] += int((p & ~y & sel).sum()); d["fn"] += int((~p & y & sel).sum())
by_size["all"] = {c: sum(d[c] for d in by_size.values()) for c in ("pairs", "tp", "fp", "fn")}
for d in by_size.values():   # pooled over the scans (the records' affinity_f1 is the mean over the scans)
    pr, rc = d["tp"] / max(d["tp"] + d["fp"], 1), d["tp"] / max(d["tp"] + d["fn"], 1)
    d.update(precision=pr, recall=rc, f1=2 * pr * rc / max(pr + rc, 1e-12))
res = {"command": "python scripts/partnet_errors.py " + " ".join(sys.argv[1:]),
       "commit": provenance.commit(short=True), "weights": a.weights or "shipped", "junction_seeds": model.cfg.junction_seeds,
       "time": time.strftime("%Y-%m-%d %H:%M:%S"), "scans": len(outs), "threshold": th, "tta": model.cfg.tta,
       "affinity_f1": float(np.mean(net)), "mixed_seed_share": float(np.mean(mixed)), "majority_oracle_f1": float(np.mean(oracle)),
       "false_positives": fp, "false_positives_with_mixed_seed": fp_mixed, "false_negatives": fn, "false_negatives_with_mixed_seed": fn_mixed,
       "lone_seed_share": float(np.mean(lone)), "by_smaller_part_seeds": by_size}


def pair_features(o):
    "(features (m, 12), same part (m,), ok (m,), i, j) of the scored seed pairs (i < j)."
    q, fine, S = o["q"], o["fine"], len(o["seed_xyz"])
    jp = 1 / (1 + np.exp(-o["junction"]))
    axis, lin, size = np.tile([0.0, 0, 1], (S, 1)), np.zeros(S), np.zeros(S)
    for s in range(S):
        m = fine == s; size[s] = m.sum()
        if m.sum() >= 3:
            P = q[m] - q[m].mean(0); w, v = np.linalg.eigh(P.T @ P / m.sum())
            axis[s], lin[s] = v[:, -1], (w[-1] - w[-2]) / max(w[-1], 1e-12)
    js = jp[o["seed_idx"]]
    sc = o["pairs"] | o["pairs"].T
    i, j = np.nonzero(np.triu(sc, 1))
    A = np.where(sc, (o["affinity"] + o["affinity"].T) / 2, 0)
    both = sc[i] & sc[j]
    tri = np.where(both, np.minimum(A[i], A[j]), 0).max(1)
    x = o["seed_xyz"]; dx = x[j] - x[i]; d = np.linalg.norm(dx, axis=1); u = dx / np.maximum(d, 1e-9)[:, None]
    ci, cj = np.abs((axis[i] * u).sum(1)), np.abs((axis[j] * u).sum(1))
    F = np.column_stack([A[i, j], d, np.abs(dx[:, 2]), np.abs((axis[i] * axis[j]).sum(1)), np.minimum(ci, cj), np.maximum(ci, cj),
                         np.minimum(lin[i], lin[j]), np.minimum(js[i], js[j]), np.maximum(js[i], js[j]),
                         np.minimum(size[i], size[j]), tri, both.sum(1)])
    sp = o["seed_part"]
    return F, sp[i] == sp[j], (sp[i] >= 0) & (sp[j] >= 0), i, j


if a.refine:
    from sklearn.ensemble import HistGradientBoostingClassifier
    train = load_or_make_pool(work / "train_pool.npz")
    tr = seed_outputs(model, train[-a.refine_scans:], n, seed=4242)
    feats = [pair_features(o) for o in tr]
    clf = HistGradientBoostingClassifier(max_iter=300, random_state=0).fit(np.concatenate([f[0][f[2]] for f in feats]),
                                                                             np.concatenate([f[1][f[2]] for f in feats]))
    f1 = {}
    for t in (0.4, 0.45, 0.5):
        rows = []
        for o in outs:
            F, _, _, i, j = pair_features(o); S = len(o["seed_xyz"]); P = np.zeros((S, S))
            P[i, j] = P[j, i] = clf.predict_proba(F)[:, 1]
            rows.append(affinity_scores(P, o["seed_part"], t, pairs=o["pairs"])["f1"])
        f1[str(t)] = float(np.mean(rows))
    res["refined_f1"] = f1; res["refine_scans"] = len(tr)
Path(a.out).parent.mkdir(parents=True, exist_ok=True)
Path(a.out).write_text(json.dumps(res, indent=1))
print(json.dumps(res, indent=1))
