"""Evaluate a trained run on the held-out split of its dataset and ship it: weights, tokenizer and model card.

Usage: python scripts/ship_elm.py [--species elm] [--run runs/NAME] [--data data/NAME] [--n-samples 1000] [--no-ship]
Writes results/NAME_eval.json (command, commit, machine, metrics: metrics.sample_scores) and, unless --no-ship,
treebook/data/weights/NAME.{pt,tok.json,md} (the card: species_runs.species_card) and results/NAME_loss.png. NAME is
the species (default elm: `make elm`; the others: `make species SPECIES=NAME`). The logic is chapter 05a's
(treebook.species_runs.ship_main); `--help` lists every flag.
"""
import sys
import provenance   # scripts/provenance.py, beside this script
from treebook.species_runs import ship_main
from treebook.tree import TreebookError

if __name__ == "__main__":
    try: ship_main(record=lambda res, out, **machine: provenance.record("scripts/ship_elm.py", res, out, **machine),
                   results=provenance.ROOT / "results")
    except TreebookError as e: print(f"ship_elm.py: error: {e}", file=sys.stderr); sys.exit(2)
