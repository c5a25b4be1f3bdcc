#!/usr/bin/env python3
"""Whether each task of a `quadcl run` starts near the network it continues (issue 31):
per task, the mean training performance over its first N iterations (metrics.json's
curves) beside the base policy's zero-shot performance on that task (`quadcl eval`,
the mean action, 32 episodes unless changed), and their gap.

    python3 scripts/start_vs_zero_shot.py RUN_DIR BASE_POLICY [--first 10] [--episodes 32] [--seed 1] [--bin target/release/quadcl]

The training performance is of the exploring policy (actions sampled around the mean
at the task's starting std), the zero-shot one of the mean action: a gap of a few
hundredths is expected even for a task that starts exactly from the base.
"""
import argparse
import json
import pathlib
import subprocess
import sys


def main():
    p = argparse.ArgumentParser()
    p.add_argument("run")
    p.add_argument("base")
    p.add_argument("--first", type=int, default=10)
    p.add_argument("--episodes", type=int, default=32)
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--bin", default="target/release/quadcl")
    a = p.parse_args()
    path = pathlib.Path(a.run) / "metrics.json"
    try:
        metrics = json.loads(path.read_text())
    except (OSError, json.JSONDecodeError) as e:
        sys.exit(f"{path}: {e}")
    print(f"| task | first {a.first} iterations: performance | base zero-shot: performance (fall / lin m/s) | gap |")
    print("| --- | --- | --- | --- |")
    for curve in metrics["curves"]:
        first = curve["performance"][: a.first]
        start = sum(first) / len(first) if first else float("nan")
        out = subprocess.run(
            [a.bin, "eval", "--policy", a.base, "--task", curve["name"], "--episodes", str(a.episodes),
             "--seed", str(a.seed), "--json"],
            capture_output=True, text=True)
        if out.returncode != 0:
            sys.exit(f"quadcl eval of {a.base} on {curve['name']}: {out.stderr.strip()}")
        zero = json.loads(out.stdout)
        gap = start - zero["performance"]
        print(f"| {curve['name']} | {start:.3f} | {zero['performance']:.3f} ({zero['fall_rate']:.3f} / "
              f"{zero['lin_vel_err']:.3f}) | {gap:+.3f} |")


if __name__ == "__main__":
    main()
