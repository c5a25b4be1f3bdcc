#!/usr/bin/env bash
# Are two quadcl binaries' simulations the same, bit for bit? (issue 33, stage 1)
#
#   scripts/same_physics.sh REFERENCE_BINARY NEW_BINARY [ITERATIONS]
#
# Both binaries, in turn, in temporary folders:
# 1. train ITERATIONS (default 3) iterations of scenes/train-base.toml from scratch (seed 1, no
#    TensorBoard): every checkpoint file (the model and optimiser tensors, the training state)
#    must be the same bytes;
# 2. hold the shipped base's gait for 20 s (quadcl gait --json, three commands): the same report;
# 3. evaluate the shipped paper run's last checkpoint on crash:FL and invert:RL (16 episodes, --json): the same
#    figures.
# Timing fields (wall-clock, steps per second) and the commit the binary was built from are
# dropped before comparing. Prints what
# differs, exits 1 if anything does.
set -euo pipefail
cd "$(dirname "$0")/.."
[ $# -ge 2 ] || { echo "usage: scripts/same_physics.sh REFERENCE_BINARY NEW_BINARY [ITERATIONS]" >&2; exit 2; }
ref=$(realpath "$1")
new=$(realpath "$2")
iterations=${3:-3}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

strip_timing() {
  python3 -c '
import json, sys
def strip(v):
    if isinstance(v, dict):
        return {k: strip(x) for k, x in v.items()
                if not any(t in k for t in ("wall", "per_s", "elapsed", "_ms", "SPS", "time/", "time_", "git_dirty", "git_commit"))}
    if isinstance(v, list):
        return [strip(x) for x in v]
    return v
for line in sys.stdin:
    line = line.strip()
    if line.startswith("{"):
        print(json.dumps(strip(json.loads(line)), sort_keys=True))
'
}

for side in ref new; do
  bin=$ref; [ "$side" = new ] && bin=$new
  mkdir -p "$work/$side"
  "$bin" train --config scenes/train-base.toml --out "$work/$side/train" --iterations "$iterations" --seed 1 --no-tb \
    > "$work/$side/train.log" 2>&1
  for cmd in "--vx 0.5 --wz 0" "--vx 1.0 --wz 0" "--vx 0.3 --wz 0.8"; do
    # shellcheck disable=SC2086
    "$bin" gait --policy policies/base-a1-flat-ranked $cmd --seconds 20 --json | strip_timing >> "$work/$side/gait.json"
  done
  for task in crash:FL invert:RL; do
    "$bin" eval --policy policies/sequence-a1-paper/checkpoints/step-03-crash_FR --task "$task" --episodes 16 --json | strip_timing >> "$work/$side/eval.json"
  done
done

status=0
checked=0
while IFS= read -r -d '' file; do
  rel=${file#"$work/ref/train/"}
  case "$rel" in
    *.txt|*.log|*.toml|*.md|*.csv|tb/*) continue ;;
    *.json|*.jsonl)  # figures and provenance, with the clock's fields dropped
      same() { cmp -s <(tr -d '\n' < "$file" | sed 's/}{/}\n{/g; s/^/\n/' | strip_timing) \
                      <(tr -d '\n' < "$work/new/train/$rel" | sed 's/}{/}\n{/g; s/^/\n/' | strip_timing); } ;;
    *) same() { cmp -s "$file" "$work/new/train/$rel"; } ;;
  esac
  checked=$((checked + 1))
  if ! same; then
    echo "differs: train/$rel"
    status=1
  fi
done < <(find "$work/ref/train" -type f -print0)
for f in gait.json eval.json; do
  if ! cmp -s "$work/ref/$f" "$work/new/$f"; then
    echo "differs: $f"
    diff <(tr ',' '\n' < "$work/ref/$f") <(tr ',' '\n' < "$work/new/$f") | head -20
    status=1
  fi
done
if [ "$status" -eq 0 ]; then
  echo "same: $checked files of the training run (tensors and training state byte for byte, JSON without its timing fields) after $iterations iterations, 3 gaits of 20 s, 2 evaluations of 16 episodes"
fi
exit "$status"
