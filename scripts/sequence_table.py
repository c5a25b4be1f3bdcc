#!/usr/bin/env python3
"""Markdown tables of a `quadcl run` metrics.json: every task evaluated after the
last completed task (with issue 5's targets, fall_rate <= 0.10 and lin_vel_err
<= 0.40 m/s, unless changed), how each masked step used the network (share of its
mask from earlier tasks, vacant share left; with --masks, how much came from the first
task's weights and how much from the tasks between), the entropy phase (the actor's sigma
and mask churn over a task's first iterations, where recorded), and each task's
training curve in blocks.

    python3 scripts/sequence_table.py RUN/metrics.json [--block 250] [--fall 0.10] [--lin 0.40] [--entropy-block 50] [--masks MASKS.json]
"""
import argparse
import json
import math


def mean(values):
    values = [v for v in values if v is not None and not math.isnan(v)]
    return sum(values) / len(values) if values else float("nan")


def capacity_from_masks(report, names):
    """The steps' capacity figures from `quadcl masks --json` of the final policy, for runs
    written before metrics.json recorded them: tasks end in id order, and a task's
    `from_vacant` elements leave the vacant pool for good."""
    layers = [l for n in report["networks"] for l in n["layers"]]
    total = sum(l["shape"][0] * l["shape"][1] for l in layers)
    used, out = 0, []
    left = {l["name"]: l["shape"][0] * l["shape"][1] for l in layers}
    for task in report["tasks"]:
        rows = [m for l in layers for m in l["per_task"] if m["task"] == task]
        used += sum(m["from_vacant"] for m in rows)
        for l in layers:
            left[l["name"]] -= sum(m["from_vacant"] for m in l["per_task"] if m["task"] == task)
        if task not in names:
            continue
        exhausted = [name for name, n in left.items() if n == 0]
        out.append((task, {
            "from_occupied_share": sum(m["from_occupied"] for m in rows) / max(1, sum(m["selected"] for m in rows)),
            "vacant_share_after": 1 - used / total,
            "exhausted_layers": exhausted,
        }))
    return out


def print_reuse(report):
    """Where each task's mask came from, over every masked layer: the first task's (the base's)
    weights, the fresh weights of the tasks between, or vacant weights. The first task's
    elements are all occupied, and every other occupied element is an earlier task's fresh one,
    so the middle share is the task's occupied share less its overlap with the first task."""
    layers = [l for n in report["networks"] for l in n["layers"]]
    tasks = report["tasks"]
    print(f"\nWhere each task's mask came from (shares of its selected weights):\n")
    print(f"| task | from {tasks[0]} | from the tasks between | fresh (vacant) |")
    print("| --- | --- | --- | --- |")
    for i, t in enumerate(tasks[1:], 1):
        rows = [m for l in layers for m in l["per_task"] if m["task"] == t]
        selected = max(1, sum(m["selected"] for m in rows))
        occupied = sum(m["from_occupied"] for m in rows)
        # overlap rows and columns follow the tasks of the layer's own per_task list.
        first = 0
        for l in layers:
            names = [m["task"] for m in l["per_task"]]
            if t in names and tasks[0] in names:
                first += l["overlap"][names.index(t)][names.index(tasks[0])]
        print(f"| {t} | {first / selected:.3f} | {(occupied - first) / selected:.3f} | {1 - occupied / selected:.3f} |")


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("metrics")
    parser.add_argument("--block", type=int, default=250)
    parser.add_argument("--fall", type=float, default=0.10)
    parser.add_argument("--lin", type=float, default=0.40)
    parser.add_argument("--entropy-block", type=int, default=50)
    parser.add_argument("--masks", help="`quadcl masks --json` of the final policy: where each mask came from "
                        "(and the capacity table of runs written before metrics.json recorded it)")
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
    capacity = [(s["name"], s["capacity"]) for s in m["steps"][:done] if s.get("capacity")]
    if not capacity and args.masks:
        capacity = capacity_from_masks(json.load(open(args.masks)), [s["name"] for s in m["steps"][:done]])
    if capacity:
        print("\nHow each masked step used the network (its mask's share taken from earlier tasks' "
              "weights; the layers' vacant share left after it):\n")
        print("| task | from earlier tasks | vacant left | layers with no vacant weight |")
        print("| --- | --- | --- | --- |")
        for name, cap in capacity:
            print(f"| {name} | {cap['from_occupied_share']:.3f} | {cap['vacant_share_after']:.3f} "
                  f"| {', '.join(cap['exhausted_layers']) or '-'} |")
    if args.masks:
        print_reuse(json.load(open(args.masks)))
    phases = [c for c in m["curves"][:done] if c.get("sigma")]
    if phases:
        print(f"\nThe entropy phase: the actor's mean sigma and mask churn (share redrawn per iteration), "
              f"per block of {args.entropy_block} iterations:\n")
        print("| task | iterations | sigma | churn |")
        print("| --- | --- | --- | --- |")
        for c in phases:
            actor = [k for k in c["sigma"] if k.startswith("actor.")]
            n = max(len(c["sigma"][k]) for k in actor)
            for start in range(0, min(n, args.entropy_block * 4), args.entropy_block):
                end = min(start + args.entropy_block, n)
                sigma = mean([mean(c["sigma"][k][start:end]) for k in actor])
                churn = mean([mean(c.get("mask_churn", {}).get(k, [])[max(start - 1, 0):max(end - 1, 0)]) for k in actor])
                print(f"| {c['name']} | {start + 1}-{end} | {sigma:.3f} | {churn:.4f} |")
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
