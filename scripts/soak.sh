#!/usr/bin/env bash
# Soak: runs a long sequence and samples the process's resident memory and
# its iteration rate; memory after warm-up must stay flat (issue 16 item 8).
#
#   scripts/soak.sh [QUADCL_BINARY] [ITERATIONS] [TASKS] [run|train]
#
# run (default): the sequence is scenes/smoke.toml (tiny networks, 8 envs)
# cut to its first TASKS tasks (default 1) of ITERATIONS each (default
# 2,100), with 32 episodes of 2 s per evaluation.
# train: `quadcl train` of the same networks for ITERATIONS iterations with
# 20 s episodes and a checkpoint every 25 (each env keeps its episode's
# actions for an exact resume: memory rises until every env has run one
# whole episode, 63 iterations, and must stay flat from then on). Prints one line per sample (elapsed s,
# iterations done, RSS MB), then the RSS at 10 % of the iterations and at
# the end, the growth between them and the iterations per second; exits 1
# when the growth exceeds 5 % beyond what the results keep by design (the
# training curves of metrics.json, a few values per iteration: the script
# counts them). With several tasks, each task adds its own
# masks, biases, curves and evaluations, so memory rises by a step per task
# by design: the flatness check is meant for one long task.
set -euo pipefail
cd "$(dirname "$0")/.."
bin=${1:-target/release/quadcl}
per_task=${2:-2100}
tasks=${3:-1}
kind=${4:-run}
[ -x "$bin" ] || { echo "no binary at $bin: cargo build --release first" >&2; exit 1; }
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
sed -e "s/^iterations = 3$/iterations = $per_task/" -e 's/^episodes = 4$/episodes = 32/' scenes/smoke.toml |
  awk -v keep="$tasks" '/^\[\[task\]\]/ { n++ } n <= keep' > "$dir/soak.toml"
[ "$(grep -c '^\[\[task\]\]' "$dir/soak.toml")" -eq "$tasks" ] || { echo "the smoke sequence has fewer than $tasks tasks" >&2; exit 1; }
grep -q "^iterations = $per_task$" "$dir/soak.toml" || { echo "could not set the iterations" >&2; exit 1; }
total=$((tasks * per_task))
if [ "$kind" = train ]; then
  [ "$tasks" -eq 1 ] || { echo "train soaks one task" >&2; exit 1; }
  # The run's [env], [net] and [ppo] tables as a training config.
  awk '/^\[\[task\]\]|^\[method\]|^\[eval\]/ { skip = 1 } /^\[(env|net|ppo)/ { skip = 0 } !skip' "$dir/soak.toml" |
    grep -v '^iterations = \|^episode_s = ' | sed -e "s/^\[ppo\]$/[ppo]\niterations = $per_task\ncheckpoint_every = 25/" > "$dir/train.toml"
  "$bin" train --config "$dir/train.toml" --out "$dir/train" 2> "$dir/log" > /dev/null &
else
  "$bin" run --config "$dir/soak.toml" --out "$dir/run" 2> "$dir/log" > /dev/null &
fi
pid=$!
start=$(date +%s.%N)
samples="$dir/samples"
: > "$samples"
while kill -0 "$pid" 2>/dev/null; do
  rss=$(awk '/^VmRSS/ {print $2}' "/proc/$pid/status" 2>/dev/null || true)
  if [ "$kind" = train ]; then
    # Completed iterations: the rows of metrics.jsonl (one appended per iteration).
    its=0
    [ -f "$dir/train/metrics.jsonl" ] && its=$(wc -l < "$dir/train/metrics.jsonl")
  else
    # Completed iterations: finished tasks plus the running task's last echoed iteration.
    done_tasks=$(grep -c '"event":"task_ended"' "$dir/log" || true)
    last=$(grep -o 'iteration [0-9]*/' "$dir/log" | tail -1 | tr -dc '0-9' || true)
    its=$(( done_tasks * per_task + ${last:-0} ))
  fi
  [ "$its" -gt "$total" ] && its=$total
  if [ -n "$rss" ]; then
    now=$(date +%s.%N)
    awk -v a="$now" -v b="$start" -v i="$its" -v r="$rss" 'BEGIN { printf "%.0f %d %.1f\n", a - b, i, r / 1024 }' | tee -a "$samples"
  fi
  sleep 1
done
wait "$pid" || { echo "quadcl $kind failed:" >&2; tail -5 "$dir/log" >&2; exit 1; }
end=$(date +%s.%N)
# What the results keep per iteration by design (the run's training curves in metrics.json: a
# few values per iteration and masked layer), at 8 bytes a value and up to twice that for a
# growing vector's spare capacity: the growth this may explain.
kept_mb=0
if [ "$kind" = run ]; then
  kept_mb=$(python3 -c '
import json, sys
def count(v): return sum(count(x) for x in v.values()) if isinstance(v, dict) else sum(count(x) for x in v) if isinstance(v, list) else 1
curves = json.load(open(sys.argv[1]))["curves"]
print(sum(count({k: v for k, v in c.items() if isinstance(v, (list, dict))}) for c in curves) * 16 / 2**20)
' "$dir/run/metrics.json")
fi
awk -v total="$total" -v kept="$kept_mb" -v secs="$(awk -v a="$end" -v b="$start" 'BEGIN { print a - b }')" '
  { t[NR] = $1; it[NR] = $2; rss[NR] = $3 }
  END {
    for (i = 1; i <= NR; i++) if (it[i] >= total / 10) { w = i; break }
    if (!w) w = 1
    growth = 100 * (rss[NR] - rss[w]) / rss[w]
    unexplained = 100 * (rss[NR] - rss[w] - kept) / rss[w]
    printf "soak: %d iterations in %.0f s (%.1f it/s); RSS %.1f MB after warm-up (iteration %d), %.1f MB at the end: %+.1f %%",
      total, secs, total / secs, rss[w], it[w], rss[NR], growth
    if (kept > 0) printf "; the training curves kept as results explain up to %.2f MB: %+.1f %% beyond them", kept, unexplained
    printf "\n"
    exit (unexplained > 5) ? 1 : 0
  }' "$samples"
