"""TreePartNet's runs (chapters 09a, 09c), one subcommand each, their logic in chapter 09a1 (treebook.partnet_runs).
  train         train TreePartNet (resumable), evaluate it, write the weights, card, results/partnet_train*.json
  errors        where the affinity goes wrong on the held-out scans: results/partnet_errors.json
  pair-context  give trained weights a pair context, score it on new trees: results/partnet_context.json
  seed-cut      the junction cut of the seed layout, on training scans: results/partnet_seed_cut.json
  soup          the mean of runs' weights: python scripts/partnet.py soup OUT.pt RUN1.pt RUN2.pt [...]
  ablation      the merging ablation (paper Table 1), four trained networks: results/partnet_ablation.json
  results       the one file chapter 09a reads, from the runs' records: results/partnet.json [--at REV]
  pool-pack     pack|unpack|make scan pools, to train on a machine that cannot scan
  foliage       the wood/leaf network of chapter 09c: weights, card, results/foliage.json
Usage: python scripts/partnet.py SUBCOMMAND [ARGS]   (the flags of one: python scripts/partnet.py SUBCOMMAND -h)"""
import sys
from pathlib import Path

import provenance   # scripts/provenance.py, beside this script
sys.path.insert(0, str(provenance.ROOT))
from treebook.tree import TreebookError
from treebook import partnet_runs as runs

MAIN = {"train": runs.train_main, "errors": runs.errors_main, "pair-context": runs.pair_context_main,
        "seed-cut": runs.seed_cut_main, "ablation": runs.ablation_main, "results": runs.results_main,
        "foliage": runs.foliage_main}
SOUP_USAGE = "Usage: python scripts/partnet.py soup OUT.pt RUN1.pt RUN2.pt [...]"

if len(sys.argv) < 2 or sys.argv[1] not in (*MAIN, "soup", "pool-pack"): sys.exit(__doc__)
cmd, argv = sys.argv[1], sys.argv[2:]
try:
    if cmd == "soup":
        if len(argv) < 3: raise TreebookError(SOUP_USAGE)
        runs.soup(argv[0], argv[1:])
    elif cmd == "pool-pack": runs.pool_pack_main(argv)
    else: MAIN[cmd](argv, provenance.ROOT, " ".join(["python scripts/partnet.py", *sys.argv[1:]]), provenance.commit)
except TreebookError as e:
    sys.exit(str(e))
