"""Train TreePartNet on procedural scans; resumable; writes the shipped weights, a model card and results/partnet_train.json.

Usage: python scripts/train_partnet.py [--minutes 45] [--steps 100000] [--work tmp/partnet] [--out treebook/data/weights/partnet.pt]

The pool of labelled scans (grown trees of all species, scanned with noise, outliers and holes) is made once and cached in
--work; checkpoints (model, optimiser, step, random state) are written there atomically every --every steps, so killing
and re-running the same command goes on where it stopped. Training stops at --steps or after --minutes of wall time.
"""
import argparse, json, os, platform, sys, time
from dataclasses import replace
from pathlib import Path

import numpy as np
import torch
from tqdm.auto import tqdm

root = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(root))
import provenance   # scripts/provenance.py, beside this script
from treebook.tree import _atomic_write
from treebook.botany import SPECIES, grow
from treebook.scan import scan
from treebook.partnet import (LINKAGES, PartNetConfig, TreePartNet, affinity_scores, augment, branch_chains, cluster_scores, merge_scores,
                              merge_seeds, network_state, normalize_points, partnet_loss, point_pair_scores, predict_seeds, save_partnet)


def scan_job(job):
    "One labelled scan: dict of points (m, 3), part (m,), junction (m,), species."
    name, s, n_points = job
    rng = np.random.default_rng(s)
    t = grow(name, seed=s, stages=1)[-1]
    sc = scan(t, n_points=n_points, seed=s, noise=rng.uniform(0, 0.004), outliers=rng.uniform(0, 0.02),
              missing=int(rng.integers(0, 3)), views=int(rng.integers(2, 5)))
    chain = branch_chains(t)
    part = np.where(sc.branch >= 0, chain[np.maximum(sc.branch, 0)], -1)
    return dict(points=sc.points, part=part.astype(np.int32), junction=sc.junction, species=name)


def make_pool(n_per_species: int, seed: int, n_points: int, desc: str):
    "Raw labelled scans (`scan_job`), made by one process per core; the same scans whatever the number of cores."
    from concurrent.futures import ProcessPoolExecutor
    jobs = [(name, 1000 * seed + i, n_points) for i in range(n_per_species) for name in SPECIES]
    with ProcessPoolExecutor(os.cpu_count()) as ex: return list(tqdm(ex.map(scan_job, jobs, chunksize=4), total=len(jobs), desc=desc))


def load_or_make_pool(path: Path, **kw):
    if path.exists():
        with np.load(path, allow_pickle=False) as z:  # read each array once: every z[...] reads the whole array again
            P, T, J, off, species = (z[k] for k in ("points", "part", "junction", "offsets", "species"))
            made_with = int(z["seed"]) if "seed" in z else None   # pools made before the seed was kept, or unpacked ones: unknown
        want = kw.get("n_points")  # a cached pool must hold what the command asks for (callers that only read it pass nothing)
        if want and len(off) > 1 and not np.all(np.diff(off) == want):
            sys.exit(f"{path} holds scans of {sorted(set(np.diff(off).tolist()))} points, not {want}: use another --work or --pool-points")
        if kw.get("seed") is not None and made_with is not None and made_with != kw["seed"]:
            sys.exit(f"{path} holds the scans of seed {made_with}, not {kw['seed']}: use another --work")
        return [dict(points=P[a:b], part=T[a:b], junction=J[a:b], species=str(sp)) for a, b, sp in zip(off[:-1], off[1:], species)]
    pool = make_pool(**kw)
    off = np.concatenate([[0], np.cumsum([len(p["points"]) for p in pool])])
    _atomic_write(path, lambda f: np.savez(f, points=np.concatenate([p["points"] for p in pool]),
                                           part=np.concatenate([p["part"] for p in pool]),
                                           junction=np.concatenate([p["junction"] for p in pool]),
                                           offsets=off, species=np.array([p["species"] for p in pool]), seed=np.array(kw["seed"])))
    return pool


