#!/usr/bin/env bash
# The shipped `elm` model: data, training (resumable), then the model card's evaluation and the copy into the package.
# Usage: bash scripts/train_elm.sh            (run again to resume after a kill: the data and training steps pick up where they stopped)
set -euo pipefail
cd "$(dirname "$0")/.."
PY=${PY:-.venv/bin/python}
# 1. 10,000 procedural elms (<= 200 branches), 9,000 train / 1,000 test by the dataset's split; resumable.
$PY -c "from treebook.datasets import generate_dataset; generate_dataset('elm', 10000, 'data/elm', max_branches=200, workers=2, seed=0)"
# 2. Train DFS / Full. dim 128, 8 layers, 4 heads (1.6 M parameters), batch 16, a 4,000-step schedule; each call stops after
#    100 minutes (--time-limit 6000): run the script again to resume where it stopped.
RUN=${RUN:-runs/elm2}
RESUME=""; [ -f $RUN/last.pt ] && RESUME="--resume"
$PY -m treebook.train --data data/elm --out $RUN --order dfs --arch full --dim 128 --depth 8 --heads 4 \
    --batch-size 16 --steps 4000 --lr 2e-3 --warmup 100 --val-every 500 --val-trees 128 --ckpt-every 50 --time-limit 6000 \
    --threads 2 --seed 0 --quiet $RESUME
# 3. Evaluate best.pt on the held-out 1,000 and write the model card + weights into the package.
$PY scripts/ship_elm.py --run $RUN --data data/elm --temperature 1.0 --top-p 1.0
