#!/usr/bin/env bash
# Train runs side by side on one GPU; OUTDIR gets each run's weights without the optimiser's moments. Evaluate anywhere.
#
# Usage: scripts/gpu.sh conditions SECONDS OUTDIR "ARGS" ["ARGS" ...]
#   ARGS: scripts/train_conditions.py's arguments for one run, with --out and --tag, without --steps, --device,
#   --train-only or --time-limit. A short probe of all runs at once measures each one's seconds per step, then each
#   gets a cosine schedule that ends when SECONDS of wall time do. OUTDIR receives NAME.pt (model, step, seconds, meta;
#   NAME: the last part of --out), NAME.log.csv, its record results/conditions_..._TAG.json, and log.txt. Evaluate with
#   `train_conditions.py ... --eval-only` and the same --out. Makes data/elm when it is missing (the dataset's seed).
# Usage: scripts/gpu.sh partnet POOLS OUTDIR "ARGS" ["ARGS" ...]
#   POOLS: the train pool as scripts/partnet.py pool-pack packs it (several, comma-separated, make one pool). ARGS:
#   scripts/partnet.py train's arguments for one run, with --work and --minutes, without --device or --train-only
#   (a machine that cannot scan: no open3d). Each --work receives the unpacked pool; OUTDIR receives NAME.pt (NAME: the
#   last part of --work), the run's checkpoint, and NAME.log. To evaluate, put NAME.pt in its --work as checkpoint.pt
#   and run partnet.py train with the same ARGS, --device cuda, without --train-only: it scores on the CPU.
# Usage: scripts/gpu.sh species SECONDS OUTDIR NAME... [FLAGS]: a model per species, all side by side (chapter 05a).
# TREEBOOK_COMMIT: the commit being run (the copy there may carry a stale git history). DEVICE=cpu: without a GPU.
set -uo pipefail
cd "$(dirname "$0")/.."
kind=$1; arg=$2; dest=$3; shift 3; jobs=("$@"); dev=${DEVICE:-cuda}; rc=0
mkdir -p "$dest" tmp
[ "$kind" = species ] && export PYTHONPATH="$PWD${PYTHONPATH:+:$PYTHONPATH}" &&   # treebook.species_runs.gpu_runs
  exec python3 -m treebook.species_runs gpu "$arg" "$dest" "${jobs[@]}" --device "$dev"
flag() { local prev="" w; for w in $2; do [ "$prev" = "$1" ] && echo "$w"; prev=$w; done; }
run_all() {   # every job at once, each with the arguments "$1 JOB" prints; output to "$2 JOB"
  local pids=() job p
  for job in "${jobs[@]}"; do python scripts/$script $job $($1 "$job") >> "$($2 "$job")" 2>&1 & pids+=($!); done
  for p in "${pids[@]}"; do wait "$p" || rc=1; done
}
if [ "$kind" = partnet ]; then
  script="partnet.py train"; log_of() { echo "$dest/$(basename "$(flag --work "$1")").log"; }
  for job in "${jobs[@]}"; do w=$(flag --work "$job"); [ -n "$w" ] || { echo "no --work in: $job" >&2; exit 2; }
    python scripts/partnet.py pool-pack unpack "$arg" "$w" || exit 1; : > "$(log_of "$job")"; done
  train_args() { echo "--device $dev --train-only"; }; run_all train_args log_of
  for job in "${jobs[@]}"; do w=$(flag --work "$job"); n=$(basename "$w")
    python -c "import torch; b = torch.load('$w/checkpoint.pt', map_location='cpu', weights_only=False)
b['opt'] = dict(state={}, param_groups=b['opt']['param_groups'])   # loads as a fresh Adam: enough to evaluate
torch.save(b, '$dest/$n.pt')" || rc=1; tail -c 300 "$dest/$n.log"; echo; done; exit $rc
fi
[ "$kind" = conditions ] || { echo "usage: scripts/gpu.sh conditions|partnet|species ..." >&2; exit 2; }
set -e; script=train_conditions.py; log="$dest/log.txt"; : > "$log"; log_of() { echo "$log"; }
start=$(date +%s); touch tmp/gpu-start
[ -f data/elm/manifest.json ] || python -c "from treebook.datasets import generate_dataset; generate_dataset('elm', 10000, 'data/elm', max_branches=200, workers=$(nproc), seed=0)" >> "$log" 2>&1
echo "data ready after $(( $(date +%s) - start )) s" >> "$log"
probe_args() { echo "--out tmp/probe-$(basename "$(flag --out "$1")") --device $dev --steps 75 --train-only"; }
run_all probe_args log_of; [ $rc = 0 ] || exit $rc
left=$(( arg - ($(date +%s) - start) - 40 ))
main_args() {
  local n; n=$(basename "$(flag --out "$1")")
  local pace; pace=$(python -c "import csv; r=list(csv.DictReader(open('tmp/probe-$n/log.csv'))); print((float(r[-1]['seconds'])-float(r[0]['seconds']))/(int(r[-1]['step'])-int(r[0]['step'])))")
  echo "$n: $pace s a step with all jobs running: $(python -c "print(int($left / $pace * 0.95))") steps in $left s" >&2
  echo "--device $dev --steps $(python -c "print(int($left / $pace * 0.95))") --time-limit $left --train-only"
}
run_all main_args log_of 2>> "$log"; [ $rc = 0 ] || exit $rc
for job in "${jobs[@]}"; do o=$(flag --out "$job"); n=$(basename "$o")
  python -c "import torch; c=torch.load('$o/last.pt', map_location='cpu', weights_only=True); c.pop('opt'); torch.save(c, '$dest/$n.pt')"
  cp "$o/log.csv" "$dest/$n.log.csv"
done
find results -name 'conditions_*.json' -newer tmp/gpu-start -exec cp {} "$dest/" \;
echo "done after $(( $(date +%s) - start )) s" >> "$log"
