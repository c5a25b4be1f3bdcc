#!/usr/bin/env python3
"""quadcl's physics against MuJoCo's, side by side on one thread (issue 33).

One A1 env steps in each simulator, alternating in rounds within one run, at
the same physics step and substeps: quadcl's default (0.01 s x 2) and MuJoCo's
reference setting (0.005 s x 4). quadcl's figures come from
`quadcl bench --json --only env` (`env_control_steps_per_s_1t` and
`env_control_steps_per_s_1t_dt0005_x4`: one env, a 2 Hz trot plus noise,
episodes reset as they end). MuJoCo's come from its own Python bindings
stepping quadcl's A1 (scenes/a1.urdf with a floating base and a floor) under
the same kind of actions: position actuators (kp 20, kd 0.5, torque 33.5 N m)
around the default pose, action scale 0.25, the same trot-plus-noise rows,
a reset when the trunk falls below 0.18 m or tilts past 1 rad, or after 20 s;
its integrator is implicitfast (Euler goes unstable at 0.01 s here).
MuJoCo runs `mj_step` `decimation` times per control step from Python. Its
clock holds physics, the PD targets and the fall check only; quadcl's also holds
its observation and reward, so the ratio leans against quadcl.

    pip install mujoco numpy
    python3 scripts/physics_vs_mujoco.py [--quadcl target/release/quadcl] [--rounds 5] [--seconds 3] [--json]

Prints the median over rounds of each side's control steps/s per setting and
the ratio quadcl / MuJoCo (issue 33's target: at least 1.0 at 0.01 s x 2).
"""

import argparse
import json
import statistics
import subprocess
import time

import mujoco
import numpy as np

from mujoco_a1 import DEFAULT_Q, ROOT, a1_model as _a1_model

ACTION_SCALE = 0.25
ACTION_ROWS = 256


def a1_model(dt):
    # Euler (MuJoCo's default) blows up at 0.01 s with these gains (NaN in qacc within 2 s of the
    # trot); implicitfast is what MuJoCo's own legged models (Menagerie, mjlab) run, and holds at both.
    return _a1_model(dt, mujoco.mjtIntegrator.mjINT_IMPLICITFAST)


def gait_actions(policy_dt):
    """quadcl's bench actions: a 2 Hz trot on thighs and calves plus uniform noise of 0.3."""
    rng = np.random.default_rng(0)
    rows = np.zeros((ACTION_ROWS, 12))
    for k in range(ACTION_ROWS):
        phase = k * policy_dt * 2.0 * 2.0 * np.pi
        for j in range(12):
            leg = j // 3
            diagonal = 1.0 if leg in (0, 3) else -1.0
            swing = 0.0 if j % 3 == 0 else diagonal * np.sin(phase)
            rows[k, j] = swing + 0.3 * rng.uniform(-1.0, 1.0)
    return rows


def mujoco_rate(dt, decimation, seconds):
    model = a1_model(dt)
    data = mujoco.MjData(model)
    targets = DEFAULT_Q + ACTION_SCALE * gait_actions(dt * decimation)
    episode_steps = int(20.0 / (dt * decimation))

    def reset():
        mujoco.mj_resetData(model, data)
        data.qpos[7:] = DEFAULT_Q
        mujoco.mj_forward(model, data)

    reset()
    steps, episode = 0, 0
    start = time.perf_counter()
    while time.perf_counter() - start < seconds:
        for _ in range(50):
            data.ctrl[:] = targets[steps % ACTION_ROWS]
            for _ in range(decimation):
                mujoco.mj_step(model, data)
            steps += 1
            episode += 1
            w, x, y, _ = data.qpos[3:7]
            up = 1.0 - 2.0 * (x * x + y * y)  # z of the trunk's up axis
            if data.qpos[2] < 0.18 or up < np.cos(1.0) or episode >= episode_steps:
                reset()
                episode = 0
    return steps / (time.perf_counter() - start)


def bench_env(binary, seconds):
    """`quadcl bench --json --only env`'s report (every `env_*` figure)."""
    out = subprocess.run(
        [binary, "bench", "--json", "--only", "env", "--seconds", str(seconds)],
        check=True, capture_output=True, text=True,
    ).stdout
    return json.loads(out)


def quadcl_rates(binary, seconds):
    report = bench_env(binary, seconds)
    return report["env_control_steps_per_s_1t"], report["env_control_steps_per_s_1t_dt0005_x4"]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quadcl", default=str(ROOT / "target" / "release" / "quadcl"))
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--seconds", type=float, default=3.0)
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()

    rows = {"q_dt001_x2": [], "q_dt0005_x4": [], "m_dt001_x2": [], "m_dt0005_x4": []}
    for r in range(args.rounds):
        q1, q2 = quadcl_rates(args.quadcl, args.seconds)
        rows["q_dt001_x2"].append(q1)
        rows["q_dt0005_x4"].append(q2)
        rows["m_dt001_x2"].append(mujoco_rate(0.01, 2, args.seconds))
        rows["m_dt0005_x4"].append(mujoco_rate(0.005, 4, args.seconds))
        if not args.json:
            print(f"round {r + 1}: " + ", ".join(f"{k} {v[-1]:.0f}" for k, v in rows.items()), flush=True)
    med = {k: statistics.median(v) for k, v in rows.items()}
    result = {
        "quadcl_control_steps_per_s_1t_dt001_x2": round(med["q_dt001_x2"]),
        "mujoco_control_steps_per_s_1t_dt001_x2": round(med["m_dt001_x2"]),
        "ratio_dt001_x2": round(med["q_dt001_x2"] / med["m_dt001_x2"], 3),
        "quadcl_control_steps_per_s_1t_dt0005_x4": round(med["q_dt0005_x4"]),
        "mujoco_control_steps_per_s_1t_dt0005_x4": round(med["m_dt0005_x4"]),
        "ratio_dt0005_x4": round(med["q_dt0005_x4"] / med["m_dt0005_x4"], 3),
        "rounds": args.rounds,
        "seconds": args.seconds,
        "mujoco": mujoco.__version__,
    }
    if args.json:
        print(json.dumps(result, indent=2))
    else:
        print(f"0.01 s x 2:  quadcl {result['quadcl_control_steps_per_s_1t_dt001_x2']:>7} /s   "
              f"MuJoCo {result['mujoco_control_steps_per_s_1t_dt001_x2']:>7} /s   ratio {result['ratio_dt001_x2']:.2f}")
        print(f"0.005 s x 4: quadcl {result['quadcl_control_steps_per_s_1t_dt0005_x4']:>7} /s   "
              f"MuJoCo {result['mujoco_control_steps_per_s_1t_dt0005_x4']:>7} /s   ratio {result['ratio_dt0005_x4']:.2f}")
        print(f"(medians of {args.rounds} alternated rounds of {args.seconds} s, one thread each, MuJoCo {mujoco.__version__})")


if __name__ == "__main__":
    main()
