#!/usr/bin/env bash
# Every findings sweep of issues 34 and 60 (scenes/findings/), in the order their inputs need,
# resumable: a second call picks up where the first stopped (`quadcl sweep local` resumes
# stopped cells and skips finished ones; a fine-tuning with its finetune.json is done).
#
#   scripts/findings.sh run [JOBS [THREADS_PER_JOB]]   plan and train everything: JOBS workers
#                                                      (default 2, 1 thread each) share the cells
#   scripts/findings.sh harvest                        commit every finished sweep into
#                                                      policies/findings/ (scripts/findings_harvest.sh)
#   scripts/findings.sh status                         where every sweep stands
#   scripts/findings.sh sim2real [THREADS]             the fine-tunings whose sequence-12 cell has
#                                                      finished, now (short: a session's tail)
#   scripts/findings.sh save                           keep the finished cells of unharvested sweeps
#                                                      in policies/findings/progress (commit it)
#
# Run folders: runs/findings/NAME. QUADCL_BIN picks the binary (default target/release/quadcl).
# About 80,000 iterations in all: 18 h or more on 2 cores, two or three hours on 16.
# runs/ is not committed, so a fresh checkout has none of it: `save` keeps each finished cell's
# metrics.json and log.txt (no checkpoints) with the run file it trained (the checkout's path
# written as {repository}), and `run` puts them back into a newly planned sweep where the plan's
# run file is the same, so those cells count as finished. A cell stopped midway starts again.
set -euo pipefail
cd "$(dirname "$0")/.."
bin=${QUADCL_BIN:-target/release/quadcl}
[ -x "$bin" ] || { echo "$bin: no such binary (cargo build --release, or set QUADCL_BIN)" >&2; exit 1; }
# name, the group the others are set against (paired by seed), whether the final checkpoints
# are kept (sim2real fine-tunes sequence-12's), the sweep whose cells must all have finished
# before this one is planned and started (fig11-transfer's plan names the reference's
# metrics.json). In the order the workers take them: a dependent sweep after another, so that
# no worker waits long for its dependency; the long sequence-12 cells early, so that the last
# cells to run are short.
sweeps=(
  "fig11-reference||0|"
  "fig4-methods|name=ours|0|"
  "fig11-transfer|init=scratch|0|fig11-reference"
  "sequence-12||1|"
  "fig5-selection|lambda=0.25|0|"
  "fig8-plasticity|reinit_scores=none reinit_weights=false|0|"
  "fig4-budget|iterations=500 name=ours|0|"
  "ladder|arm=finetune|0|"
  "ladder-candidates|arm=finetune|0|"
  "paper-shape|name=ours|0|"
)
shift_file=scenes/findings/sim2real.shift.toml
progress=policies/findings/progress

# save|restore SWEEP_DIR PROGRESS_DIR KEEP: finished cells from the run folder into the progress
# folder, or back into a freshly planned run folder (only where the run file is the same);
# KEEP 1: with each cell's final checkpoint (sim2real fine-tunes sequence-12's).
cells() {
  python3 - "$@" <<'EOF'
import json, os, shutil, sys
mode, sweep, kept, keep = sys.argv[1:]
files = ["metrics.json", "log.txt"] + (["checkpoints"] if keep == "1" else [])
def copy(src, dst):
    for f in files:
        if os.path.isdir(os.path.join(src, f)):
            shutil.copytree(os.path.join(src, f), os.path.join(dst, f), dirs_exist_ok=True)
        elif os.path.exists(os.path.join(src, f)):
            shutil.copy(os.path.join(src, f), os.path.join(dst, f))
plan = json.load(open(os.path.join(sweep, "sweep.json")))
def finished(path):
    try:
        m = json.load(open(os.path.join(path, "metrics.json")))
    except (OSError, ValueError):
        return False
    return m.get("completed_steps") == m.get("total_steps") and m.get("total_steps", 0) > 0
def run_file(cell):
    # The cell's run file with this checkout's path taken out: the plan writes the base
    # policy's and the reference's absolute paths into it.
    text = open(os.path.join(sweep, cell["config"])).read()
    return text.replace(os.getcwd(), "{repository}")
def kept_run_file(store):
    try:
        return open(os.path.join(store, "run_file.toml")).read()
    except OSError:
        return None
moved = 0
for cell in plan["cells"]:
    run = os.path.join(sweep, cell["run"])
    store = os.path.join(kept, str(cell["index"]))
    if mode == "save" and finished(run) and not (finished(store) and kept_run_file(store) == run_file(cell)):
        tmp = store + ".tmp"
        shutil.rmtree(tmp, ignore_errors=True)
        os.makedirs(tmp)
        copy(run, tmp)
        with open(os.path.join(tmp, "run_file.toml"), "w") as f:
            f.write(run_file(cell))
        shutil.rmtree(store, ignore_errors=True)
        os.rename(tmp, store)
        moved += 1
    elif mode == "restore" and finished(store) and not finished(run):
        if kept_run_file(store) != run_file(cell):
            print(f"{store}: kept for another run file than cell {cell['index']}'s, not restored", file=sys.stderr)
            continue
        os.makedirs(run, exist_ok=True)
        copy(store, run)
        moved += 1
if moved:
    print(f"{sweep}: {moved} finished cells {'kept in' if mode == 'save' else 'restored from'} {kept}")
EOF
}

