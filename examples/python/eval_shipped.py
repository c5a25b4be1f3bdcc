#!/usr/bin/env python3
"""Scores a shipped policy from Python: every task it learned, recalled through
the Rust masked network and evaluated by `quadcl.evaluate` (the measures of
`quadcl eval` and `metrics.json`), and one episode stepped by hand with
`make_vec` to show the loop a researcher's own code would run.

    pip install ./python
    python3 examples/python/eval_shipped.py [POLICY_DIR] [--episodes 32]

POLICY_DIR defaults to the shipped four-task sequence's final policy,
`policies/sequence-a1-adapter/checkpoints/step-03-crash_FR`.
"""

import argparse

import numpy as np

import quadcl


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("policy", nargs="?", default="policies/sequence-a1-adapter/checkpoints/step-03-crash_FR")
    p.add_argument("--episodes", type=int, default=32)
    p.add_argument("--seed", type=int, default=0)
    a = p.parse_args()

    tasks = quadcl.load_policy(a.policy, "none").tasks
    print(f"{a.policy}: {len(tasks)} tasks, {a.episodes} episodes each (seed {a.seed})")
    print(f"{'task':<12} {'performance':>11} {'fall rate':>9} {'lin_vel_err':>11} {'ang_vel_err':>11}")
    for task in tasks:
        policy = quadcl.load_policy(a.policy, task)
        r = quadcl.evaluate(policy, task, episodes=a.episodes, seed=a.seed)
        print(f"{task:<12} {r['performance']:>11.3f} {r['fall_rate']:>9.3f} {r['lin_vel_err']:>11.3f} {r['ang_vel_err']:>11.3f}")

    # The same policy stepped by hand: the last task, 8 environments, one 20 s episode.
    task = tasks[-1]
    policy = quadcl.load_policy(a.policy, task)
    envs = quadcl.make_vec(task=task, num_envs=8, seed=a.seed, env_toml=policy.env_toml)
    obs, _ = envs.reset(seed=a.seed)
    done, returns = np.zeros(8, bool), np.zeros(8)
    while not done.all():
        obs, reward, terminated, truncated, infos = envs.step(policy(obs))
        returns += np.where(done, 0.0, reward)
        done |= terminated | truncated
    print(f"{task}, stepped by hand: returns {np.round(returns, 2).tolist()}")


if __name__ == "__main__":
    main()
