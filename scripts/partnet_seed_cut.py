"""How the junction cut of TreePartNet's seed layout trades the seed-pair F1 against the clustering of the points.

Usage: python scripts/partnet_seed_cut.py [--work tmp/partnet5] [--cuts -2,-1,-0.5,0,0.5,1] [--scans 60]

With `junction_seeds` the seeds go only on points whose junction logit from a first pass is below 0 (the network's own
call, probability 0.5); the shipped weights keep it off (chapter 9a). This script moves that cut and scores the shipped
weights on the first --scans *training* scans (the ones train_partnet.py fits the merging on; never the held-out ones): a
lower cut keeps the seeds further from anything junction-like. The seed-pair F1 rises as the seeds leave the hard places,
while the points there go to seeds further away, so the scores over the points (NMI, point-pair F1) fall: a seed layout
cannot be judged by the seed scores alone. Writes results/partnet_seed_cut.json.
"""
import argparse, json, sys, time
from pathlib import Path
import torch

root = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(root)); sys.path.insert(0, str(root / "scripts"))
import provenance
from train_partnet import load_or_make_pool, seed_outputs, evaluate
from treebook.partnet import PartNetConfig, TreePartNet, load_partnet


class CutNet(TreePartNet):
    "TreePartNet whose seeds go on the points with a first-pass junction logit below `cut`."
    cut = 0.0
    @torch.no_grad()
    def seed_candidates(self, xyz, seed=None): return self(xyz, seed=seed)["junction"] < self.cut


ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
ap.add_argument("--work", default=str(root / "tmp" / "partnet5")); ap.add_argument("--cuts", default="-2,-1,-0.5,0,0.5,1")
ap.add_argument("--scans", type=int, default=60); ap.add_argument("--threads", type=int, default=2)
ap.add_argument("--out", default=str(root / "results" / "partnet_seed_cut.json"))
a = ap.parse_args()
torch.set_num_threads(a.threads)
if not (Path(a.work) / "train_pool.npz").exists(): sys.exit(f"no scan pools in {a.work}: run scripts/train_partnet.py with --work {a.work} first")
shipped = load_partnet()
cfg = PartNetConfig(**{**shipped.cfg.to_dict(), "junction_seeds": True})
model = CutNet(cfg); model.load_state_dict(shipped.state_dict()); model.eval()
train = load_or_make_pool(Path(a.work) / "train_pool.npz")[:a.scans]
rows = {}
for c in [float(x) for x in a.cuts.split(",")]:
    model.cut = c
    outs = seed_outputs(model, train, cfg.n_points, seed=777)   # the scans and seeds of train_partnet.py's merging fit
    r = evaluate(outs, cfg.threshold, cfg.linkage)
    rows[f"{c:g}"] = r
    print(f"cut {c:+.1f}: affinity F1 {r['aff_f1']:.3f}, merged F1 {r['f1']:.3f}, RI {r['ri']:.3f}, NMI {r['nmi']:.3f}, point-pair F1 {r['point_f1']:.3f}", flush=True)
res = dict(command="python scripts/partnet_seed_cut.py " + " ".join(sys.argv[1:]), commit=provenance.commit(short=True),
           time=time.strftime("%Y-%m-%d %H:%M:%S"), scans=len(train), split="training scans", threshold=cfg.threshold,
           linkage=cfg.linkage, tta=cfg.tta, rows=rows)
Path(a.out).write_text(json.dumps(res, indent=1))
print(f"wrote {a.out}")
