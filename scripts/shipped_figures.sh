#!/usr/bin/env bash
# Prints the evaluation figures and mask statistics of every shipped policy,
# one line each, so that a change that must not change behaviour can be
# checked against them: run it before and after, and diff the outputs.
#
#   scripts/shipped_figures.sh [QUADCL_BINARY] > figures.txt
#
# Evaluations: 32 episodes, seed 0, pushes on (the `quadcl eval` defaults);
# the gait at the `quadcl gait` defaults (0.5 m/s); the sha256 of `masks --json`.
set -euo pipefail
cd "$(dirname "$0")/.."
bin=${1:-target/release/quadcl}
[ -x "$bin" ] || { echo "no binary at $bin: cargo build --release first" >&2; exit 1; }
seq_ckpt=policies/sequence-a1-adapter/checkpoints/step-03-crash_FR
evals=(
  "policies/base-a1-flat none"
  "policies/base-a1-flat crash:FL"
  "policies/base-a1-flat-run/checkpoint none"
  "policies/base-a1-flat-shared none"
)
for task in none crash:FL invert:RL noise:FL crash:FR; do
  evals+=("$seq_ckpt $task")
done
for entry in "${evals[@]}"; do
  read -r dir task <<<"$entry"
  echo "eval $dir $task: $("$bin" eval --policy "$dir" --task "$task" --json)"
done
echo "gait policies/base-a1-flat: $("$bin" gait --policy policies/base-a1-flat --json)"
for dir in policies/base-a1-flat policies/base-a1-flat-shared "$seq_ckpt"; do
  echo "masks $dir: sha256 $("$bin" masks --policy "$dir" --json | sha256sum | cut -d' ' -f1)"
done
