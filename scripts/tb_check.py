#!/usr/bin/env python3
"""Reads a quadcl run's TensorBoard events back with TensorBoard's own reader
(EventAccumulator) and checks them against the run's metrics.json: every task
folder's `charts/performance` equals that task's curve (as float32), the
sequence folder holds every iteration on one axis and the measures after each
task under `eval/`. Exits non-zero, naming what differs.

    python3 scripts/tb_check.py RUN_DIR          (needs `pip install tensorboard`)
"""
import json
import pathlib
import struct
import sys

from tensorboard.backend.event_processing.event_accumulator import EventAccumulator


def f32(x):
    return struct.unpack("f", struct.pack("f", x))[0]


def scalars(folder):
    acc = EventAccumulator(str(folder), size_guidance={"scalars": 0})
    acc.Reload()
    return {tag: [(e.step, e.value) for e in acc.Scalars(tag)] for tag in acc.Tags()["scalars"]}


def main():
    run = pathlib.Path(sys.argv[1])
    metrics = json.loads((run / "metrics.json").read_text())
    total = 0
    for i, curve in enumerate(metrics["curves"]):
        name = curve["name"].replace(":", "_").replace("+", "_")
        folder = run / "tb" / f"{i:02d}-{name}"
        got = scalars(folder).get("charts/performance")
        want = [(k + 1, f32(v)) for k, v in enumerate(curve["performance"])]
        if got != want:
            sys.exit(f"{folder}: charts/performance {got[:3] if got else got}... != metrics.json's {want[:3]}...")
        total += len(want)
    seq = scalars(run / "tb" / "sequence")
    perf = seq.get("charts/performance", [])
    if [s for s, _ in perf] != list(range(1, total + 1)):
        sys.exit(f"tb/sequence: charts/performance has steps {[s for s, _ in perf][:5]}..., expected 1..{total}")
    avg = seq.get("eval/average_performance", [])
    if len(avg) != metrics["completed_steps"] or abs(avg[-1][1] - f32(metrics["average_performance"])) > 0:
        sys.exit(f"tb/sequence: eval/average_performance {avg} against {metrics['average_performance']}")
    tags = sorted(seq)
    print(f"tensorboard {sys.modules['tensorboard'].__version__ if 'tensorboard' in sys.modules else ''} read "
          f"{len(metrics['curves'])} task folders and the sequence ({len(tags)} tags, {total} iterations): "
          f"as metrics.json")


if __name__ == "__main__":
    import tensorboard  # noqa: F401  (for its version in the message)
    main()
