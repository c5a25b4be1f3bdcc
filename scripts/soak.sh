#!/usr/bin/env bash
# Soak: runs a long sequence and samples the process's resident memory and
# its iteration rate; memory after warm-up must stay flat (issue 16 item 8).
#
#   scripts/soak.sh [QUADCL_BINARY] [ITERATIONS] [TASKS]
#
# The sequence is scenes/smoke.toml (tiny networks, 8 envs) cut to its first
# TASKS tasks (default 1) of ITERATIONS each (default 2,100), with 32
# episodes of 2 s per evaluation. Prints one line per sample (elapsed s,
# iterations done, RSS MB), then the RSS at 10 % of the iterations and at
# the end, the growth between them and the iterations per second; exits 1
# when the growth exceeds 5 %. With several tasks, each task adds its own
# masks, biases, curves and evaluations, so memory rises by a step per task
# by design: the flatness check is meant for one long task.
set -euo pipefail
cd "$(dirname "$0")/.."
bin=${1:-target/release/quadcl}
per_task=${2:-2100}
tasks=${3:-1}
[ -x "$bin" ] || { echo "no binary at $bin: cargo build --release first" >&2; exit 1; }
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
sed -e "s/^iterations = 3$/iterations = $per_task/" -e 's/^episodes = 4$/episodes = 32/' scenes/smoke.toml |
  awk -v keep="$tasks" '/^\[\[task\]\]/ { n++ } n <= keep' > "$dir/soak.toml"
[ "$(grep -c '^\[\[task\]\]' "$dir/soak.toml")" -eq "$tasks" ] || { echo "the smoke sequence has fewer than $tasks tasks" >&2; exit 1; }
grep -q "^iterations = $per_task$" "$dir/soak.toml" || { echo "could not set the iterations" >&2; exit 1; }
total=$((tasks * per_task))
"$bin" run --config "$dir/soak.toml" --out "$dir/run" 2> "$dir/log" > /dev/null &
pid=$!
start=$(date +%s.%N)
samples="$dir/samples"
: > "$samples"
while kill -0 "$pid" 2>/dev/null; do
  rss=$(awk '/^VmRSS/ {print $2}' "/proc/$pid/status" 2>/dev/null || true)
  # Completed iterations: finished tasks plus the running task's last echoed iteration.
  done_tasks=$(grep -c '"event":"task_ended"' "$dir/log" || true)
  last=$(grep -o 'iteration [0-9]*/' "$dir/log" | tail -1 | tr -dc '0-9' || true)
  its=$(( done_tasks * per_task + ${last:-0} ))
  [ "$its" -gt "$total" ] && its=$total
  if [ -n "$rss" ]; then
    now=$(date +%s.%N)
    awk -v a="$now" -v b="$start" -v i="$its" -v r="$rss" 'BEGIN { printf "%.0f %d %.1f\n", a - b, i, r / 1024 }' | tee -a "$samples"
  fi
  sleep 1
done
wait "$pid" || { echo "quadcl run failed:" >&2; tail -5 "$dir/log" >&2; exit 1; }
end=$(date +%s.%N)
awk -v total="$total" -v secs="$(awk -v a="$end" -v b="$start" 'BEGIN { print a - b }')" '
  { t[NR] = $1; it[NR] = $2; rss[NR] = $3 }
  END {
    for (i = 1; i <= NR; i++) if (it[i] >= total / 10) { w = i; break }
    if (!w) w = 1
    growth = 100 * (rss[NR] - rss[w]) / rss[w]
    printf "soak: %d iterations in %.0f s (%.1f it/s); RSS %.1f MB after warm-up (iteration %d), %.1f MB at the end: %+.1f %%\n",
      total, secs, total / secs, rss[w], it[w], rss[NR], growth
    exit (growth > 5) ? 1 : 0
  }' "$samples"
