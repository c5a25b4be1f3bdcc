#!/usr/bin/env python3
"""Parity of exported quadcl policies in a real runtime: each FILE (.onnx in
ONNX Runtime, .safetensors in NumPy) is run on the observation histories of
FILE.reference.safetensors (written by `quadcl export --reference`) and its
actions and joint targets are compared with quadcl's own forward on them.
An ONNX file is also checked by `onnx.checker` when the `onnx` package is
installed. Prints the max abs differences; exits 1 if one exceeds the
tolerance (1e-5) or the contract lacks a key.

    python3 scripts/check_export.py crash_FL.onnx ewc.safetensors
    (pip install onnxruntime safetensors numpy [onnx])
"""
import pathlib
import sys

from safetensors.numpy import load_file

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
from quadcl_exported import load  # noqa: E402

TOLERANCE = 1e-5
CONTRACT = [
    "task", "joint_names", "default_joint_pos", "kp", "kd", "action_scale", "clip_actions",
    "control_dt", "obs_layout", "obs_normalization", "history_len", "obs_dim",
    "quadcl_version", "git_commit",
]


def check(path):
    problems = []
    if path.suffix == ".onnx":
        try:
            import onnx
        except ImportError:
            onnx = None
        if onnx is not None:
            onnx.checker.check_model(onnx.load(str(path)), full_check=True)
    policy = load(path)
    missing = [k for k in CONTRACT if k not in policy.metadata]
    if missing:
        problems.append(f"contract lacks {missing}")
    names = policy.metadata.get("joint_names", [])
    if len(names) != 12:
        problems.append(f"{len(names)} joint names, expected 12")
    reference = load_file(f"{path}.reference.safetensors")
    out = policy(reference["obs_history"])
    diffs = {k: float(abs(out[k] - reference[k]).max()) for k in ("actions", "joint_targets")}
    rows = reference["obs_history"].shape[0]
    print(
        f"{path}: task {policy.metadata.get('task')}, {rows} observation histories, "
        f"max |diff| actions {diffs['actions']:.2e}, joint_targets {diffs['joint_targets']:.2e} "
        f"(tolerance {TOLERANCE:g})"
    )
    problems += [f"{k} differ by {d:.2e}" for k, d in diffs.items() if not d <= TOLERANCE]
    return problems


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    failed = False
    for arg in sys.argv[1:]:
        for problem in check(pathlib.Path(arg)):
            print(f"{arg}: {problem}", file=sys.stderr)
            failed = True
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
