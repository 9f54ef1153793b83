"""How long the six species' datasets take to grow: CPU seconds per tree of `generate_dataset` (one worker, in this
process, so that the CPU time is the process's own), trees of each species up to its preset's max_branches, and the
estimate for N trees a species on W workers (no more than the cores). Writes results/species_data.json.

    nice -n 19 .venv/bin/python benchmarks/species_data.py                 # 60 trees a species, about a minute
    .venv/bin/python benchmarks/species_data.py --trees 6 --out tmp/x.json  # a check of the script
"""
import argparse, json, os, shutil, sys, tempfile, time
from pathlib import Path
sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "scripts"))
import provenance   # scripts/provenance.py

if __name__ == "__main__":
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--trees", type=int, default=60); p.add_argument("--estimate", type=int, default=10_000)
    p.add_argument("--workers", type=int, default=16); p.add_argument("--out", default="results/species_data.json")
    a = p.parse_args()
    from treebook.botany import SPECIES
    from treebook.datasets import generate_dataset
    rows, tmp = {}, Path(tempfile.mkdtemp())
    for name, sp in SPECIES.items():
        c0, t0 = time.process_time(), time.perf_counter()
        m = generate_dataset(name, a.trees, tmp / name, workers=1, seed=0, shard_size=a.trees, progress=False)
        cpu, wall = time.process_time() - c0, time.perf_counter() - t0
        size = sum(f.stat().st_size for f in (tmp / name).iterdir())
        rows[name] = dict(max_branches=sp.max_branches, branches_mean=m["counts"]["branches"] / a.trees,
                          cpu_s_per_tree=cpu / a.trees, wall_s_per_tree=wall / a.trees, bytes_per_tree=size / a.trees)
        print(name, {k: round(v, 4) for k, v in rows[name].items()}, flush=True)
    shutil.rmtree(tmp)
    total = sum(r["cpu_s_per_tree"] for r in rows.values()) * a.estimate
    est = dict(trees_per_species=a.estimate, workers=a.workers, cpu_s=total, wall_s=total / a.workers,
               bytes=sum(r["bytes_per_tree"] for r in rows.values()) * a.estimate)
    print(f"{a.estimate:,} trees of each species: {total:.0f} CPU s, {total / a.workers / 60:.1f} minutes on "
          f"{a.workers} workers, {est['bytes'] / 2**20:.0f} MiB")
    provenance.record("benchmarks/species_data.py", {"trees": a.trees, "species": rows, "estimate": est}, a.out,
                      loadavg=os.getloadavg())
