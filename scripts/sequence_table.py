#!/usr/bin/env python3
"""Markdown tables of a `quadcl run` metrics.json: every task evaluated after the
last completed task (with issue 5's targets, fall_rate <= 0.10 and lin_vel_err
<= 0.40 m/s, unless changed), and each task's training curve in blocks.

    python3 scripts/sequence_table.py RUN/metrics.json [--block 250] [--fall 0.10] [--lin 0.40]
"""
import argparse
import json
import math


def mean(values):
    values = [v for v in values if v is not None and not math.isnan(v)]
    return sum(values) / len(values) if values else float("nan")


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("metrics")
    parser.add_argument("--block", type=int, default=250)
    parser.add_argument("--fall", type=float, default=0.10)
    parser.add_argument("--lin", type=float, default=0.40)
    args = parser.parse_args()
    m = json.load(open(args.metrics))
    done = m["completed_steps"]
    print(f"{m['method']}: {done} of {m['total_steps']} steps; average performance {m['average_performance']}, "
          f"forgetting {m['forgetting']}, plasticity {m['plasticity']}\n")
    if done == 0:
        return
    trained = {s["name"] for s in m["steps"][:done]}
    print("| task | performance | return | fall_rate | lin_vel_err | ang_vel_err | meets targets |")
    print("| --- | --- | --- | --- | --- | --- | --- |")
    for e in m["evaluations"][done - 1]:
        ok = e["fall_rate"] <= args.fall and e["lin_vel_err"] <= args.lin
        mark = ("yes" if ok else "NO") if e["task"] in trained else "(base)"
        print(f"| {e['task']} | {e['performance']:.3f} | {e['mean_return']:.2f} | {e['fall_rate']:.3f} "
              f"| {e['lin_vel_err']:.3f} | {e['ang_vel_err']:.3f} | {mark} |")
    for c in m["curves"][:done]:
        print(f"\n{c['name']} (step {c['step']}), training rollouts:\n")
        keys = ["performance", "episodic_return", "lin_vel_err", "ang_vel_err"] + (["fall_rate"] if c.get("fall_rate") else [])
        print("| iterations | " + " | ".join(keys) + " |")
        print("| --- " * (len(keys) + 1) + "|")
        n = len(c["performance"])
        for start in range(0, n, args.block):
            end = min(start + args.block, n)
            # Episode metrics skip iterations in which no episode ended: blocks of them are approximate.
            cols = [mean(c[k][start:end]) for k in keys]
            print(f"| {start + 1}-{end} | " + " | ".join(f"{v:.3f}" for v in cols) + " |")


if __name__ == "__main__":
    main()
