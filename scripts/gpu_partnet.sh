#!/usr/bin/env bash
# Train TreePartNet runs side by side on one GPU (a machine that cannot scan: no open3d), each to its own --minutes.
#
# Usage: scripts/gpu_partnet.sh POOLS OUTDIR "ARGS" ["ARGS" ...]
#   POOLS: the train pool as scripts/pool_pack.py packs it (several, comma-separated, make one pool). ARGS: scripts/train_partnet.py's arguments for one run, with
#   --work and --minutes, without --device or --train-only. Each run's --work receives the unpacked pool; OUTDIR receives
#   NAME.pt (NAME: the last part of --work), the run's checkpoint with the optimiser's moments left out, and NAME.log.
#   To evaluate a run on any machine, put NAME.pt in its --work as checkpoint.pt and give train_partnet.py the same ARGS
#   with --device cuda and without --train-only: the time is spent, so it trains no further and scores on the CPU.
# Set TREEBOOK_COMMIT to the commit being run (the copy of the tree there carries no git history).
# DEVICE=cpu tries the script on a machine without one.
set -uo pipefail
cd "$(dirname "$0")/.."
pools=$1; dest=$2; shift 2
mkdir -p "$dest"
work_of() { local prev="" w; for w in $1; do [ "$prev" = "--work" ] && echo "$w"; prev=$w; done; }
pids=()
for job in "$@"; do
  w=$(work_of "$job"); [ -n "$w" ] || { echo "no --work in: $job" >&2; exit 2; }
  python scripts/pool_pack.py unpack "$pools" "$w" || exit 1
  python scripts/train_partnet.py $job --device "${DEVICE:-cuda}" --train-only > "$dest/$(basename "$w").log" 2>&1 & pids+=($!)
done
rc=0
for p in "${pids[@]}"; do wait "$p" || rc=1; done
for job in "$@"; do
  w=$(work_of "$job")
  python -c "import torch; b = torch.load('$w/checkpoint.pt', map_location='cpu', weights_only=False)
b['opt'] = dict(state={}, param_groups=b['opt']['param_groups'])   # loads as a fresh Adam: enough to evaluate
torch.save(b, '$dest/$(basename "$w").pt')" || rc=1
  tail -c 300 "$dest/$(basename "$w").log"; echo
done
exit $rc
