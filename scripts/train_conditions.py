"""Train a conditional model (image, sketch or point cloud to tree; HourglassTree 4.4), evaluate it on held-out trees, optionally ship it.

Usage (resumable: run the same command again after a kill):
    python scripts/train_conditions.py --kind image --order dfs --out runs/elm-image-dfs --init runs/elm/best.pt --steps 300 [--ship]
    python scripts/train_conditions.py --kind image --order bfs --out runs/elm-image-bfs --steps 300      (BFS: from scratch, see below)
    python scripts/train_conditions.py --kind points --out runs/elm-points --init runs/elm/best.pt --steps 300 --baseline runs/elm/best.pt
    python scripts/train_conditions.py --kind image --out runs/elm-image-glimpse --from elm-image --glimpse --steps 2000 --lr 5e-4 --ship
        (start from a conditional model, add the glimpse: condition.Glimpse)
    python scripts/train_conditions.py ... --eval-only   (evaluate the run as it stands)
    python scripts/train_conditions.py --kind image ... --eval-only --fit --candidates 4   (the network, then fitted to the
        silhouette and best of 4 by IoU: rows "image/dfs+fit+best4", results/conditions_image_dfs_fit_best4.json)
    python scripts/train_conditions.py ... --device cuda --workers 12 --train-only   (train on a GPU, batches made by 12
        processes; --train-only writes the training record, results/conditions_<kind>_<order>[_glimpse][_<tag>].json, and stops:
        evaluate afterwards with --eval-only, on any machine, from the same --out)

Data: the training trees of data/elm, turned and mirrored, then photographed (`scan.silhouette`), sketched (`scan.sketch`) or
sampled (200 surface points); held-out: the first --n-eval test trees. The decoder starts from --init (a DFS-trained
unconditional model) or from scratch (--dim ...). Writes results/conditions_<kind>_<order>.json and merges the row into
results/conditions.json ("table").
"""
import argparse, json, os, platform, re, sys, time
from pathlib import Path
import numpy as np, torch
from treebook.datasets import load_trees
from treebook.tokens import Tokenizer
from treebook.hourglass import ModelConfig, TreeTransformer
from treebook.train import WEIGHTS, load_pretrained
from treebook.growth import extend_context, fit
from provenance import commit   # scripts/provenance.py
from treebook.condition import (ConditionalTree, cond_batch, save_conditional, load_conditional, evaluate_image, evaluate_points, N_QUERIES)

