"""Train and ship the species PointNet behind FPD (our stand-in for FID).

Usage: python scripts/train_species_pointnet.py [--per-species 150] [--epochs 30]
Writes treebook/data/weights/species_pointnet.pt and results/species_pointnet.json (command, commit, machine, accuracy).
"""
import argparse, json, os, platform, sys, time
from pathlib import Path
import provenance   # scripts/provenance.py, beside this script
import numpy as np, torch
from tqdm.auto import tqdm
from treebook.botany import SPECIES, grow_tree, species
from treebook.metrics import tree_clouds, train_species_pointnet, save_species_pointnet, POINTNET_POINTS

root = Path(__file__).resolve().parent.parent
p = argparse.ArgumentParser()
p.add_argument("--per-species", type=int, default=150); p.add_argument("--epochs", type=int, default=30)
p.add_argument("--seed", type=int, default=0); p.add_argument("--threads", type=int, default=1)
a = p.parse_args()
torch.set_num_threads(a.threads)
t0 = time.time()
names = list(SPECIES)
rng = np.random.default_rng(a.seed)
clouds, labels = [], []
for k, name in enumerate(names):
    sp = species(name)
    # a mix of sizes: the species' own cap, and smaller caps such as the 200 of the elm set
    caps = rng.choice([50, 100, 200, sp.max_branches or 400], a.per_species)
    trees = [grow_tree(sp, seed=10_000 * k + i, max_branches=int(c)) for i, c in enumerate(tqdm(caps, desc=name))]
    clouds.append(tree_clouds(trees, n=POINTNET_POINTS, seed=k * 100_000, progress=False)); labels += [k] * len(trees)
clouds, labels = np.concatenate(clouds), np.array(labels)
perm = rng.permutation(len(clouds)); n_test = len(clouds) // 5
te, tr = perm[:n_test], perm[n_test:]
t1 = time.time()
net = train_species_pointnet(clouds[tr], labels[tr], names, epochs=a.epochs, seed=a.seed)
with torch.no_grad(): acc = float((net(torch.from_numpy(clouds[te])).argmax(1).numpy() == labels[te]).mean())
commit = provenance.commit()
cmd = "python scripts/train_species_pointnet.py " + " ".join(sys.argv[1:])
out = root / "treebook" / "data" / "weights" / "species_pointnet.pt"
save_species_pointnet(net, out, accuracy=acc, command=cmd, commit=commit)
res = {"command": cmd, "commit": commit, "time": time.strftime("%Y-%m-%d %H:%M:%S"),
       "machine": {"platform": platform.platform(), "cpus": os.cpu_count(), "threads": a.threads, "torch": torch.__version__},
       "species": names, "trees_per_species": a.per_species, "points": POINTNET_POINTS, "epochs": a.epochs,
       "train_clouds": len(tr), "test_clouds": len(te), "test_accuracy": acc,
       "data_seconds": t1 - t0, "train_seconds": time.time() - t1, "weights": str(out.relative_to(root)), "weights_bytes": out.stat().st_size}
(root / "results").mkdir(exist_ok=True)
(root / "results" / "species_pointnet.json").write_text(json.dumps(res, indent=1))
print(json.dumps(res, indent=1))
