#!/usr/bin/env bash
# Issue 15's learning-speed measure: how long a config takes to train a walking
# base from scratch. Trains CONFIG in segments (to FIRST iterations, then STEP
# more at a time, each segment resumed exactly from the last one's checkpoint,
# so the run is the same bit for bit as one that never stopped), evaluates each
# segment's checkpoint over 128 episodes (seed 0, scored as if the task ended
# there, under the default env's pushes whatever CONFIG trains with: a push of
# up to 1 m/s every 15 s) and prints a row per evaluation: iteration, the training's
# own wall-clock to it (metrics.jsonl's time/wall_s: evaluations, process starts
# and resume replays are not counted), fall rate, lin_vel_err, ang_vel_err,
# return. It stops at the first evaluation that meets fall <= FALL and
# lin_vel_err <= LIN (the issue's 0.05 and 0.25 m/s), or at MAX iterations.
#
#   scripts/time_to_walk.sh CONFIG OUT [FIRST=1000] [STEP=100] [MAX=3000]
#
# Environment: QUADCL (the binary; default target/release/quadcl, built if
# missing), FALL, LIN, EPISODES (128), EVAL_PUSH_INTERVAL_S (15) and
# EVAL_PUSH_MAX_VEL (1.0). OUT must not exist yet; it keeps
# every evaluated checkpoint under OUT/kept/ITERATION and the table in
# OUT/time_to_walk.tsv. A run of the base config takes 20-25 min on 2 cores.
set -euo pipefail

if [[ $# -lt 2 ]]; then
    sed -n '2,20p' "$0" | sed 's/^# \{0,1\}//'
    exit 2
fi
config=$1 out=$2 first=${3:-1000} step=${4:-100} max=${5:-3000}
fall=${FALL:-0.05} lin=${LIN:-0.25} episodes=${EPISODES:-128}
push_interval=${EVAL_PUSH_INTERVAL_S:-15} push_max_vel=${EVAL_PUSH_MAX_VEL:-1.0}
for n in "$first" "$step" "$max" "$episodes"; do
    [[ $n =~ ^[1-9][0-9]*$ ]] || { echo "time_to_walk: '$n' is not a positive whole number" >&2; exit 2; }
done
[[ -f $config ]] || { echo "time_to_walk: $config: no such config file" >&2; exit 2; }
[[ ! -e $out ]] || { echo "time_to_walk: $out exists; give a new folder" >&2; exit 2; }

root=$(cd "$(dirname "$0")/.." && pwd)
bin=${QUADCL:-$root/target/release/quadcl}
if [[ ! -x $bin ]]; then
    (cd "$root" && cargo build --release --quiet)
fi

# The segments need checkpoints; the end of each segment is always one, so any
# interval will do. A config that turns them off (0) gets the default, 25.
mkdir -p "$out/kept"
python3 - "$config" "$out/config.toml" <<'PY'
import re, sys
text = open(sys.argv[1]).read()
if re.search(r"^\s*checkpoint_every\s*=\s*0\s*$", text, re.M):
    text = re.sub(r"^\s*checkpoint_every\s*=\s*0\s*$", "checkpoint_every = 25", text, flags=re.M)
open(sys.argv[2], "w").write(text)
PY

printf 'iteration\twall_s\tfall_rate\tlin_vel_err\tang_vel_err\treturn\n' | tee "$out/time_to_walk.tsv"
target=$first
resume=()
while :; do
    "$bin" train --config "$out/config.toml" --out "$out/run" --iterations "$target" "${resume[@]}" \
        > "$out/train.log" 2>&1 || { tail -5 "$out/train.log" >&2; exit 1; }
    resume=(--resume)
    cp -r "$out/run/checkpoint" "$out/kept/$target"
    "$bin" eval --policy "$out/kept/$target" --task none --episodes "$episodes" \
        --push-interval-s "$push_interval" --push-max-vel "$push_max_vel" --json > "$out/kept/$target/eval.json"
    row=$(python3 - "$out/run/metrics.jsonl" "$target" "$out/kept/$target/eval.json" "$fall" "$lin" <<'PY'
import json, sys
rows = [json.loads(line) for line in open(sys.argv[1])]
it = int(sys.argv[2])
wall = rows[it - 1]["time/wall_s"]
e = json.load(open(sys.argv[3]))
met = e["fall_rate"] <= float(sys.argv[4]) and e["lin_vel_err"] <= float(sys.argv[5])
print(f"{it}\t{wall:.0f}\t{e['fall_rate']:.3f}\t{e['lin_vel_err']:.3f}\t{e['ang_vel_err']:.3f}\t{e['mean_return']:.1f}\t{'met' if met else ''}")
PY
)
    printf '%s\n' "$row" | tee -a "$out/time_to_walk.tsv"
    if [[ $row == *met ]]; then
        echo "time_to_walk: met at iteration $target after $(cut -f2 <<<"$row") s of training"
        exit 0
    fi
    if (( target >= max )); then
        echo "time_to_walk: not met by iteration $max"
        exit 1
    fi
    target=$(( target + step > max ? max : target + step ))
done
