#!/usr/bin/env python3
"""Markdown table of a `quadcl train` metrics.jsonl: means over blocks of iterations.

    python3 scripts/curve_table.py RUN/metrics.jsonl [--block 250]
"""
import argparse
import json
import math

COLUMNS = [
    ("return", "charts/episodic_return", "{:.2f}"),
    ("episode s", "charts/episodic_length_s", "{:.1f}"),
    ("fall rate", "charts/fall_rate", "{:.2f}"),
    ("lin err", "charts/lin_vel_err", "{:.3f}"),
    ("ang err", "charts/ang_vel_err", "{:.3f}"),
    ("action std", "charts/action_std", "{:.3f}"),
    ("mask churn", "charts/mask_churn_actor", "{:.3f}"),
    ("env steps/s", "charts/SPS", "{:.0f}"),
]


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("metrics")
    parser.add_argument("--block", type=int, default=250)
    args = parser.parse_args()
    rows = [json.loads(line) for line in open(args.metrics) if line.strip()]
    print("| iterations | " + " | ".join(c[0] for c in COLUMNS) + " |")
    print("| --- " * (len(COLUMNS) + 1) + "|")
    for start in range(0, len(rows), args.block):
        block = rows[start : start + args.block]
        first, last = int(block[0]["charts/iteration"]), int(block[-1]["charts/iteration"])
        cells = []
        for _, key, fmt in COLUMNS:
            values = [r[key] for r in block if key in r and r[key] is not None and math.isfinite(r[key])]
            cells.append(fmt.format(sum(values) / len(values)) if values else "-")
        print(f"| {first}-{last} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
