#!/usr/bin/env bash
# Two processes on one run folder (issue 55): `quadcl run --resume` started twice on the same
# --out, N times started at the same moment and N times one second apart. Every try must end
# with exactly one refusal naming the lock's holder, one run that finished, a metrics.json
# whose evaluation matrix is the one an undisturbed run gives, and an emptied (released) lock.
#
#   scripts/lock_race.sh [QUADCL_BINARY] [N]      (default target/debug/quadcl, N = 20)
#
# The run is the toy learner over three tasks (a few seconds with its figures), so the second
# process starts while the first trains even one second later.
set -euo pipefail
cd "$(dirname "$0")/.."
bin=$(realpath "${1:-target/debug/quadcl}")
n=${2:-20}
[ -x "$bin" ] || { echo "no binary at $bin: cargo build first" >&2; exit 1; }
tmp=$(mktemp -d /tmp/quadcl-lock.XXXXXX)
trap 'rm -rf "$tmp"' EXIT
cat > "$tmp/run.toml" <<'RUN'
seed = 3
iterations = 6000
[run]
learner = "toy"
[eval]
episodes = 1
[[task]]
name = "crash:FL"
[[task]]
name = "invert:RR"
[[task]]
name = "noise:FR"
RUN
"$bin" run --config "$tmp/run.toml" --out "$tmp/alone" --no-tb > /dev/null 2>&1
matrix() { python3 -c 'import json, sys; print(json.dumps(json.load(open(sys.argv[1]))["eval_matrix"]))' "$1/metrics.json"; }
expected=$(matrix "$tmp/alone")
refusals=0
for apart in 0 1; do
  for i in $(seq "$n"); do
    out="$tmp/race-$apart-$i"
    "$bin" run --resume --config "$tmp/run.toml" --out "$out" --no-tb > "$tmp/a.out" 2> "$tmp/a.err" &
    a=$!
    sleep "$apart"
    "$bin" run --resume --config "$tmp/run.toml" --out "$out" --no-tb > "$tmp/b.out" 2> "$tmp/b.err" &
    b=$!
    rc_a=0; wait $a || rc_a=$?
    rc_b=0; wait $b || rc_b=$?
    failed=0
    for side in a b; do
      rc=$rc_a; [ $side = b ] && rc=$rc_b
      if [ "$rc" -ne 0 ]; then
        failed=$((failed + 1))
        grep -q "is in use by pid" "$tmp/$side.err" || { echo "try $apart/$i: $side failed otherwise:"; cat "$tmp/$side.err"; exit 1; }
      fi
    done
    if [ "$failed" -ne 1 ]; then
      echo "try $apart/$i: $failed refusals (rc $rc_a, $rc_b)"; cat "$tmp/a.err" "$tmp/b.err"; exit 1
    fi
    refusals=$((refusals + failed))
    [ "$(matrix "$out")" = "$expected" ] || { echo "try $apart/$i: the evaluation matrix differs from an undisturbed run's"; exit 1; }
    [ ! -s "$out/run.lock" ] || { echo "try $apart/$i: the lock was not released"; exit 1; }
    ls "$out/checkpoints" | grep -qv '\.new$\|\.old$' || { echo "try $apart/$i: no checkpoint"; exit 1; }
    ! ls "$out/checkpoints" | grep -q '\.new$\|\.old$' || { echo "try $apart/$i: a half-written checkpoint was left"; exit 1; }
  done
done
echo "lock race: $((2 * n)) tries (N together, N one second apart): $refusals refusals, every folder complete and identical to an undisturbed run's"
