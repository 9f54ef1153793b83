"""Structure-aware decoding against drawing freely and snapping loose starts (`structure="snap"`), on the figures of
the distribution: each shipped species' samples both ways against the same procedural trees (chapter 05a).

For each species (default: every one whose model ships): --n samples each way (seed 0), and 2 x --n procedural trees
grown afresh (seeds from 2,000,000 and 3,000,000, none of them a seed of the datasets' trees: checked in 05a). The
first --n are the reference, the other --n are scored against them as the data's own figures. MMD-CD, COV-CD, 1-NNA,
JSD and FPD of each against the reference, and `long_share`. Writes results/decoding.json, keeping rows this call
does not run.

    .venv/bin/python benchmarks/decoding.py --species spruce            # 200 a way: some minutes a species
    .venv/bin/python benchmarks/decoding.py --species elm --n 4 --out tmp/decoding.json   # a check
"""
import argparse, json, sys, time
from pathlib import Path
sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "scripts"))
import provenance   # scripts/provenance.py

if __name__ == "__main__":
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--species", nargs="+", default=None, help="default: every species whose model ships")
    p.add_argument("--n", type=int, default=200, help="samples each way, and reference trees")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--out", default="results/decoding.json")
    a = p.parse_args()
    import numpy as np
    from tqdm.auto import tqdm
    from treebook.botany import species, grow_tree
    from treebook.metrics import evaluate, fpd, load_species_pointnet, tree_clouds
    from treebook.species_runs import long_share
    from treebook.train import load_pretrained, sample_trees, shipped_species, species_model
    out, settings = Path(a.out), dict(n=a.n, seed=a.seed)
    rows = provenance.kept_rows(out, **settings)
    pn = load_species_pointnet()
    for name in a.species or shipped_species():
        net, tok = load_pretrained(species_model(name))
        cap = min(species(name).max_branches, net.config.max_len // 8 - 2)
        ref = [grow_tree(species(name), 2 * 10**6 + i, max_branches=cap) for i in tqdm(range(a.n), desc="reference")]
        own = [grow_tree(species(name), 3 * 10**6 + i, max_branches=cap) for i in tqdm(range(a.n), desc="procedural")]
        R = tree_clouds(ref, seed=2, progress=False)
        row = {}
        for way, trees in (("procedural", own),
                           ("structure", sample_trees(a.n, model=(net, tok), seed=a.seed, progress=True)),
                           ("snap", sample_trees(a.n, model=(net, tok), seed=a.seed, structure="snap",
                                                 progress=True))):
            t0 = time.time()
            G = tree_clouds(trees, seed=1, progress=False)
            s = evaluate(G, R) | {"FPD": fpd(G, R, pn)}
            row[way] = {k: s[k] for k in ("MMD-CD", "COV-CD", "1-NNA", "JSD", "FPD")} | {
                "long": long_share(trees, ref), "branches_mean": float(np.mean([t.n for t in trees])),
                "seconds_metrics": time.time() - t0}
        rows[name] = row | {"window": net.config.window, "max_branches": cap,
                            **provenance.stamp("benchmarks/decoding.py")}
        print(name, json.dumps({w: {k: round(v, 4) for k, v in row[w].items() if isinstance(v, float)} for w in row}),
              flush=True)
        provenance.write_rows(out, rows, **settings)   # after each species
