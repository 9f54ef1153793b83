"""Branches that span the crown: how the branch lengths of sampled trees compare with procedural ones (chapter 05a,
`long_share`), with structure-aware decoding (as `treebook sample` draws), without it, and drawn without it and
snapped (`structure="snap"`: each loose start moved onto the nearest earlier end).

For each species whose model ships (or --model as row --key): --trees procedural trees of the model's branch cap
and --n samples each way (the same seed each way: the snapped are the free ones, repaired); the share of the
samples' branches longer (over their tree's height) than the procedural branches' 99.9th percentile, and than twice
it, and both 99th percentiles. Writes results/strays.json, keeping rows this call does not run, and
results/strays_NAME.png for --picture NAME: two procedural trees, two samples by structure-aware decoding and the same
two snapped; long branches red.

    .venv/bin/python benchmarks/strays.py                        # every shipped species, some minutes
    .venv/bin/python benchmarks/strays.py --species elm --n 2 --trees 2 --out tmp/strays.json --picture none
"""
import argparse, json, sys, time
from pathlib import Path
sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "scripts"))
import provenance   # scripts/provenance.py


def picture(procedural, samples, cut, path):
    "Two procedural trees, then the `samples`, side by side; branches longer than `cut` marked by red points."
    import numpy as np
    from treebook.render import image_grid, render
    from treebook.species_runs import relative_lengths
    tiles = []
    for t in list(procedural[:2]) + list(samples):
        long = np.flatnonzero(relative_lengths(t) > cut)
        s = np.linspace(0, 1, 40)[:, None]
        pts = [t.start[i, :3] + s * (t.end[i, :3] - t.start[i, :3]) for i in long]
        pts = np.concatenate(pts) if pts else None
        red = None if pts is None else np.tile([[220, 30, 30]], (len(pts), 1))
        scene = [t] + ([pts] if pts is not None else [])
        tiles.append(render(scene, view="front", size=(360, 360), colors=red).convert("RGB"))
    image_grid(tiles, ncols=len(tiles), pad=0).save(path)


if __name__ == "__main__":
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--species", nargs="+", default=None, help="default: every species whose model ships")
    p.add_argument("--n", type=int, default=24, help="samples a species, each way")
    p.add_argument("--trees", type=int, default=48, help="procedural trees a species")
    p.add_argument("--seed", type=int, default=0); p.add_argument("--threads", type=int, default=None)
    p.add_argument("--model", default=None, help="a checkpoint (.pt) instead of the species' shipped model")
    p.add_argument("--key", default=None, help="the row's name (default the species'); with --model, one species")
    p.add_argument("--picture", default="spruce", help="the species to picture (none: no picture)")
    p.add_argument("--out", default="results/strays.json")
    a = p.parse_args()
    if (a.model or a.key) and len(a.species or []) != 1: p.error("--model and --key go with one --species")
    import torch
    from tqdm.auto import tqdm
    from treebook.botany import species, grow_tree
    from treebook.species_runs import long_share
    from treebook.train import load_pretrained, sample_trees, shipped_species, species_model
    if a.threads: torch.set_num_threads(a.threads)
    out, settings = Path(a.out), dict(n=a.n, trees=a.trees, seed=a.seed)
    rows = provenance.kept_rows(out, **settings)
    for name in a.species or shipped_species():
        model = a.model or species_model(name)
        net, tok = load_pretrained(model)
        cap = min(species(name).max_branches, net.config.max_len // 8 - 2)
        ref = [grow_tree(species(name), 10**6 + i, max_branches=cap) for i in tqdm(range(a.trees), desc=name)]
        t0 = time.time()
        sa = sample_trees(a.n, model=(net, tok), seed=a.seed, structure=True, progress=True)
        free = sample_trees(a.n, model=(net, tok), seed=a.seed, structure=False, progress=True)
        snap = sample_trees(a.n, model=(net, tok), seed=a.seed, structure="snap", progress=True)
        key = a.key or name
        rows[key] = dict(window=net.config.window, max_branches=cap, structure=long_share(sa, ref),
                         free=long_share(free, ref), snap=long_share(snap, ref), seconds=time.time() - t0, model=model,
                         **provenance.stamp("benchmarks/strays.py"))
        print(key, json.dumps(rows[key]), flush=True)
        if a.picture == name:
            picture(ref, sa[:2] + snap[:2], rows[key]["structure"]["threshold"], out.parent / f"strays_{key}.png")
        provenance.write_rows(out, rows, **settings)   # after each species: an interrupted call keeps what it did