root = Path(__file__).resolve().parent.parent
p = argparse.ArgumentParser()
p.add_argument("--kind", required=True, choices=("image", "sketch", "points")); p.add_argument("--order", default="dfs", choices=("dfs", "bfs"))
p.add_argument("--out", required=True); p.add_argument("--data", default="data/elm"); p.add_argument("--init", default=None)
p.add_argument("--dim", type=int, default=64); p.add_argument("--depth", type=int, default=5); p.add_argument("--heads", type=int, default=4)
p.add_argument("--trees", type=int, default=4000); p.add_argument("--steps", type=int, default=300)
p.add_argument("--batch", type=int, default=8); p.add_argument("--lr", type=float, default=1e-3); p.add_argument("--warmup", type=int, default=20)
p.add_argument("--threads", type=int, default=1); p.add_argument("--time-limit", type=float, default=None)
p.add_argument("--n-eval", type=int, default=50); p.add_argument("--baseline", default=None, help="unconditional model for the points baseline")
p.add_argument("--seed", type=int, default=0); p.add_argument("--eval-only", action="store_true"); p.add_argument("--ship", action="store_true")
p.add_argument("--fit", action="store_true", help="image / sketch: fit each generated tree to the input silhouette / strokes (condition.fit_silhouette)")
p.add_argument("--candidates", type=int, default=1, help="image / sketch: keep the best of this many samples by IoU with the input")
p.add_argument("--no-broadcast", action="store_true", help="the prompt alone, without the summary added to every token (models before it)")
p.add_argument("--from", dest="from_", default=None, help="start from this conditional model (shipped name or .pt); its decoder replaces --init")
p.add_argument("--glimpse", action="store_true", help="add the glimpse: features of the input (image, strokes drawn from the front, points in a voxel grid) where the tree is being drawn")
p.add_argument("--device", default="cpu", help="where to train: cpu, cuda, cuda:1 ... (evaluation always runs on the CPU)")
p.add_argument("--workers", type=int, default=0, help="processes that make training batches ahead of the model (0: in turn, in this process)")
p.add_argument("--train-only", action="store_true", help="train, write the training record and stop (evaluate later with --eval-only)")
p.add_argument("--tag", default="", help="a name for this run in the results (results/conditions_<kind>_<order>[_glimpse]_<tag>.json, row ...+<tag>)")
a = p.parse_args()
variant = ("+fit" if a.fit else "") + (f"+best{a.candidates}" if a.candidates > 1 else "")
if variant and a.kind == "points": p.error("--fit and --candidates are for --kind image or sketch")
if variant and a.ship: p.error("--ship stores the network's own scores: ship without --fit / --candidates")
if a.train_only and (a.eval_only or a.ship or variant): p.error("--train-only stops after training: no --eval-only, --ship, --fit or --candidates")
if a.device != "cpu" and not torch.cuda.is_available(): p.error(f"--device {a.device}: no GPU is visible to PyTorch here")
torch.set_num_threads(a.threads)
out = root / a.out if not Path(a.out).is_absolute() else Path(a.out)
out.mkdir(parents=True, exist_ok=True)
train, test = load_trees(root / a.data, "train")[:a.trees], load_trees(root / a.data, "test")[:a.n_eval]
P = -(-N_QUERIES // 8) * 8
max_len = P + max(t.n for t in train + test) * 8 + 16
if a.from_:
    src_model, tok = load_conditional(a.from_)
    if src_model.kind != a.kind: p.error(f"--from {a.from_} is a {src_model.kind} model, not {a.kind}")
    dec = extend_context(src_model.decoder, max_len)
elif a.init:
    dec, tok = load_pretrained(a.init)
    dec = extend_context(dec, max_len)
else:
    tok = Tokenizer.fit(train[:2000])
    torch.manual_seed(a.seed)
    dec = TreeTransformer(ModelConfig(arch="full", dim=a.dim, depth=a.depth, heads=a.heads, max_len=max_len))
tok.save(out / "tokenizer.json")
torch.manual_seed(a.seed + 1)
broadcast = src_model.broadcast if a.from_ else not a.no_broadcast   # a model made before the summary keeps none
model = ConditionalTree(a.kind, dec, heads=dec.config.heads, broadcast=broadcast, glimpse=a.glimpse, tok=tok)
if a.from_:   # the source's encoder, prompt and summary; a glimpse it lacks starts at zero
    missing, unexpected = model.load_state_dict({k: v for k, v in src_model.state_dict().items() if not k.startswith("decoder.")}, strict=False)
    if unexpected or any(not (k.startswith("decoder.") or k.startswith("glimpse.")) for k in missing):
        p.error(f"--from {a.from_} does not fit this model (missing {[k for k in missing if not k.startswith('decoder.')]}, unexpected {unexpected})")
meta = {"kind": a.kind, "order": a.order, "init": a.from_ or a.init, "broadcast": broadcast, "glimpse": a.glimpse, "trees": len(train),
        "batch": a.batch, "lr": a.lr, "seed": a.seed}
meta["device"] = (torch.cuda.get_device_name(torch.device(a.device)) if a.device != "cpu" else
                  f"{a.threads} thread{'s' if a.threads > 1 else ''} of a {os.cpu_count()}-core CPU")
if a.init and not a.from_ and Path(a.init).suffix == ".pt": meta["init_meta"] = {k: v for k, v in torch.load(a.init, weights_only=True).get("meta", {}).items() if k in ("step", "val_loss")}
def make_batch(k): return cond_batch(a.kind, train, tok, k, a.batch, a.seed, a.order)

class Ahead:
    "make_batch(k) for the steps k in turn, made by a pool of forked processes `depth` steps ahead of the one asked for."
    def __init__(self, workers: int, depth: int):
        import multiprocessing as mp
        self.pool, self.depth, self.pending = mp.get_context("fork").Pool(workers, initializer=torch.set_num_threads, initargs=(1,)), depth, {}
    def __call__(self, k):
        for j in range(k, k + self.depth):
            if j not in self.pending: self.pending[j] = self.pool.apply_async(make_batch, (j,))
        for j in [j for j in self.pending if j < k]: del self.pending[j]
        return self.pending.pop(k).get()

if not a.eval_only:
    batches = Ahead(a.workers, 4 * a.workers) if a.workers else make_batch   # forked before the model goes to a GPU
    if a.device != "cpu": torch.backends.cuda.matmul.allow_tf32 = torch.backends.cudnn.allow_tf32 = True
    model.to(a.device)
    r = fit(model, batches, lambda m, b: m.loss(b), out, steps=a.steps, lr=a.lr, warmup=a.warmup, ckpt_every=5 if a.device == "cpu" else 200,
            log_every=5 if a.device == "cpu" else 25, time_limit=a.time_limit, meta=meta)
    model.cpu()
    print(json.dumps(r), flush=True)
base = f"conditions_{a.kind}_{a.order}" + ("_glimpse" if a.glimpse else "") + (f"_{a.tag}" if a.tag else "")
if a.train_only:   # the record --eval-only reads back: command, commit and machine of the training
    (root / "results").mkdir(exist_ok=True)
    rec = {"command": "python scripts/train_conditions.py " + " ".join(sys.argv[1:]),
           "commit": commit(),
           "time": time.strftime("%Y-%m-%d %H:%M:%S"), "machine": {"platform": platform.platform(), "cpus": os.cpu_count(), "device": meta["device"],
           "torch": torch.__version__}, "run": r | meta}
    (root / "results" / f"{base}.json").write_text(json.dumps(rec, indent=1))
    print("trained; evaluate with --eval-only"); sys.exit(0)
ck = torch.load(out / "last.pt", map_location="cpu", weights_only=True)
if model.broadcast and "summary.weight" not in ck["model"]:  # a run from before the broadcast summary
    model = ConditionalTree(a.kind, dec, heads=dec.config.heads, broadcast=False, glimpse=a.glimpse, tok=tok); meta["broadcast"] = False
model.load_state_dict(ck["model"]); model.eval()
res = {"command": "python scripts/train_conditions.py " + " ".join(sys.argv[1:]),
       "commit": commit(),
       "time": time.strftime("%Y-%m-%d %H:%M:%S"),
       "machine": {"platform": platform.platform(), "cpus": os.cpu_count(), "threads": a.threads, "torch": torch.__version__},
       "run": {"step": ck["step"], "steps_planned": a.steps if not a.eval_only else None, "seconds": ck["seconds"], "n_params": sum(q.numel() for q in model.parameters()),
               **meta, **ck.get("meta", {}), "decoder": vars(dec.config)}}
with torch.no_grad(): res["held_out_loss"] = float(np.mean([float(model.loss(cond_batch(a.kind, test, tok, k, 8, a.seed + 7, a.order, False)))
                                                            for k in range(4)]))
t0 = time.time()
pair = (model, tok)
if a.kind == "image": res["eval"] = evaluate_image(pair, test, seed=a.seed, fit=a.fit, candidates=a.candidates)
elif a.kind == "points":
    res["eval"] = evaluate_points(pair, test, baseline=load_pretrained(a.baseline) if a.baseline else None, seed=a.seed)
else:
    from treebook.scan import sketch, silhouette
    from treebook.condition import sketch_to_tree, silhouette_scores
    rows = []
    for i, t in enumerate(test):
        g = sketch_to_tree(sketch(t)[0], 1, a.seed + i, pair, fit=a.fit, candidates=a.candidates)[0]
        rows.append(silhouette_scores(silhouette(g) if g.n else np.zeros((224, 224)), silhouette(t)))
    res["eval"] = {k: float(np.mean([r[k] for r in rows])) for k in rows[0]} | {"n": len(rows)}
res["seconds_eval"] = time.time() - t0
# a figure: four held-out inputs and the silhouettes of the trees generated from them (same front camera)
from PIL import Image, ImageDraw
from treebook.scan import silhouette, sketch, _to_px
from treebook.render import image_grid
from treebook.metrics import sample_surface
from treebook.condition import image_to_tree, sketch_to_tree, points_to_tree, points_input
pics, labels = [], []
for i, t in enumerate(test[:4]):
    if a.kind == "image": inp, g = Image.fromarray(255 - silhouette(t)), image_to_tree(silhouette(t), 1, a.seed + i, pair, fit=a.fit, candidates=a.candidates)[0]
    elif a.kind == "sketch": inp, g = Image.fromarray(255 - sketch(t)[1]), sketch_to_tree(sketch(t)[0], 1, a.seed + i, pair, fit=a.fit, candidates=a.candidates)[0]
    else:
        pts = sample_surface(t, 4 * 200, a.seed + i)
        inp = Image.new("L", (224, 224), 255); dr = ImageDraw.Draw(inp)
        for x, y in _to_px(points_input(pts, a.seed + i)[1][:, [0, 2]], 224): dr.ellipse([x - 1, y - 1, x + 1, y + 1], fill=0)
        g = points_to_tree(pts, 1, a.seed + i, pair)[0]
    pics += [inp, Image.fromarray(255 - silhouette(g)) if g.n else Image.new("L", (224, 224), 255)]
    labels += [f"held-out {i}: input", f"generated ({g.n} branches)"]
(root / "results").mkdir(exist_ok=True)
name = base + variant.replace("+", "_")
if a.eval_only and (root / "results" / f"{base}.json").exists():   # keep the command that trained the run
    old = json.loads((root / "results" / f"{base}.json").read_text())
    res["train_command"] = old.get("train_command", old.get("command"))
    res["train_commit"] = old.get("train_commit", old.get("commit"))
    res["train_machine"] = old.get("train_machine", old.get("machine"))
    res["run"]["steps_planned"] = int(m.group(1)) if (m := re.search(r"--steps (\d+)", res["train_command"] or "")) else None   # the training's --steps
image_grid(pics, ncols=4, labels=labels).save(root / "results" / f"{name}.png")
(root / "results" / f"{name}.json").write_text(json.dumps(res, indent=1))
tp = root / "results" / "conditions.json"
table = json.loads(tp.read_text()) if tp.exists() else {"table": {}}
table["table"][f"{a.kind}/{a.order}{'+glimpse' if a.glimpse else ''}{'+' + a.tag if a.tag else ''}{variant}"] = {"step": ck["step"], "held_out_loss": res["held_out_loss"], **res["eval"], "details": {"record": f"results/{name}.json", **{k: v for k, v in res.items() if k != "eval"}}}
tp.write_text(json.dumps(table, indent=1))
print(json.dumps(res, indent=1))
if a.ship:
    target = WEIGHTS / f"elm-{a.kind}.pt"
    save_conditional(model, tok, target, **meta, step=ck["step"])
    c = dec.config
    ev = ", ".join(f"{k} {v:.4g}" for k, v in res["eval"].items() if isinstance(v, float))
    card = f"""# elm-{a.kind}: {a.kind} to tree

- **Data**: the first {len(train)} training trees of the `elm` dataset (`data/elm`), turned about z and mirrored, then {'photographed by `scan.silhouette` (front camera, 224 px, read at 112 px)' if a.kind == 'image' else 'sketched by `scan.sketch` (2D segments)' if a.kind == 'sketch' else 'sampled (200 points of the branch surfaces)'}; sequences in {a.order.upper()} order.
- **Model**: {a.kind} encoder ({'small CNN from scratch' if a.kind == 'image' else 'per-element MLP + one self-attention layer'}), {N_QUERIES} learnable queries with cross-attention (a 56-vector prefix){' and a pooled summary added to every token' if model.broadcast else ''}{'; the glimpse (a second small CNN over the ' + {'image': 'silhouette', 'sketch': 'strokes drawn by the front camera', 'points': 'points counted into a 32^3 voxel grid, in 3D'}[a.kind] + ', sampled where each token draws, `condition.Glimpse`)' if model.glimpse is not None else ''}, hourglass decoder arch `{c.arch}`, dim {c.dim}, depth {c.depth}, heads {c.heads}; {res['run']['n_params']:,} parameters; {('started from the conditional model `' + a.from_ + '` as it was at commit ' + res.get('train_commit', res['commit'])[:7]) if a.from_ else ('decoder started from `' + str(a.init) + '`') if a.init else 'decoder trained from scratch'}.
- **Training**: AdamW, peak lr {a.lr}, {a.warmup} warm-up steps then cosine, batch {a.batch}; {ck['step']} of {res['run']['steps_planned'] or a.steps} planned steps in {ck['seconds'] / 60:.1f} minutes on {ck.get('meta', {}).get('device') or str(a.threads) + ' thread(s) of a 2-core CPU'}.
- **Command**: `{res.get('train_command', res['command'])}` (commit {res.get('train_commit', res['commit'])[:7]}){'; evaluated and shipped by `' + res['command'] + '` (commit ' + res['commit'][:7] + ')' if 'train_command' in res else ''}.
- **Metrics** on {a.n_eval} held-out trees (`results/{name}.json`): held-out loss {res['held_out_loss']:.3f}; {ev}.
- **Limits**: a small model, trained for minutes on procedural elms of one species only; inputs unlike them (photographs, other species, other cameras) are outside what it has seen.
"""
    (WEIGHTS / f"elm-{a.kind}.md").write_text(card)
    print("shipped", target)
