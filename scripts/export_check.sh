#!/usr/bin/env bash
# The exported policies in real runtimes (issue 35): every learned task of the
# shipped masked run and a dense method's task exported as ONNX and safetensors,
# run in ONNX Runtime and NumPy on quadcl's reference samples (max abs difference
# <= 1e-5, scripts/check_export.py), then an ONNX model driving the simulator
# (quadcl eval --policy-cmd scripts/policy_server.py) beside quadcl's own
# networks on the same episodes: fall rate and tracking printed side by side.
#
#   scripts/export_check.sh [QUADCL_BIN] [EPISODES]
# (pip installs onnxruntime, onnx, safetensors and numpy when missing)
set -euo pipefail
cd "$(dirname "$0")/.."
bin=${1:-target/release/quadcl}
episodes=${2:-16}
python3 -c "import onnxruntime, onnx, safetensors, numpy" 2>/dev/null \
  || python3 -m pip install -q onnxruntime onnx safetensors numpy
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
masked=policies/sequence-a1-adapter/checkpoints/step-03-crash_FR
dense=policies/compare-a1/ewc/checkpoints/step-03-crash_FR
"$bin" export --policy "$masked" --all-tasks --format onnx --out "$out/masked" --reference
"$bin" export --policy "$masked" --task crash:FL --format safetensors --out "$out/crash_FL.safetensors" --reference
"$bin" export --policy "$dense" --task crash:FR --format onnx --out "$out/ewc-crash_FR.onnx" --reference
"$bin" export --policy "$dense" --task crash:FR --format safetensors --out "$out/ewc-crash_FR.safetensors" --reference
python3 scripts/check_export.py "$out"/masked/*.onnx "$out/crash_FL.safetensors" \
  "$out/ewc-crash_FR.onnx" "$out/ewc-crash_FR.safetensors"
# Closed loop: the same task, seed and episodes with quadcl's networks and with ONNX Runtime.
native=$("$bin" eval --policy "$masked" --task crash:FL --episodes "$episodes" --seed 1 --json)
onnx=$("$bin" eval --policy "$masked" --task crash:FL --episodes "$episodes" --seed 1 --json \
  --policy-cmd "python3 scripts/policy_server.py $out/masked/crash_FL.onnx")
python3 - "$native" "$onnx" <<'PY'
import json, sys
native, onnx = (json.loads(a) for a in sys.argv[1:])
print(f"{'crash:FL, ' + str(native['episodes']) + ' episodes':<24} {'quadcl':>8} {'ONNX Runtime':>13}")
for key in ("performance", "fall_rate", "lin_vel_err", "ang_vel_err", "survival_s"):
    print(f"{key:<24} {native[key]:>8.3f} {onnx[key]:>13.3f}")
# Actions agree to 1e-5, so the episodes follow each other until chaos parts them: the figures
# must agree within noise (one episode's fall either way, a few cm/s of tracking).
one_episode = 1.0 / native["episodes"]
assert abs(native["fall_rate"] - onnx["fall_rate"]) <= one_episode + 1e-9, "fall rates differ"
assert abs(native["lin_vel_err"] - onnx["lin_vel_err"]) <= 0.05, "tracking differs"
PY
echo "export check passed"
