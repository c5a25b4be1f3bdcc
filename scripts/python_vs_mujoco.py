#!/usr/bin/env python3
"""quadcl's Python package against MuJoCo's own Python bindings, side by side on one thread (issue 40).

Three figures, alternated in rounds within one run, all 128 A1 environments on
one thread at quadcl's physics step and decimation (0.01 s x 2), under
trot-plus-noise actions, episodes reset as they end:

- quadcl from Python: `quadcl.make_vec(num_envs=128, num_threads=1)`, its `step`
  (physics, observations, rewards, resets, NumPy arrays out);
- quadcl from Rust: `quadcl bench --json --only env`'s
  `env_control_steps_per_s_batch128_1t` (the same batch without Python);
- MuJoCo from Python: the lean stack of scripts/python_ppo_baseline.py (`mujoco.rollout`
  over the 128 states, observations and rewards in NumPy, resets), its integrator
  implicitfast (Euler is unstable at 0.01 s here, see scripts/physics_vs_mujoco.py).

    pip install ./python mujoco numpy
    python3 scripts/python_vs_mujoco.py [--quadcl target/release/quadcl] [--rounds 3] [--seconds 3] [--json]

Prints the medians and the two ratios issue 40 asks for: Python quadcl / MuJoCo
(target >= 1.0) and Python quadcl / Rust quadcl (target >= 0.9).
"""

import argparse
import json
import statistics
import time

import mujoco
import numpy as np

import python_ppo_baseline as pb
import quadcl
from mujoco_a1 import ROOT, a1_model
from physics_vs_mujoco import bench_env, gait_actions

ENVS, DT, DECIMATION = 128, 0.01, 2


def batch_actions(rows, step):
    index = (step + 7 * np.arange(ENVS)) % len(rows)
    return rows[index]


def steps_per_s(step, rows, seconds):
    """Control steps per second (envs x steps) of `step(actions)` over `seconds`."""
    steps, start = 0, time.perf_counter()
    while time.perf_counter() - start < seconds:
        step(batch_actions(rows, steps))
        steps += 1
    return steps * ENVS / (time.perf_counter() - start)


def python_quadcl_rate(rows, seconds):
    envs = quadcl.make_vec(num_envs=ENVS, seed=0, num_threads=1)
    envs.reset(seed=0)
    return steps_per_s(envs.step, rows, seconds)


def mujoco_rate(rows, seconds):
    pb.DT, pb.DECIMATION, pb.EPISODE_STEPS = DT, DECIMATION, int(20.0 / (DT * DECIMATION))
    pb.a1_model = lambda: a1_model(DT, mujoco.mjtIntegrator.mjINT_IMPLICITFAST)
    return steps_per_s(pb.Envs(ENVS, 1, 0).step, rows.astype(np.float64), seconds)


def rust_rate(binary, seconds):
    return bench_env(binary, seconds)["env_control_steps_per_s_batch128_1t"]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quadcl", default=str(ROOT / "target" / "release" / "quadcl"))
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--seconds", type=float, default=3.0)
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    rows = gait_actions(DT * DECIMATION).astype(np.float32)
    got = {"python": [], "rust": [], "mujoco": []}
    for r in range(args.rounds):
        got["python"].append(python_quadcl_rate(rows, args.seconds))
        got["rust"].append(rust_rate(args.quadcl, args.seconds))
        got["mujoco"].append(mujoco_rate(rows, args.seconds))
        if not args.json:
            print(f"round {r + 1}: " + ", ".join(f"{k} {v[-1]:.0f}" for k, v in got.items()), flush=True)
    med = {k: statistics.median(v) for k, v in got.items()}
    result = {
        "quadcl_python_control_steps_per_s_128_1t": round(med["python"]),
        "quadcl_rust_control_steps_per_s_128_1t": round(med["rust"]),
        "mujoco_python_control_steps_per_s_128_1t": round(med["mujoco"]),
        "ratio_python_quadcl_over_mujoco": round(med["python"] / med["mujoco"], 3),
        "ratio_python_over_rust": round(med["python"] / med["rust"], 3),
        "rounds": args.rounds, "seconds": args.seconds, "mujoco": mujoco.__version__,
    }
    if args.json:
        print(json.dumps(result, indent=2))
    else:
        print(f"quadcl from Python {result['quadcl_python_control_steps_per_s_128_1t']:>7} /s   "
              f"quadcl in Rust {result['quadcl_rust_control_steps_per_s_128_1t']:>7} /s   "
              f"MuJoCo from Python {result['mujoco_python_control_steps_per_s_128_1t']:>7} /s")
        print(f"Python quadcl / MuJoCo {result['ratio_python_quadcl_over_mujoco']:.2f} (target 1.0)   "
              f"Python / Rust {result['ratio_python_over_rust']:.2f} (target 0.9)   "
              f"(medians of {args.rounds} alternated rounds of {args.seconds} s, 128 envs on one thread)")


if __name__ == "__main__":
    main()
