#!/usr/bin/env bash
# Kill and resume: `quadcl run` and `quadcl train` are killed with SIGKILL at
# random points and continued with --resume (killed again, at another random
# point, in about half of the tries), and the results must be byte-identical
# to a run that never stopped, timing fields aside (issue 16):
# - run: metrics.json and every checkpoint (log.txt, which has wall times, is not compared);
# - train: policy/ and checkpoint/ byte for byte (checkpoint/trainer.json
#   without its wall_s), and metrics.jsonl without its time/* and charts/SPS fields.
#
#   scripts/kill_resume.sh [QUADCL_BINARY] [TRIES] [SEED]
#
# TRIES tries of each command. The run is scenes/smoke.toml with 40
# iterations per task, the training the same networks for 150 iterations with
# a checkpoint every 5 (a few seconds each).
set -euo pipefail
cd "$(dirname "$0")/.."
bin=${1:-target/release/quadcl}
tries=${2:-4}
RANDOM=${3:-1}
[ -x "$bin" ] || { echo "no binary at $bin: cargo build --release first" >&2; exit 1; }
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
sed -e 's/^iterations = 3$/iterations = 40/' scenes/smoke.toml > "$dir/run.toml"
# The smoke networks as one task's training (short episodes and frequent pushes:
# kills fall mid-episode, after resets and after the envs' own pushes).
cat > "$dir/train.toml" <<'TOML'
seed = 5
[env]
episode_s = 1.0
push_interval_s = 0.4
[net.actor]
hidden = [64, 32]
[net.critic]
hidden = [64, 32]
[net.cenet]
hidden = [32]
[ppo]
num_envs = 8
steps_per_env = 16
minibatches = 2
epochs = 2
iterations = 150
checkpoint_every = 5
cenet_decoder_hidden = [32]
cenet_latent_dim = 4
TOML

# start_KIND OUT FLAG: the command (exec: run in the background, its pid is quadcl's, so the
# kill reaches quadcl itself); resumable_KIND OUT: the flag to go on with; same_KIND A B.
start_run() { exec "$bin" run --config "$dir/run.toml" --out "$1" $2; }
# A kill before anything was written leaves nothing to resume: start again.
resumable_run() { if [ -f "$1/run.toml" ]; then echo --resume; fi; }
same_run() {
  cmp -s "$1/metrics.json" "$2/metrics.json" && diff -r -q "$1/checkpoints" "$2/checkpoints" > /dev/null
}
start_train() { exec "$bin" train --config "$dir/train.toml" --out "$1" $2; }
# Before the first checkpoint there is nothing to resume, but what was written must be replaced.
resumable_train() { if [ -d "$1/checkpoint" ]; then echo --resume; elif [ -e "$1" ]; then echo --force; fi; }
untimed() { # metrics.jsonl or trainer.json without what measures time
  python3 -c '
import json, sys
for line in open(sys.argv[1]).read().splitlines() if sys.argv[1].endswith(".jsonl") else [open(sys.argv[1]).read()]:
    row = json.loads(line)
    print(json.dumps({k: v for k, v in row.items() if not k.startswith("time/") and k not in ("charts/SPS", "wall_s")}, sort_keys=True))
' "$1"
}
same_train() {
  local f x y
  diff -r -q -x trainer.json "$1/policy" "$2/policy" > /dev/null || return 1
  diff -r -q -x trainer.json "$1/checkpoint" "$2/checkpoint" > /dev/null || return 1
  for f in checkpoint/trainer.json metrics.jsonl; do
    x=$(untimed "$1/$f") && y=$(untimed "$2/$f") || return 1
    [ -n "$x" ] && [ "$x" = "$y" ] || return 1
  done
}

failed=0
for kind in run train; do
  start=$(date +%s.%N)
  ("start_$kind" "$dir/$kind-reference" "") > /dev/null 2>&1
  full=$(awk -v a="$(date +%s.%N)" -v b="$start" 'BEGIN { printf "%.3f", a - b }')
  echo "$kind: uninterrupted: ${full} s"
  for try in $(seq 1 "$tries"); do
    out="$dir/$kind-try-$try"
    kills=0
    flag=""
    while true; do
      "start_$kind" "$out" "$flag" > /dev/null 2> "$dir/stderr" &
      pid=$!
      # A random point within the first 90 % of the uninterrupted time.
      delay=$(awk -v r="$RANDOM" -v f="$full" 'BEGIN { printf "%.3f", r / 32767 * f * 0.9 }')
      if [ "$kills" -lt 2 ] && { [ "$kills" -eq 0 ] || [ $((RANDOM % 2)) -eq 0 ]; }; then
        sleep "$delay"
        if kill -9 "$pid" 2>/dev/null; then
          wait "$pid" 2>/dev/null || true
          kills=$((kills + 1))
          echo "$kind try $try: killed after ${delay} s"
          flag=$("resumable_$kind" "$out")
          continue
        fi
      fi
      wait "$pid" || { echo "$kind try $try: quadcl $kind $flag failed:"; tail -3 "$dir/stderr"; failed=1; break; }
      break
    done
    if "same_$kind" "$dir/$kind-reference" "$out"; then
      echo "$kind try $try: $kills kill(s), resumed results byte-identical"
    else
      echo "$kind try $try: $kills kill(s), results DIFFER from the uninterrupted $kind"
      failed=1
    fi
  done
done
exit "$failed"