# sim2real, seed $1 (0-based cell of sequence-12), fine-tuned with $2 threads; done once its
# finetune.json is there (kept in progress/ across checkouts).
sim2real_seed() {
  local i=$1 seed=$(($1 + 1)) runs=runs/findings/sequence-12/runs
  local out=runs/findings/sim2real/seed$seed checkpoint
  # A committed report (harvested, or kept by `save`) stands in for the fine-tuning.
  for kept in "policies/findings/sim2real/seed$seed" "$progress/sim2real/seed$seed"; do
    if [ ! -f "$out/finetune.json" ] && [ -f "$kept/finetune.json" ]; then
      mkdir -p "$out" && cp "$kept/finetune.json" "$out/"
    fi
  done
  [ -f "$out/finetune.json" ] && return 0
  checkpoint=$(ls -d "$runs/$i"/checkpoints/step-11-* 2>/dev/null | head -n 1 || true)
  [ -n "$checkpoint" ] || { echo "sim2real: $runs/$i has no final checkpoint yet" >&2; return 1; }
  rm -rf "$out"
  mkdir -p runs/findings/sim2real
  RAYON_NUM_THREADS=$2 "$bin" finetune --policy "$checkpoint" --task crash:FL --shift "$shift_file" \
    --seed "$seed" --episodes 32 --out "$out"
}

# Sweep $1 planned into runs/findings/$1, with its finished cells kept in progress/ put back
# ($2: whether they keep their checkpoints); a harvested sweep's committed files stand in.
prepare() {
  local name=$1 keep=$2 out=runs/findings/$1
  # A harvested sweep is finished: its committed run files stand in (a later sweep may
  # read them, as fig11-transfer reads the reference's metrics.json).
  if [ ! -f "$out/sweep.json" ] && [ -f "policies/findings/$name/collected.md" ]; then
    mkdir -p "$out" && cp -r "policies/findings/$name/." "$out/"
  fi
  [ -f "$out/sweep.json" ] || "$bin" sweep plan "scenes/findings/$name.toml" --out "$out" > /dev/null
  if [ -d "$progress/$name" ]; then cells restore "$out" "$progress/$name" "$keep"; fi
}

# Whether every cell of runs/findings/$1 has finished; waits while any of them is running
# (another worker's last), and fails if one stopped or failed without finishing.
sweep_finished() {
  local dir=runs/findings/$1 states
  while :; do
    states=$("$bin" sweep status "$dir" --json | python3 -c 'import json, sys; print(" ".join(sorted({c["state"] for c in json.load(sys.stdin)})))')
    [ "$states" = finished ] && return 0
    [[ " $states " == *" running "* ]] || { echo "$dir: not every cell finished ($states)" >&2; return 1; }
    sleep 60
  done
}

# Worker $1: one `sweep local --jobs 1` on each sweep in turn. Several `sweep local` on one
# folder share its cells (each claims a cell under the folder's lock before starting it), so
# the workers train a sweep together, and one that finds no cell left moves on to the next
# while the others finish theirs.
worker() {
  local entry name keep after rc=0
  for entry in "${sweeps[@]}"; do
    IFS='|' read -r name _ keep after <<< "$entry"
    if [ -n "$after" ]; then
      # Its dependency unfinished: left for the next run, the other sweeps go on.
      sweep_finished "$after" || { echo "$name: skipped, $after has not finished" >&2; rc=1; continue; }
      # Planned once its dependency has finished, by the first worker here (not again by
      # the next, which would put kept cells back under a running one).
      ( flock 9 && { [ -f "runs/findings/$name/sweep.json" ] || prepare "$name" "$keep"; } ) \
        9> runs/findings/.plan.lock
    fi
    echo "== $name: worker $1 ($(date -u +%H:%M))"
    # A failed cell (its log in the sweep's logs/ says why) leaves its sweep unfinished; the
    # worker goes on with the next.
    "$bin" sweep local "runs/findings/$name" --jobs 1 --threads-per-job "$2" || rc=1
  done
  return "$rc"
}

