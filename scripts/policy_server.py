#!/usr/bin/env python3
"""Drives quadcl's simulator with an exported policy running outside quadcl:
the program `quadcl eval --policy-cmd` talks to (see src/rl/external_policy.rs
for the protocol). Each control step it reads every environment's observation
history, (QUADCL_NUM_ENVS, QUADCL_HISTORY_LEN * QUADCL_OBS_DIM) little-endian
float32, runs the model (ONNX Runtime for .onnx, NumPy for .safetensors) and
writes the (N, QUADCL_ACT_DIM) actions back.

    quadcl eval --policy DIR --task crash:FL \\
        --policy-cmd "python3 scripts/policy_server.py crash_FL.onnx"
"""
import os
import pathlib
import sys

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
from quadcl_exported import load  # noqa: E402


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    policy = load(sys.argv[1])
    envs = int(os.environ["QUADCL_NUM_ENVS"])
    obs_dim, history_len = int(os.environ["QUADCL_OBS_DIM"]), int(os.environ["QUADCL_HISTORY_LEN"])
    act = int(os.environ["QUADCL_ACT_DIM"])
    meta = policy.metadata
    if (meta.get("obs_dim"), meta.get("history_len")) != (obs_dim, history_len):
        sys.exit(f"{sys.argv[1]}: made for frames of {meta.get('obs_dim')} x {meta.get('history_len')}, "
                 f"the simulator sends {obs_dim} x {history_len}")
    size = envs * obs_dim * history_len * 4
    stdin, stdout = sys.stdin.buffer, sys.stdout.buffer
    while True:
        data = stdin.read(size)
        if not data:
            return
        if len(data) != size:
            sys.exit(f"policy_server: a step of {len(data)} bytes, expected {size}")
        history = np.frombuffer(data, dtype="<f4").reshape(envs, -1)
        actions = policy(history)["actions"]
        assert actions.shape == (envs, act), actions.shape
        stdout.write(np.ascontiguousarray(actions, dtype="<f4").tobytes())
        stdout.flush()


if __name__ == "__main__":
    main()
