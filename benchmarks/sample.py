"""Time `treebook sample`: 16 trees from each shipped species' model on this machine's CPU (the elm's target: at most
15 s on 2 cores; a species of twice the branches writes sequences twice as long).

Usage: python benchmarks/sample.py [--species elm shadbush ...] [--n 16] [--repeats 3]
Writes results/sample.json: command, commit, machine, and for each species (default: every one that ships) the
seconds of each repeat, best and median, and the branches of the trees drawn, each model drawing as its card was
scored (`model_decoding`: structure-aware, or snapped where the card says so).
"""
import argparse, json, os, platform, sys, time
from pathlib import Path
sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "scripts"))
import provenance   # scripts/provenance.py
import numpy as np, torch
from treebook.train import sample_trees, load_pretrained, shipped_species, species_model, model_decoding

root = Path(__file__).resolve().parent.parent
p = argparse.ArgumentParser()
p.add_argument("--species", nargs="+", default=None, help="default: every species whose model ships")
p.add_argument("--n", type=int, default=16); p.add_argument("--repeats", type=int, default=3)
a = p.parse_args()
runs = {}
for name in a.species or shipped_species():
    t = time.time(); model = load_pretrained(species_model(name)); load_s = time.time() - t
    times, branches, way = [], [], model_decoding(name)   # as `treebook sample` draws by default
    for r in range(a.repeats):
        t = time.time(); trees = sample_trees(a.n, model=model, seed=r, structure=way); times.append(time.time() - t)
        branches.append(float(np.mean([x.n for x in trees])))
    runs[name] = {"load_seconds": load_s, "seconds": times, "best_s": min(times), "median_s": float(np.median(times)),
                  "branches_mean": branches, "max_len": model[0].config.max_len,
                  "decoding": "snap" if way == "snap" else "structure-aware"}
    print(name, json.dumps(runs[name]))
res = {"command": "python benchmarks/sample.py " + " ".join(sys.argv[1:]),
       "commit": provenance.commit(),
       "time": time.strftime("%Y-%m-%d %H:%M:%S"),
       "machine": {"platform": platform.platform(), "cpus": os.cpu_count(), "threads": torch.get_num_threads(),
                   "torch": torch.__version__, "load_average": os.getloadavg()},
       "n": a.n, "species": runs, "target": "16 elms in <= 15 s on 2 cores"}
(root / "results").mkdir(exist_ok=True)
(root / "results" / "sample.json").write_text(json.dumps(res, indent=1))
print(json.dumps(res, indent=1))