case "${1:-}" in
  run)
    jobs=${2:-2} threads=${3:-1}
    mkdir -p runs/findings
    # Every sweep without a dependency planned now; the others by a worker, in turn.
    for entry in "${sweeps[@]}"; do
      IFS='|' read -r name _ keep after <<< "$entry"
      [ -n "$after" ] || prepare "$name" "$keep"
    done
    pids=()
    for w in $(seq 1 "$jobs"); do
      worker "$w" "$threads" &
      pids+=($!)
    done
    failed=0
    for pid in "${pids[@]}"; do wait "$pid" || failed=1; done
    echo "== sim2real ($(date -u +%H:%M))"
    # The three fine-tunings side by side (short; on 2 cores three share them).
    pids=()
    for i in 0 1 2; do
      sim2real_seed "$i" "$threads" &
      pids+=($!)
    done
    for pid in "${pids[@]}"; do wait "$pid" || failed=1; done
    [ "$failed" = 0 ] || { echo "not everything finished (see above: a failed cell, whose sweep's logs/ say why, a sweep not planned or skipped); run again to resume" >&2; exit 1; }
    ;;
  harvest)
    for entry in "${sweeps[@]}"; do
      IFS='|' read -r name against keep _ <<< "$entry"
      args=()
      [ -n "$against" ] && args+=(--against "$against")
      [ "$keep" = 1 ] && args+=(--keep-checkpoints)
      # Harvested already (and standing in for its run folder): remove policies/findings/NAME
      # to harvest it again.
      if [ -f "policies/findings/$name/collected.md" ]; then
        echo "$name: harvested already"
      elif [ -f "runs/findings/$name/sweep.json" ]; then
        QUADCL_BIN=$bin scripts/findings_harvest.sh "$name" "${args[@]}" || echo "$name: not harvested"
      fi
    done
    # sim2real: each seed's report (every task before and after, on the shifted robot), not the
    # policy, and their table over the seeds (`quadcl sweep finetunes`).
    harvested=0
    for i in 1 2 3; do
      report=runs/findings/sim2real/seed$i/finetune.json
      [ -f "$report" ] || continue
      mkdir -p policies/findings/sim2real/seed$i
      cp "$report" policies/findings/sim2real/seed$i/
      cp "$shift_file" policies/findings/sim2real/
      harvested=1
    done
    if [ "$harvested" = 1 ]; then
      "$bin" sweep finetunes policies/findings/sim2real
    fi
    ;;
  save)
    for entry in "${sweeps[@]}"; do
      name=${entry%%|*}
      # A harvested sweep is committed whole; its progress is no longer needed.
      if [ -f "policies/findings/$name/collected.md" ]; then
        rm -rf "${progress:?}/$name"
      elif [ -f "runs/findings/$name/sweep.json" ]; then
        IFS='|' read -r _ _ keep _ <<< "$entry"
        cells save "runs/findings/$name" "$progress/$name" "$keep"
      fi
    done
    for i in 1 2 3; do
      report=runs/findings/sim2real/seed$i/finetune.json
      # A harvested seed's report is committed in policies/findings/sim2real already.
      [ -f "policies/findings/sim2real/seed$i/finetune.json" ] && { rm -rf "${progress:?}/sim2real/seed$i"; continue; }
      [ -f "$report" ] && mkdir -p "$progress/sim2real/seed$i" && cp "$report" "$progress/sim2real/seed$i/"
    done
    rmdir "$progress/sim2real" 2>/dev/null || true
    true
    ;;
  sim2real)
    # What `run` does last, for the seeds whose twelve-task policy is there already (kept in
    # progress/ with its checkpoint): about 10 min each, so a session's last minutes, too short
    # for a sweep's cell, still finish something. One at a time.
    mkdir -p runs/findings
    prepare sequence-12 1
    failed=0
    for i in 0 1 2; do sim2real_seed "$i" "${2:-1}" || failed=1; done
    exit "$failed"
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
      if [ -f "policies/findings/sim2real/seed$i/finetune.json" ]; then
        echo "sim2real seed $i: done, harvested"
      elif [ -f "runs/findings/sim2real/seed$i/finetune.json" ]; then
        echo "sim2real seed $i: done"
      else
        echo "sim2real seed $i: not run"
      fi
    done
    ;;
  *)
    sed -n '2,14p' "$0" >&2
    exit 2
    ;;
esac
