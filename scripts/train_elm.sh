#!/usr/bin/env bash
# The shipped `elm` model: data, training (resumable), then the model card's evaluation and the copy into the package.
# Usage: bash scripts/train_elm.sh            (run again to resume after a kill: the data and training steps pick up where they stopped)
set -euo pipefail
cd "$(dirname "$0")/.."
PY=${PY:-.venv/bin/python}
# 1. 10,000 procedural elms (<= 200 branches), 9,000 train / 1,000 test by the dataset's split; resumable.
$PY -c "from treebook.datasets import generate_dataset; generate_dataset('elm', 10000, 'data/elm', max_branches=200, workers=2, seed=0)"
# 2. Train DFS / Full. dim 128, 8 layers, 4 heads (1.6 M parameters), batch 8, 330 steps: what two shared CPU cores manage in ~100 minutes.
RESUME=""; [ -f runs/elm/last.pt ] && RESUME="--resume"
$PY -m treebook.train --data data/elm --out runs/elm --order dfs --arch full --dim 128 --depth 8 --heads 4 \
    --batch-size 8 --steps 330 --lr 2e-3 --warmup 30 --val-every 66 --val-trees 128 --ckpt-every 10 --threads 2 --seed 0 $RESUME
# 3. Evaluate best.pt on the held-out 1,000 and write the model card + weights into the package.
$PY scripts/ship_elm.py --run runs/elm --data data/elm
