#!/usr/bin/env bash
# The picture of the Rerun viewer in docs/recordings.md: records 10 s of a policy on a task
# as .rrd, opens it in the viewer on a virtual display (software rendering)
# and saves a screenshot.
#   scripts/rerun_screenshot.sh [POLICY] [TASK] [OUT.png]
# Needs the viewer (pip install rerun-sdk==0.36.*; RERUN=path/to/rerun if it is
# not on PATH) and xvfb-run with a Vulkan or GL software driver (Debian:
# apt-get install xvfb mesa-vulkan-drivers libgl1-mesa-dri).
set -euo pipefail
cd "$(dirname "$0")/.."
policy=${1:-policies/sequence-a1-adapter/checkpoints/step-03-crash_FR}
task=${2:-crash:FL}
out=${3:-snapshots/rerun_view_crash_fl.png}
rerun=${RERUN:-rerun}
bin=${QUADCL_BIN:-target/release/quadcl}
[ -x "$bin" ] || cargo build --release
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
"$bin" record --policy "$policy" --task "$task" --seconds 10 --vx 0.5 --out "$tmp/view.rrd"
XDG_RUNTIME_DIR=$tmp xvfb-run -a -s "-screen 0 1600x1000x24" \
    "$rerun" "$tmp/view.rrd" --window-size 1600x1000 --screenshot-to "$tmp/shot.png" > "$tmp/viewer.log" 2>&1 || true
[ -s "$tmp/shot.png" ] || { echo "no screenshot; the viewer said:" >&2; tail -20 "$tmp/viewer.log" >&2; exit 1; }
python3 -c "
from PIL import Image
Image.open('$tmp/shot.png').convert('RGB').resize((1600, 1000), Image.LANCZOS).save('$out', optimize=True)
"
echo "wrote $out"
