#!/usr/bin/env bash
# Every findings sweep of issue 34 (scenes/findings/), in the order their inputs need,
# resumable: a second call picks up where the first stopped (`quadcl sweep local` resumes
# stopped cells and skips finished ones; a fine-tuning with its finetune.json is done).
#
#   scripts/findings.sh run [JOBS [THREADS_PER_JOB]]   plan and train everything (default 2 1)
#   scripts/findings.sh harvest                        commit every finished sweep into
#                                                      policies/findings/ (scripts/findings_harvest.sh)
#   scripts/findings.sh status                         where every sweep stands
#
# Run folders: runs/findings/NAME. QUADCL_BIN picks the binary (default target/release/quadcl).
# About 68,000 iterations in all: 12 h or more on 2 cores, an hour or two on 16.
set -euo pipefail
cd "$(dirname "$0")/.."
bin=${QUADCL_BIN:-target/release/quadcl}
[ -x "$bin" ] || { echo "$bin: no such binary (cargo build --release, or set QUADCL_BIN)" >&2; exit 1; }
# name, the group the others are set against (paired by seed), whether the final checkpoints
# are kept (sim2real fine-tunes sequence-12's).
sweeps=(
  "fig11-reference||0"
  "fig11-transfer|init=scratch|0"
  "fig4-methods|name=ours|0"
  "fig5-selection|lambda=0.25|0"
  "fig8-plasticity|reinit_scores=none reinit_weights=false|0"
  "sequence-12||1"
)
shift_file=scenes/findings/sim2real.shift.toml

sim2real() {
  local runs=runs/findings/sequence-12/runs
  for i in 0 1 2; do
    local seed=$((i + 1)) out=runs/findings/sim2real/seed$((i + 1))
    [ -f "$out/finetune.json" ] && continue
    local checkpoint
    checkpoint=$(ls -d "$runs/$i"/checkpoints/step-11-* 2>/dev/null | head -n 1)
    [ -n "$checkpoint" ] || { echo "sim2real: $runs/$i has no final checkpoint yet" >&2; return 1; }
    rm -rf "$out"
    mkdir -p runs/findings/sim2real
    "$bin" finetune --policy "$checkpoint" --task crash:FL --shift "$shift_file" --seed "$seed" \
      --episodes 32 --out "$out"
  done
}

case "${1:-}" in
  run)
    jobs=${2:-2} threads=${3:-1}
    for entry in "${sweeps[@]}"; do
      name=${entry%%|*}
      out=runs/findings/$name
      [ -f "$out/sweep.json" ] || "$bin" sweep plan "scenes/findings/$name.toml" --out "$out" > /dev/null
      echo "== $name ($(date -u +%H:%M))"
      "$bin" sweep local "$out" --jobs "$jobs" --threads-per-job "$threads"
    done
    echo "== sim2real ($(date -u +%H:%M))"
    sim2real
    ;;
  harvest)
    for entry in "${sweeps[@]}"; do
      IFS='|' read -r name against keep <<< "$entry"
      args=()
      [ -n "$against" ] && args+=(--against "$against")
      [ "$keep" = 1 ] && args+=(--keep-checkpoints)
      if [ -f "runs/findings/$name/sweep.json" ]; then
        QUADCL_BIN=$bin scripts/findings_harvest.sh "$name" "${args[@]}" || echo "$name: not harvested"
      fi
    done
    # sim2real: each seed's report (every task before and after, on the shifted robot), not the policy.
    for i in 1 2 3; do
      report=runs/findings/sim2real/seed$i/finetune.json
      [ -f "$report" ] || continue
      mkdir -p policies/findings/sim2real/seed$i
      cp "$report" policies/findings/sim2real/seed$i/
      cp "$shift_file" policies/findings/sim2real/
    done
    ;;
  status)
    for entry in "${sweeps[@]}"; do
      name=${entry%%|*}
      if [ -f "runs/findings/$name/sweep.json" ]; then
        echo "$name: $("$bin" sweep status "runs/findings/$name" | tail -n 1)"
      else
        echo "$name: not planned"
      fi
    done
    for i in 1 2 3; do
      [ -f "runs/findings/sim2real/seed$i/finetune.json" ] && echo "sim2real seed $i: done" || echo "sim2real seed $i: not run"
    done
    ;;
  *)
    sed -n '2,12p' "$0" >&2
    exit 2
    ;;
esac
