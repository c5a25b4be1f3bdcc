#!/usr/bin/env bash
# Opens the real workbench binary in tmux (120x40) on a copy of
# scenes/smoke.toml with longer tasks, and checks the pane's text at each
# stage: the first screen, the help overlay, the cursor, starting a step,
# pausing it, resuming, quitting (with the question asked while training),
# and that the run folder holds the results afterwards. Then the Sweep screen
# (`quadcl tui --sweep`) on a finished 2 x 2 smoke sweep (scenes/sweep-smoke.toml):
# its cells and collected table, a cell's run opened in the workbench, and back.
#   scripts/tui_smoke.sh [BIN]      (default: builds and uses target/debug/quadcl)
set -euo pipefail
cd "$(dirname "$0")/.."
BIN=${1:-}
if [ -z "$BIN" ]; then
  cargo build --quiet --bin quadcl
  BIN=target/debug/quadcl
fi
command -v tmux >/dev/null || { echo "tui_smoke: tmux is not installed" >&2; exit 1; }

TMP=$(mktemp -d)
SESSION="quadcl-smoke-$$"
SWEEP_SESSION="quadcl-smoke-sweep-$$"
cleanup() {
  tmux kill-session -t "$SESSION" 2>/dev/null || true
  tmux kill-session -t "$SWEEP_SESSION" 2>/dev/null || true
  rm -rf "$TMP"
}
trap cleanup EXIT
sed 's/^iterations = 3$/iterations = 400/' scenes/smoke.toml > "$TMP/smoke.toml"

pane() { tmux capture-pane -p -t "$SESSION" 2>/dev/null || true; }
# wait_exit FILE: until the command in the session wrote its exit status there; it must be 0.
wait_exit() {
  local deadline=$((SECONDS + 60))
  until [ -f "$1" ]; do
    [ $SECONDS -lt $deadline ] || { echo "tui_smoke: FAILED: the workbench did not exit" >&2; pane >&2; exit 1; }
    sleep 0.2
  done
  grep -q "exited 0" "$1" || { echo "tui_smoke: FAILED: $(cat "$1")" >&2; cat "$TMP/stderr" >&2; exit 1; }
}
# wait_screen shows|lacks TEXT STAGE [SECONDS]: until the pane shows (or no longer shows)
# TEXT, a grep -E pattern; fails with the pane printed after SECONDS (default 60).
wait_screen() {
  local want=$1 pattern=$2 stage=$3 deadline=$((SECONDS + ${4:-60}))
  while true; do
    if pane | grep -Eq -- "$pattern"; then [ "$want" = shows ] && break; else [ "$want" = lacks ] && break; fi
    if [ $SECONDS -ge $deadline ]; then
      echo "tui_smoke: FAILED at '$stage': the screen $([ "$want" = shows ] && echo lacks || echo still shows) '$pattern':" >&2
      pane >&2
      exit 1
    fi
    sleep 0.2
  done
  echo "tui_smoke: ok: $stage"
}
wait_for() { wait_screen shows "$@"; }
wait_gone() { wait_screen lacks "$1" "$2" 30; }

tmux new-session -d -s "$SESSION" -x 120 -y 40 "$BIN tui --run $TMP/run --config $TMP/smoke.toml 2>$TMP/stderr; echo exited \$? > $TMP/exit; sleep 30"
wait_for "Sequence" "the first screen"
wait_for "› 0 crash:FL +new +pending" "the timeline with the cursor on step 0"
wait_for "Masks: crash:FL" "the masks of the selected task"
wait_for "Curves: performance" "the curves panel"
tmux send-keys -t "$SESSION" '?'
wait_for "this help" "the help overlay opens"
tmux send-keys -t "$SESSION" Escape
wait_gone "this help" "the help overlay closes"
tmux send-keys -t "$SESSION" Down
wait_for "› 1 invert:RR" "the cursor moves"
tmux send-keys -t "$SESSION" ' '
wait_for "training step 0 crash:FL" "the first step trains"
wait_for "▶ +[0-9]+%" "the timeline shows its progress"
tmux send-keys -t "$SESSION" ' '
wait_for "paused step 0 crash:FL" "the step pauses"
wait_for "‖ +[0-9]+%" "the timeline shows it paused"
before=$(pane | grep -Eo '[0-9]+/400' | head -1)
sleep 1
after=$(pane | grep -Eo '[0-9]+/400' | head -1)
[ "$before" = "$after" ] || { echo "tui_smoke: FAILED: training went on while paused ($before -> $after)" >&2; exit 1; }
echo "tui_smoke: ok: nothing trains while paused ($after)"
tmux send-keys -t "$SESSION" ' '
wait_for "training step 0 crash:FL" "the step resumes"
tmux send-keys -t "$SESSION" q
wait_for "Quit now\?" "quitting while training asks first"
tmux send-keys -t "$SESSION" n
wait_gone "Quit now\?" "'n' keeps training"
tmux send-keys -t "$SESSION" q
wait_for "Quit now\?" "quitting asks again"
tmux send-keys -t "$SESSION" y
wait_exit "$TMP/exit"
echo "tui_smoke: ok: the workbench exits 0"
test -f "$TMP/run/metrics.json" && test -f "$TMP/run/run.toml" && grep -q '"stopped"' "$TMP/run/log.txt" \
  || { echo "tui_smoke: FAILED: the run folder lacks metrics.json, run.toml or the stop in log.txt" >&2; ls -R "$TMP/run" >&2; exit 1; }
echo "tui_smoke: ok: the run folder holds metrics.json, run.toml and the log"

# The Sweep screen on a finished smoke sweep: the cells, the table, a cell opened and closed.
"$BIN" sweep plan scenes/sweep-smoke.toml --out "$TMP/sweep" >/dev/null
"$BIN" sweep local "$TMP/sweep" --jobs 2 >/dev/null 2>"$TMP/sweep-stderr" \
  || { echo "tui_smoke: FAILED: sweep local" >&2; cat "$TMP/sweep-stderr" >&2; exit 1; }
SESSION=$SWEEP_SESSION
tmux new-session -d -s "$SESSION" -x 120 -y 40 "$BIN tui --sweep $TMP/sweep 2>$TMP/stderr; echo exited \$? > $TMP/sweep-exit; sleep 30"
wait_for "sweep .* 4 cells: 4 finished" "the Sweep screen counts the finished cells"
wait_for "› +0 finished .* capacity=0.2 seed=1" "the cells with the cursor on the first"
wait_for "capacity=0.3 +2/2 +[0-9.]+ \[" "the collected table with intervals"
tmux send-keys -t "$SESSION" Down
wait_for "› +1 finished" "the cursor moves to cell 1"
tmux send-keys -t "$SESSION" Enter
wait_for "runs/1 · ours · 3/3 steps" "Enter opens cell 1's run in the workbench"
wait_for "Sequence" "the workbench's timeline"
tmux send-keys -t "$SESSION" q
wait_for "Collected" "quitting the run comes back to the Sweep screen"
tmux send-keys -t "$SESSION" q
wait_exit "$TMP/sweep-exit"
echo "tui_smoke: ok: the Sweep screen exits 0"
echo "tui_smoke: passed"
