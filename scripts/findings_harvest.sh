#!/usr/bin/env bash
# Copies a finished findings sweep (issue 34) from its run folder into
# policies/findings/NAME, the committed form: sweep.json, cells/, each cell's
# metrics.json and log.txt (no checkpoints, unless --keep-checkpoints: a later
# step reads them, as sim2real reads sequence-12's), then writes its tables and
# figures there with the same commands a reader runs:
#   quadcl sweep collect policies/findings/NAME --per-task --plasticity-trend [--against GROUP]
#   quadcl plot policies/findings/NAME --out policies/findings/NAME/plots
#
#   scripts/findings_harvest.sh NAME [--against GROUP] [--keep-checkpoints] [--from DIR]
#     NAME     a sweep of scenes/findings/ (fig4-methods, fig5-selection, ...)
#     --from   its run folder (default runs/findings/NAME)
# QUADCL_BIN picks the binary (default target/release/quadcl). Refuses a sweep with
# unfinished cells: a committed table is over every planned seed.
set -euo pipefail
cd "$(dirname "$0")/.."
name=${1:?usage: scripts/findings_harvest.sh NAME [--against GROUP] [--keep-checkpoints] [--from DIR]}
shift
against="" keep=0 from="runs/findings/$name"
while [ $# -gt 0 ]; do
  case "$1" in
    --against) against=$2; shift 2 ;;
    --keep-checkpoints) keep=1; shift ;;
    --from) from=$2; shift 2 ;;
    *) echo "unknown argument $1" >&2; exit 2 ;;
  esac
done
bin=${QUADCL_BIN:-target/release/quadcl}
[ -x "$bin" ] || { echo "$bin: no such binary (cargo build --release, or set QUADCL_BIN)" >&2; exit 1; }
[ -f "$from/sweep.json" ] || { echo "$from: no sweep.json (plan and run the sweep first)" >&2; exit 1; }
status=$("$bin" sweep status "$from")
if ! echo "$status" | tail -n 1 | grep -Eq '^([0-9]+) cells: \1 finished'; then
  echo "$from: not every cell has finished:" >&2
  echo "$status" >&2
  exit 1
fi
out=policies/findings/$name
mkdir -p policies/findings
stage=$(mktemp -d "policies/findings/.$name.XXXX")
trap 'rm -rf "$stage"' EXIT
cp "$from/sweep.json" "$stage/"
cp -r "$from/cells" "$stage/"
for run in "$from"/runs/*/; do
  i=$(basename "$run")
  mkdir -p "$stage/runs/$i"
  cp "$run/metrics.json" "$run/log.txt" "$stage/runs/$i/"
  if [ "$keep" = 1 ] && [ -d "$run/checkpoints" ]; then
    # The final checkpoint only (keep_last_checkpoint_only leaves one).
    cp -r "$run/checkpoints" "$stage/runs/$i/"
  fi
done
args=(--per-task --plasticity-trend)
[ -n "$against" ] && args+=(--against "$against")
"$bin" sweep collect "$stage" "${args[@]}" > /dev/null
"$bin" plot "$stage" --out "$stage/plots" > /dev/null
rm -rf "$out"
mv "$stage" "$out"
trap - EXIT
echo "$out: $(find "$out" -type f | wc -l) files, $(du -sh "$out" | cut -f1)"
cat "$out/collected.md"
[ -f "$out/contrast.md" ] && { echo; cat "$out/contrast.md"; }
true
