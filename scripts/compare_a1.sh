#!/usr/bin/env bash
# The baselines' comparison on the robot (issue 14): every method of
# scenes/compare-a1.toml, one after the other, into OUT/METHOD (resuming any
# that stopped), then the table of scripts/compare_table.py.
#   scripts/compare_a1.sh [OUT] [METHODS...]     (default runs/compare-a1, all methods)
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-runs/compare-a1}
shift || true
methods=("$@")
[ ${#methods[@]} -gt 0 ] || methods=(finetune ewc si ours)
bin=${QUADCL_BIN:-target/release/quadcl}
[ -x "$bin" ] || cargo build --release
for m in "${methods[@]}"; do
    dir="$out/$m"
    resume=()
    [ -f "$dir/run.toml" ] && resume=(--resume)
    start=$(date +%s)
    echo "== $m ($(date -u +%H:%M)) =="
    if [ "$m" = ours-paper ]; then
        "$bin" run --config scenes/compare-a1-paper.toml --out "$dir" "${resume[@]}"
    else
        "$bin" run --config scenes/compare-a1.toml --method "$m" --out "$dir" "${resume[@]}"
    fi
    echo "== $m took $(( $(date +%s) - start )) s =="
done
