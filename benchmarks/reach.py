"""How far back a branch's parent lies, in procedural trees and in trees each shipped model samples without
structure-aware decoding, and how often such a branch is connected (chapter 05a, `parent_gaps`).

A model trained with `window=W` sees the last W/8 branches in its full-resolution layers: a parent further back
("far") is reached only through the shortened layers. For each species whose model ships: the share of far parents
in --trees procedural trees (the model's branch cap), and over --n free samples Connect of the branches whose parent
(or nearest earlier end) is near and of those whose is far. Writes results/reach.json, keeping the species it holds
that this call does not run.

    .venv/bin/python benchmarks/reach.py                                  # 48 samples a species, some minutes
    .venv/bin/python benchmarks/reach.py --species elm --n 4 --trees 4 --out tmp/reach.json   # a check
    .venv/bin/python benchmarks/reach.py --species hickory --model runs/hickory/best.pt --key hickory-2300
                                                    # a model that does not ship, as its own row
    .venv/bin/python benchmarks/reach.py --drop hickory-2300              # a row no longer wanted, nothing run
"""
import argparse, json, os, sys, time
from pathlib import Path
sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "scripts"))
import provenance   # scripts/provenance.py


def summary(pairs, far: int) -> dict:
    """Branches, the share whose parent lies more than `far` back (and more than 32, 64, 128), Connect of all, of the
    near and of the far ones, and the far ones' share of the unconnected."""
    import numpy as np
    g = np.concatenate([p[0] for p in pairs]); a = np.concatenate([p[1] for p in pairs])
    f = g > far
    rate = lambda m: float(a[m].mean()) if m.any() else None
    beyond = {k: float((g > k).mean()) for k in (32, 64, 128)}
    return dict(branches=int(len(g)), far_share=float(f.mean()), beyond=beyond,
                connect=float(a.mean()), connect_near=rate(~f), connect_far=rate(f),
                far_share_of_unconnected=float(f[~a].mean()) if (~a).any() else None)


if __name__ == "__main__":
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--species", nargs="+", default=None, help="default: every species whose model ships")
    p.add_argument("--n", type=int, default=48, help="free samples a species")
    p.add_argument("--trees", type=int, default=200, help="procedural trees a species")
    p.add_argument("--far", type=int, default=16, help="branches back beyond which a parent counts as far")
    p.add_argument("--seed", type=int, default=0); p.add_argument("--threads", type=int, default=None)
    p.add_argument("--model", default=None, help="a checkpoint (.pt) instead of the species' shipped model")
    p.add_argument("--key", default=None, help="the row's name (default the species'); with --model, one species")
    p.add_argument("--drop", nargs="+", default=None, metavar="KEY", help="remove these rows; runs nothing")
    p.add_argument("--out", default="results/reach.json")
    a = p.parse_args()
    if (a.model or a.key) and len(a.species or []) != 1: p.error("--model and --key go with one --species")
    if a.drop:
        out = Path(a.out)
        old = json.loads(out.read_text()) if out.is_file() else {"species": {}}
        if gone := [k for k in a.drop if k not in old["species"]]: p.error(f"{a.out} has no row {', '.join(gone)}")
        for k in a.drop: del old["species"][k]
        out.write_text(json.dumps(old, indent=1)); print("dropped", ", ".join(a.drop)); sys.exit(0)
    import torch
    from tqdm.auto import tqdm
    from treebook.botany import species, grow_tree
    from treebook.sampling import sample
    from treebook.species_runs import parent_gaps
    from treebook.train import load_pretrained, shipped_species, species_model
    if a.threads: torch.set_num_threads(a.threads)
    out = Path(a.out)
    rows = provenance.kept_rows(out, far=a.far, seed=a.seed)
    for name in a.species or shipped_species():
        model = a.model or species_model(name)
        net, tok = load_pretrained(model)
        cap = min(species(name).max_branches, net.config.max_len // 8 - 2)
        trees = [grow_tree(species(name), 10**6 + i, max_branches=cap) for i in tqdm(range(a.trees), desc=name)]
        proc = summary([parent_gaps(tok.encode(t), tok) for t in trees], a.far)
        t0 = time.time()
        seqs = sample(net, a.n, tok=tok, structure=False, min_len=24, seed=a.seed, progress=True)
        free = summary([parent_gaps(s, tok) for s in seqs], a.far) | {"samples": a.n, "seconds": time.time() - t0}
        key = a.key or name
        rows[key] = dict(window=net.config.window, max_branches=cap, procedural=proc | {"trees": a.trees}, free=free,
                         model=model, **provenance.stamp("benchmarks/reach.py"))
        print(key, json.dumps(rows[key]), flush=True)
        provenance.write_rows(out, rows, far=a.far, seed=a.seed, n=a.n, trees=a.trees)   # after each species