def example(raw: dict, n: int, seed: int, aug: bool = True):
    rng = np.random.default_rng(seed)
    pick = rng.choice(len(raw["points"]), n, replace=len(raw["points"]) < n)
    p = raw["points"][pick].astype(np.float64)
    if aug: p = augment(p, seed=seed)
    q, _, _ = normalize_points(p)
    return q, raw["part"][pick].astype(np.int64), raw["junction"][pick].astype(np.float32)


def batch(pool, idx, n, seed, aug=True):
    ex = [example(pool[i], n, seed * 7919 + k, aug) for k, i in enumerate(idx)]
    return (torch.from_numpy(np.stack([e[0] for e in ex])), torch.from_numpy(np.stack([e[1] for e in ex])),
            torch.from_numpy(np.stack([e[2] for e in ex])))


def seed_outputs(model, pool, n, seed=12345) -> list:
    "Per scan of `pool` (no augmentation, a fixed subset): `predict_seeds`'s outputs, the cloud `q`, its labels `part`, the seeds' parts, junction accuracy."
    outs = []
    for k, raw in enumerate(pool):
        q, part, junc = batch(pool, [k], n, seed + k, aug=False)
        o = predict_seeds(model, q[0].numpy(), seed=seed, tta=model.cfg.tta)  # pairs the network does not score are "not one branch"
        outs.append(dict(o, q=q[0].numpy(), seed_part=part[0].numpy()[o["seed_idx"]], part=part[0].numpy(),
                         junction_acc=float(((o["junction"] > 0) == junc[0].numpy().astype(bool)).mean())))
    model.train()
    return outs


def evaluate(outs, threshold, linkage):
    "Mean RI, NMI, merging precision/recall/F1 (seed pairs and point pairs), junction accuracy over `seed_outputs`, merging at `threshold` by `linkage`."
    return mean_scores(scan_scores(outs, threshold, linkage))


def mean_scores(rows) -> dict:
    "The mean over the scans of each score in `rows` (`scan_scores`)."
    return {k: float(np.mean([r[k] for r in rows])) for k in rows[0]}


def scan_scores(outs, threshold, linkage) -> list:
    "`evaluate`'s scores for each scan of `seed_outputs` (a dict per scan)."
    th, rows = threshold, []
    for o in outs:
        sb, sp = merge_seeds(o["prob"], th, linkage=linkage, pairs=o["pairs"]), o["seed_part"]
        af = affinity_scores(o["prob"], sp, th, pairs=o["pairs"])  # the network's own decisions
        branch = sb[o["fine"]]  # the branch of each point: that of its fine cluster's seed
        cs, fs, ms = cluster_scores(branch, o["part"]), cluster_scores(o["fine"], o["part"]), merge_scores(sb, sp)
        pps = point_pair_scores(branch, o["part"])  # over the points: does not depend on where the seeds sit
        rows.append(dict(ri=cs["ri"], nmi=cs["nmi"], clusters=cs["clusters"], true_parts=int(len(np.unique(sp[sp >= 0]))),
                         fine_ri=fs["ri"], fine_nmi=fs["nmi"], precision=ms["precision"], recall=ms["recall"], f1=ms["f1"],
                         aff_precision=af["precision"], aff_recall=af["recall"], aff_f1=af["f1"], point_precision=pps["precision"], point_recall=pps["recall"], point_f1=pps["f1"],
                         junction_acc=o["junction_acc"]))
    return rows


GRID = np.round(np.arange(0.30, 0.705, 0.02), 2)


def fit_threshold(model, pool, n, linkages=("closure",), grid=GRID):
    "(linkage, threshold) with the best mean merged F1 on `pool` (training scans), and that F1 for every pair tried ('linkage@threshold')."
    return choose_merging(seed_outputs(model, pool, n, seed=777), linkages, grid)


