#!/usr/bin/env bash
# Compares the training throughput of two or more quadcl binaries on a shared
# machine: runs `quadcl train` with each in turn (A B A B ...), so slow
# minutes of the machine fall on all of them alike, and prints per run the
# median and fastest env steps/s of the measured iterations, the least
# physics and update time of an iteration, the CPU time stolen by other
# tenants while it ran (/proc/stat, in 1/100 s of one CPU), its minor page
# faults, system time and peak memory (GNU time, when installed).
#
#   scripts/ab_throughput.sh [-c CONFIG] [-r ROUNDS] [-i ITERATIONS] BIN_A BIN_B [BIN ...]
#
# Defaults: scenes/train-base.toml, 3 rounds, 14 iterations of which the first
# 2 (warm-up) are not counted. Same bytes or not is a separate question: train
# 3 iterations with each binary and `cmp` the policy/ and checkpoint/ files.
set -euo pipefail

config=scenes/train-base.toml
rounds=3
iterations=14
while getopts "c:r:i:" opt; do
    case $opt in
        c) config=$OPTARG ;;
        r) rounds=$OPTARG ;;
        i) iterations=$OPTARG ;;
        *) echo "usage: $0 [-c CONFIG] [-r ROUNDS] [-i ITERATIONS] BIN_A BIN_B [BIN ...]" >&2; exit 2 ;;
    esac
done
shift $((OPTIND - 1))
if [ $# -lt 2 ]; then
    echo "usage: $0 [-c CONFIG] [-r ROUNDS] [-i ITERATIONS] BIN_A BIN_B [BIN ...]" >&2
    exit 2
fi
if [ "$iterations" -lt 4 ]; then
    echo "$0: -i must be at least 4 (2 warm-up iterations are not counted)" >&2
    exit 2
fi
[ -r "$config" ] || { echo "$0: cannot read config $config" >&2; exit 2; }
for bin in "$@"; do
    [ -x "$bin" ] || { echo "$0: $bin is not an executable" >&2; exit 2; }
done

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
gnu_time=$(command -v /usr/bin/time || true)
steal() { awk '/^cpu /{print $9}' /proc/stat; }

# phys_min / upd_min: the least physics / update time of a counted iteration (ms);
# upd_med: the median update time (ms).
printf '%-24s %5s %6s %8s %8s %8s %8s %8s %8s %6s %6s\n' binary round steal sps_med sps_best phys_min upd_min upd_med faults sys_s rss_mb
for round in $(seq "$rounds"); do
    for index in $(seq $#); do
        bin=${!index}
        out=$work/run$index
        rm -rf "$out"
        before=$(steal)
        if [ -n "$gnu_time" ]; then
            "$gnu_time" -o "$work/time" -f '%R %S %M' "$bin" train --config "$config" --out "$out" --iterations "$iterations" >/dev/null 2>"$work/err" ||
                { cat "$work/err" >&2; exit 1; }
        else
            "$bin" train --config "$config" --out "$out" --iterations "$iterations" >/dev/null 2>"$work/err" ||
                { cat "$work/err" >&2; exit 1; }
            echo "- - -" >"$work/time"
        fi
        after=$(steal)
        python3 - "$bin" "$round" "$((after - before))" "$out/metrics.jsonl" "$work/time" <<'PY'
import json, statistics, sys

name, round_, stolen, metrics, timing = sys.argv[1:6]
rows = [json.loads(line) for line in open(metrics)][2:]
sps = [r["charts/SPS"] for r in rows]
physics = [1000 * r["time/env_s"] for r in rows]
update = [1000 * r["time/update_s"] for r in rows]
faults, sys_s, rss = (open(timing).read().split() + ["-"] * 3)[:3]
rss_mb = f"{int(rss) / 1024:.0f}" if rss.isdigit() else "-"
print(f"{name[-24:]:<24} {round_:>5} {stolen:>6} {statistics.median(sps):8.0f} {max(sps):8.0f} "
      f"{min(physics):8.0f} {min(update):8.0f} {statistics.median(update):8.0f} {faults:>8} {sys_s:>6} {rss_mb:>6}")
PY
    done
done
