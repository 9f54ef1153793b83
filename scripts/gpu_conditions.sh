#!/usr/bin/env bash
# Train conditional models side by side on one GPU for about SECONDS of wall time, each with a cosine schedule that ends
# when the time does: a short probe of all jobs at once measures each one's seconds per step first. Writes training
# records only; evaluate afterwards on any machine with `train_conditions.py ... --eval-only` and the same --out.
#
# Usage: scripts/gpu_conditions.sh SECONDS OUTDIR "JOB ARGS" ["JOB ARGS" ...]
#   JOB ARGS: the arguments of scripts/train_conditions.py for one run, with --out and --tag, without --steps, --device,
#   --train-only or --time-limit. OUTDIR receives for each run NAME.pt (model, step, seconds, meta; no optimiser state),
#   NAME.log.csv and its training record results/conditions_..._TAG.json (NAME: the last part of --out), and log.txt.
# Set TREEBOOK_COMMIT to the commit being run: the copy of the tree there may carry a stale git history.
# DEVICE=cpu tries the script on a machine without one.
# Makes data/elm when it is missing, from the dataset's own seed: the same trees as everywhere else.
set -euo pipefail
cd "$(dirname "$0")/.."
budget=$1; dest=$2; shift 2
mkdir -p "$dest" tmp; log="$dest/log.txt"; : > "$log"
start=$(date +%s); touch tmp/gpu-start
[ -f data/elm/manifest.json ] || python -c "from treebook.datasets import generate_dataset; generate_dataset('elm', 10000, 'data/elm', max_branches=200, workers=$(nproc), seed=0)" >> "$log" 2>&1
echo "data ready after $(( $(date +%s) - start )) s" >> "$log"
out_of() { local prev=""; for w in $1; do [ "$prev" = "--out" ] && echo "$w"; prev=$w; done; }
run_all() {   # run_all EXTRA_ARGS_FUNCTION: every job at once, each with the arguments the function prints for it
  local pids=() job
  for job in "${jobs[@]}"; do python scripts/train_conditions.py $job $("$1" "$job") >> "$log" 2>&1 & pids+=($!); done
  for p in "${pids[@]}"; do wait "$p"; done
}
jobs=("$@")
probe_args() { echo "--out tmp/probe-$(basename "$(out_of "$1")") --device ${DEVICE:-cuda} --steps 75 --train-only"; }
run_all probe_args
left=$(( budget - ($(date +%s) - start) - 40 ))
main_args() {
  local n; n=$(basename "$(out_of "$1")")
  local pace; pace=$(python -c "import csv; r=list(csv.DictReader(open('tmp/probe-$n/log.csv'))); print((float(r[-1]['seconds'])-float(r[0]['seconds']))/(int(r[-1]['step'])-int(r[0]['step'])))")
  echo "$n: $pace s a step with all jobs running: $(python -c "print(int($left / $pace * 0.95))") steps in $left s" >&2
  echo "--device ${DEVICE:-cuda} --steps $(python -c "print(int($left / $pace * 0.95))") --time-limit $left --train-only"
}
run_all main_args 2>> "$log"
for job in "${jobs[@]}"; do o=$(out_of "$job"); n=$(basename "$o")
  python -c "import torch; c=torch.load('$o/last.pt', map_location='cpu', weights_only=True); c.pop('opt'); torch.save(c, '$dest/$n.pt')"
  cp "$o/log.csv" "$dest/$n.log.csv"
done
find results -name 'conditions_*.json' -newer tmp/gpu-start -exec cp {} "$dest/" \;
echo "done after $(( $(date +%s) - start )) s" >> "$log"
