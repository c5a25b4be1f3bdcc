#!/usr/bin/env python3
"""The comparison table of issue 14: one row per method run under DIR
(DIR/METHOD/metrics.json, as scripts/compare_a1.sh writes them): average
performance, forgetting, plasticity (METHOD.md 4), the base task's final
performance, and every sequence task's final fall rate; then whether the
paper's ordering holds on what was measured.

    python3 scripts/compare_table.py [DIR]      (default runs/compare-a1)
"""
import json
import os
import sys

# `ours` is the adapter regime (scenes/compare-a1.toml), `ours-paper` the paper's (issue 13).
ORDER = ["ours", "ours-paper", "wsn", "packnet", "piggyback", "finetune", "ewc", "si", "rwalk", "er", "agem"]


def fmt(v, digits=3):
    return "-" if v is None else f"{v:.{digits}f}"


def main():
    root = sys.argv[1] if len(sys.argv) > 1 else "runs/compare-a1"
    rows = {}
    for name in sorted(os.listdir(root)):
        path = os.path.join(root, name, "metrics.json")
        if os.path.exists(path):
            rows[name] = json.load(open(path))
    if not rows:
        sys.exit(f"no METHOD/metrics.json under {root}")
    tasks = next(iter(rows.values()))["tasks"]
    seq = [t for t in tasks if t != "none"]
    print("| method | steps | average performance | forgetting | plasticity | none (base) at end | "
          + " | ".join(f"fall {t}" for t in seq) + " |")
    print("| --- " * (6 + len(seq)) + "|")
    for name in sorted(rows, key=lambda n: ORDER.index(n) if n in ORDER else len(ORDER)):
        m = rows[name]
        done = m["completed_steps"]
        final = {e["task"]: e for e in m["evaluations"][done - 1]} if done else {}
        base = final.get("none", {}).get("performance")
        falls = [fmt(final[t]["fall_rate"]) if t in final else "-" for t in seq]
        print(f"| {name} | {done}/{m['total_steps']} | {fmt(m['average_performance'])} | {fmt(m['forgetting'])} "
              f"| {fmt(m['plasticity'])} | {fmt(base)} | " + " | ".join(falls) + " |")
    done = {n: m for n, m in rows.items() if m["completed_steps"] == m["total_steps"]}
    checks = []
    for name in ("ours", "ours-paper"):
        if name in done:
            checks.append((f"{name} forgets nothing", done[name]["forgetting"] == 0.0))
    reg = [n for n in ("ewc", "si", "rwalk") if n in done]
    others = [n for n in done if n not in reg and n != "finetune"]
    if reg and others:
        most = min(done[n]["forgetting"] for n in reg)
        checks.append((f"{'/'.join(reg)} forget more than {'/'.join(sorted(others))}",
                       all(most > done[n]["forgetting"] for n in others)))
    if "packnet" in done and len(done) > 1:
        worst = min(done, key=lambda n: done[n]["plasticity"])
        checks.append((f"packnet learns worst (lowest plasticity; lowest here: {worst})", worst == "packnet"))
    if checks:
        print()
        for what, ok in checks:
            print(f"- {what}: {'holds' if ok else 'does NOT hold'} here")


if __name__ == "__main__":
    main()
