"""Does the training's augmentation (a random turn about z and a mirror, chapter 05 `augment`) move trees away from
the held-out ones, as the scores of chapter 06 see them? For each species: --n training trees against --n held-out
trees of its dataset, once as stored and once turned and mirrored as training sees them (`augment`), with the same
clouds otherwise (MMD-CD, COV-CD, 1-NNA, JSD: `treebook.metrics.evaluate`). If the turned trees score like the
stored ones, the procedural trees have no preferred azimuth and a model trained on turned trees loses nothing by it.
Writes results/orientation.json, keeping the species it holds that this call does not run.

    .venv/bin/python benchmarks/orientation.py --species elm            # 500 and 500 trees of data/elm, minutes
    .venv/bin/python benchmarks/orientation.py --species elm --n 8 --out tmp/orientation.json   # a check
"""
import argparse, json, sys, time
from pathlib import Path
sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "scripts"))
import provenance   # scripts/provenance.py

if __name__ == "__main__":
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--species", nargs="+", default=["elm"])
    p.add_argument("--data", default="data", help="the folder that holds data/NAME (`make species` makes it)")
    p.add_argument("--n", type=int, default=500, help="training and held-out trees a species")
    p.add_argument("--seed", type=int, default=0, help="the augmentation's seed (epoch 0, index i)")
    p.add_argument("--threads", type=int, default=None)
    p.add_argument("--out", default="results/orientation.json")
    a = p.parse_args()
    import torch
    from treebook.datasets import load_trees
    from treebook.metrics import evaluate, tree_clouds
    from treebook.train import augment
    if a.threads: torch.set_num_threads(a.threads)
    out = Path(a.out)
    old = json.loads(out.read_text()) if out.is_file() else {}
    rows = old.get("species", {})
    for name in a.species:
        t0 = time.time()
        train, test = load_trees(Path(a.data) / name, "train")[:a.n], load_trees(Path(a.data) / name, "test")[:a.n]
        R = tree_clouds(test, seed=2)
        stored = tree_clouds(train, seed=3)
        turned = tree_clouds([augment(t, a.seed, 0, i) for i, t in enumerate(train)], seed=3)
        keep = ("MMD-CD", "COV-CD", "1-NNA", "JSD")
        rows[name] = {"stored": {k: evaluate(stored, R)[k] for k in keep},
                      "turned": {k: evaluate(turned, R)[k] for k in keep},
                      "train": len(train), "test": len(test), "seconds": time.time() - t0,
                      "command": "python benchmarks/orientation.py " + " ".join(sys.argv[1:]),
                      "commit": provenance.commit(), "time": time.strftime("%Y-%m-%d %H:%M:%S")}
        print(name, json.dumps(rows[name]), flush=True)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps({"species": rows}, indent=1))
