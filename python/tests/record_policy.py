"""A `quadcl eval --policy-cmd` program for the parity tests: answers every step
with deterministic actions (a function of the step and the env) and appends
every observation history it receives to the .npy file named first."""

import os
import sys

import numpy as np


def actions_for(step, envs, act):
    k = np.arange(envs * act, dtype=np.float64).reshape(envs, act)
    return (0.8 * np.sin(0.37 * step + 0.11 * k)).astype(np.float32)


def main():
    out = sys.argv[1]
    envs, act = int(os.environ["QUADCL_NUM_ENVS"]), int(os.environ["QUADCL_ACT_DIM"])
    width = int(os.environ["QUADCL_OBS_DIM"]) * int(os.environ["QUADCL_HISTORY_LEN"])
    seen = []
    step = 0
    while True:
        data = sys.stdin.buffer.read(envs * width * 4)
        if not data:
            break
        seen.append(np.frombuffer(data, dtype="<f4").reshape(envs, width).copy())
        sys.stdout.buffer.write(actions_for(step, envs, act).astype("<f4").tobytes())
        sys.stdout.buffer.flush()
        step += 1
    np.save(out, np.stack(seen))


if __name__ == "__main__":
    main()