def choose_merging(outs, linkages=("closure",), grid=GRID):
    "`fit_threshold` on given `seed_outputs`."
    f1 = {(l, float(t)): float(np.mean([merge_scores(merge_seeds(o["prob"], t, linkage=l, pairs=o["pairs"]), o["seed_part"])["f1"] for o in outs]))
          for l in linkages for t in grid}
    linkage, threshold = max(f1, key=f1.get)
    return linkage, threshold, {f"{l}@{t:.2f}": v for (l, t), v in f1.items()}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--minutes", type=float, default=45)
    ap.add_argument("--steps", type=int, default=100_000)
    ap.add_argument("--batch", type=int, default=2)
    ap.add_argument("--lr", type=float, default=1e-3)
    ap.add_argument("--train-per-species", type=int, default=60)
    ap.add_argument("--test-per-species", type=int, default=5)
    ap.add_argument("--test-seed", type=int, default=999, help="the held-out trees: 1000 * this + i (999: the scans every record before it used)")
    ap.add_argument("--every", type=int, default=25)
    ap.add_argument("--work", default=str(root / "tmp" / "partnet"))
    ap.add_argument("--out", default=str(root / "treebook" / "data" / "weights" / "partnet.pt"))
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--no-cosine", action="store_true", help="ablation: plain MLP affinity instead of the scaled cosine distance")
    ap.add_argument("--no-focal", action="store_true", help="ablation: BCE instead of the focal loss")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--width", type=int, default=PartNetConfig.width, help="channels of the PointNet++ backbone")
    ap.add_argument("--results", default=None, help="where to write the training record (default results/partnet_train*.json)")
    ap.add_argument("--points", type=int, default=PartNetConfig.n_points, help="points the network takes per cloud (a random subset of each scan)")
    ap.add_argument("--pool-points", type=int, default=None, help="points per scan in the pools (default twice --points)")
    ap.add_argument("--init", default=None, help="start from these weights (same sizes); layers they lack start fresh")
    ap.add_argument("--no-pair-term", action="store_true", help="the affinity without the learned pair term (as in the paper)")
    ap.add_argument("--fit-scans", type=int, default=60, help="training scans on which to choose the merging threshold (0: keep 0.5)")
    ap.add_argument("--linkage", default="auto", choices=("auto", *LINKAGES), help="how seeds merge; auto: the better on the --fit-scans (closure with --fit-scans 0)")
    ap.add_argument("--device", default="cpu", help="where to train: cpu, cuda ... (evaluation runs on the CPU)")
    ap.add_argument("--train-only", action="store_true", help="train, write the checkpoint in --work and stop; the same command without it evaluates and ships")
    ap.add_argument("--tta", type=int, default=1, help="test-time passes over turned copies of each cloud, averaged (partnet.predict_seeds)")
    ap.add_argument("--junction-seeds", action="store_true", help="seeds only off the junctions the network itself finds, in training and after (PartNetConfig.junction_seeds)")
    ap.add_argument("--patch-term", action="store_true", help="add the pair-patch term to the affinity (PartNetConfig.patch_term, partnet.PairPatch)")
    ap.add_argument("--patch-points", type=int, default=PartNetConfig.patch_points, help="with --patch-term: the points nearest each seed that it reads")
    ap.add_argument("--freeze-init", action="store_true", help="with --init: train only the layers those weights lack; the others stay as they are")
    a = ap.parse_args()
    if a.tta < 1: ap.error("--tta must be at least 1")
    if a.freeze_init and not a.init: ap.error("--freeze-init needs --init")
    if a.patch_points < 1: ap.error("--patch-points must be at least 1")
    torch.set_num_threads(a.threads)
    cfg = PartNetConfig(cosine=not a.no_cosine, focal=not a.no_focal, width=a.width, n_points=a.points, pair_term=not a.no_pair_term,
                        junction_seeds=a.junction_seeds, patch_term=a.patch_term, patch_points=a.patch_points)
    pool_points = a.pool_points or 2 * cfg.n_points
    if pool_points < cfg.n_points: ap.error(f"--pool-points {pool_points} is fewer than --points {cfg.n_points}")
    work = Path(a.work); work.mkdir(parents=True, exist_ok=True)
    train = load_or_make_pool(work / "train_pool.npz", n_per_species=a.train_per_species, seed=1 + a.seed, n_points=pool_points, desc="train scans")
    test = load_or_make_pool(work / "test_pool.npz", n_per_species=a.test_per_species, seed=a.test_seed, n_points=pool_points, desc="test scans")
    gpu = a.device != "cpu" and torch.cuda.is_available()   # without one, a finished GPU run can still be evaluated here
    torch.manual_seed(a.seed)
    model = TreePartNet(cfg).to(a.device if gpu else "cpu")
    src = torch.load(a.init, map_location="cpu", weights_only=False) if a.init else None
    if a.freeze_init:  # the same layers are frozen whether the run starts or resumes
        for k, p in model.named_parameters(): p.requires_grad_(k not in src["state"])
        if not any(p.requires_grad for p in model.parameters()): ap.error(f"--freeze-init: {a.init} holds every layer, so nothing would train")
    opt = torch.optim.Adam([p for p in model.parameters() if p.requires_grad], lr=a.lr)
    device = torch.cuda.get_device_name(torch.device(a.device)) if gpu else f"{platform.machine()}, {a.threads} threads (CPU)"
    ck = work / "checkpoint.pt"
    commit = provenance.commit(short=True)
    command = "python scripts/train_partnet.py " + " ".join(sys.argv[1:])
    trained_by = dict(command=command, commit=commit)   # what made the checkpoint, kept when another command resumes it
    step, elapsed, log, train_scans = 0, 0.0, [], len(train)
    if ck.exists():
        blob = torch.load(ck, map_location="cpu", weights_only=False)
        if PartNetConfig.from_dict(blob["config"]) != cfg: sys.exit(f"{ck} was made with another config; use another --work")
        model.load_state_dict(blob["model"]); opt.load_state_dict(blob["opt"])
        step, elapsed, log = blob["step"], blob["elapsed"], blob["log"]
        device, train_scans = blob.get("device", device), blob.get("train_scans", len(train))   # where it was trained
        trained_by = blob.get("trained_by", trained_by)
        print(f"resumed at step {step} ({elapsed / 60:.1f} min)" + (f"; {a.init} is not read for the weights: the checkpoint's are used" if a.init else ""))
    elif a.init:
        theirs = PartNetConfig.from_dict(src["config"])
        if replace(theirs, n_points=cfg.n_points, pair_term=cfg.pair_term, threshold=cfg.threshold, linkage=cfg.linkage, tta=cfg.tta, junction_seeds=cfg.junction_seeds,
                   patch_term=cfg.patch_term, patch_points=cfg.patch_points, pair_context=cfg.pair_context) != cfg: sys.exit(f"{a.init} has another config ({theirs}); --init needs the same sizes")
        net_only = network_state(src["state"])
        if len(net_only) < len(src["state"]):   # a pair context fits the network it was trained on: it is not carried over
            src["state"] = net_only
            print(f"{a.init}: its pair context is left out (train a new one with scripts/train_pair_context.py)")
        missing, unexpected = model.load_state_dict(src["state"], strict=False)
        if unexpected: sys.exit(f"{a.init} holds weights this model lacks: {unexpected}")
        print(f"started from {a.init}; fresh: {', '.join(missing) or 'nothing'}{' (the only layers trained)' if a.freeze_init else ''}")
    def save_checkpoint():
        blob = dict(model={k: v.cpu() for k, v in model.state_dict().items()}, opt=opt.state_dict(), step=step, elapsed=time.time() - t0, log=log,
                    config=cfg.to_dict(), device=device, train_scans=train_scans, trained_by=trained_by)
        _atomic_write(ck, lambda f: torch.save(blob, f))
    if a.device != "cpu" and not gpu and step < a.steps and elapsed < a.minutes * 60:
        ap.error(f"--device {a.device}: no GPU is visible to PyTorch here, and the run in {work} has steps left")
    rng = np.random.default_rng([a.seed, step])
    t0 = time.time() - elapsed
    bar = tqdm(total=a.steps, initial=step, desc="train")
    run = []
    while step < a.steps and time.time() - t0 < a.minutes * 60:
        for g in opt.param_groups: g["lr"] = a.lr * (0.1 if time.time() - t0 > 0.8 * a.minutes * 60 else 1.0)
        q, part, junc = batch(train, rng.integers(len(train), size=a.batch), cfg.n_points, seed=step)
        q, part, junc = q.to(a.device), part.to(a.device), junc.to(a.device)  # (a GPU: checked above)
        s = int(rng.integers(1 << 30))
        out = model(q, seed=s, seed_mask=model.seed_candidates(q, seed=s))  # with --junction-seeds a first pass (no gradient) finds the junctions
        loss, parts = partnet_loss(out, part, junc, cfg)
        opt.zero_grad(); loss.backward(); opt.step()
        step += 1; run.append([loss.item(), parts["junction"], parts["fine"], parts["affinity"]])
        bar.update(1); bar.set_postfix(loss=f"{np.mean([r[0] for r in run[-20:]]):.3f}")
        if step % a.every == 0:
            log.append(dict(step=step, minutes=(time.time() - t0) / 60, **dict(zip(["loss", "junction", "fine", "affinity"], np.mean(run, 0).tolist()))))
            run = []
            save_checkpoint()
    bar.close()
    if step and (not log or log[-1]["step"] != step): save_checkpoint()  # the last steps since a checkpoint, so that a re-run evaluates these weights
    # (nothing trained, nothing saved: a later --steps 0 in the same --work then evaluates its own --init, not these weights)
    if a.train_only: print(f"trained {step} steps; evaluate with the same command without --train-only"); return
    model.cpu()
    minutes = (time.time() - t0) / 60
    fit = {}
    cfg.tta = a.tta  # cfg is model.cfg: what is set here is what the network is evaluated and saved with
    cfg.linkage = "closure" if a.linkage == "auto" else a.linkage
    if a.fit_scans > 0:  # choose the merging threshold (and linkage) on training scans, never on the held-out ones
        cfg.linkage, cfg.threshold, fit = fit_threshold(model, train[:a.fit_scans], cfg.n_points, LINKAGES if a.linkage == "auto" else (a.linkage,))
        print(f"merging: {cfg.linkage} at {cfg.threshold} (mean merged F1 on {a.fit_scans} training scans {fit[f'{cfg.linkage}@{cfg.threshold:.2f}']:.3f})")
    outs = seed_outputs(model, test, cfg.n_points)  # the network runs once; the three mergings below reuse its outputs
    rows = scan_scores(outs, cfg.threshold, cfg.linkage)
    metrics = mean_scores(rows)
    per_scan = {k: [round(r[k], 5) for r in rows] for k in ("aff_f1", "f1", "nmi")}   # in the pool's order: for intervals over the scans
    at_half = evaluate(outs, 0.5, "closure")  # the paper's merging
    metrics["closure_f1"] = evaluate(outs, cfg.threshold, "closure")["f1"] if cfg.linkage != "closure" else metrics["f1"]
    print(json.dumps(metrics, indent=1))
    meta = dict(steps=step, batch=a.batch, minutes=round(minutes, 1), train_scans=train_scans, test_scans=len(test), metrics=metrics,
                threshold=cfg.threshold, linkage=cfg.linkage, tta=cfg.tta, threshold_fit=fit, metrics_at_half=at_half, init=a.init,
                command=command, commit=commit, machine=device, trained_by=trained_by, torch=str(torch.__version__))
    out = Path(a.out)
    save_partnet(model, out, **meta)
    res = Path(a.results) if a.results else root / "results" / f"partnet_train{'_nocos' if a.no_cosine else ''}{'_nofocal' if a.no_focal else ''}.json"
    res.parent.mkdir(exist_ok=True)
    _atomic_write(res, lambda f: f.write(json.dumps(dict(config=cfg.to_dict(), log=log, **meta, per_scan=per_scan), indent=1).encode()))
    if out.name == "partnet.pt":
        card = f"""# TreePartNet weights (`partnet.pt`)

- **Model**: `treebook.partnet.TreePartNet` with `PartNetConfig` {json.dumps(cfg.to_dict())}; {sum(p.numel() for p in model.parameters()):,} parameters, {out.stat().st_size / 1e6:.1f} MB.
- **Data**: {len(train)} procedural trees ({a.train_per_species} per species: {', '.join(SPECIES)}), each scanned once by `treebook.scan.scan` at {pool_points} points with noise 0-0.4% of the size, 0-2% outliers, 0-2 missing regions and 2-4 views; every step takes {'all ' + str(cfg.n_points) + ' points, shuffled' if pool_points == cfg.n_points else 'a random ' + str(cfg.n_points) + '-point subset'}, turned about z, tilted up to 10 degrees, scaled 0.8-1.2, jittered, normalised into the unit sphere. Labels: branch chains (`branch_chains`) and the scanner's junction flags.{" Seeds: only on points that a first pass of the network does not call junctions (`junction_seeds`), in training and in use." if cfg.junction_seeds else ""}
- **Training**: {step} steps of batch {a.batch}, Adam lr {a.lr} (x0.1 for the last 20% of the time), {minutes:.0f} minutes on {meta['machine']}{f", starting from {a.init}" if a.init else ""}{" and training only the layers it lacks" if a.freeze_init else ""}. Merging: {cfg.linkage} {"(the paper's transitive closure)" if cfg.linkage == "closure" else "linkage"} at {cfg.threshold}, {"chosen on " + str(a.fit_scans) + " training scans for the best merged F1" if fit else "the paper's"}; {cfg.tta} test-time pass{"es over turned copies of the cloud, averaged" if cfg.tta > 1 else ""}{f" (held-out merged F1 with the paper's closure at 0.5: {at_half['f1']:.3f})" if fit else ""}.
- **Command**: `{trained_by['command']}` (commit {trained_by['commit']}){'' if trained_by['command'] == command else f'; evaluated by `{command}` (commit {commit})'}.
- **Held-out scores** ({len(test)} scans of trees with other seeds, {cfg.n_points} points, no augmentation): Rand index {metrics['ri']:.3f}, NMI {metrics['nmi']:.3f}, affinity of the neighbouring seed pairs the network scores precision {metrics['aff_precision']:.3f} / recall {metrics['aff_recall']:.3f} / F1 {metrics['aff_f1']:.3f}; merging (all seed pairs, after {"the closure" if cfg.linkage == "closure" else "average linkage"}) precision {metrics['precision']:.3f} / recall {metrics['recall']:.3f} / F1 {metrics['f1']:.3f}; point pairs in one branch (each point with its fine cluster's seed; independent of where the seeds sit) precision {metrics['point_precision']:.3f} / recall {metrics['point_recall']:.3f} / F1 {metrics['point_f1']:.3f}; junction accuracy {metrics['junction_acc']:.3f}; {metrics['clusters']:.1f} predicted vs {metrics['true_parts']:.1f} true parts among the seeds; fine clusters alone RI {metrics['fine_ri']:.3f}, NMI {metrics['fine_nmi']:.3f}.
- **Limits**: trained for {minutes:.0f} minutes, far short of the paper's schedule; procedural scans only (no foliage). On real scans use it through `treebook.reconstruct.reconstruct(method='partnet')`, which uses the branches to split the geodesic level sets, so a poor clustering degrades gracefully to the classic skeleton.
"""
        _atomic_write(out.with_suffix(".md"), lambda f: f.write(card.encode()))
    print(f"wrote {out} and {res}")


if __name__ == "__main__":
    main()
