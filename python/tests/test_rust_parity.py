"""The Python front is the Rust simulator and recall, bit for bit: the
observations `quadcl eval --policy-cmd` hands a program equal make_vec's for
the same settings, seed and actions, step for step; quadcl.evaluate gives
`quadcl eval --json`'s numbers."""

import json
import subprocess
import sys

import numpy as np

import quadcl
from conftest import quadcl_binary

sys.path.insert(0, __import__("os").path.dirname(__file__))
from record_policy import actions_for  # noqa: E402

POLICY = "policies/base-a1-flat"


def eval_json(root, *args):
    out = subprocess.run([quadcl_binary(), "eval", "--policy", POLICY, "--json", *args], cwd=root, check=True,
                         capture_output=True, text=True).stdout
    return json.loads(out.strip().splitlines()[-1])


def test_make_vec_observations_equal_the_rust_environments_step_for_step(root, tmp_path):
    envs, seed, task = 6, 11, "crash:FL"
    seen = tmp_path / "seen.npy"
    cmd = f"{sys.executable} {root / 'python/tests/record_policy.py'} {seen}"
    eval_json(root, "--task", task, "--episodes", str(envs), "--seed", str(seed), "--policy-cmd", cmd)
    rust = np.load(seen)
    assert rust.shape[0] > 50, rust.shape
    policy = quadcl.load_policy(root / POLICY, task)
    vec = quadcl.make_vec(task=task, num_envs=envs, seed=seed, env_toml=policy.env_toml)
    obs, _ = vec.reset(seed=seed)
    for step, expected in enumerate(rust):
        assert np.array_equal(obs, expected), f"step {step}: max diff {np.abs(obs - expected).max()}"
        obs, *_ = vec.step(actions_for(step, envs, quadcl.ACT_DIM))


def test_evaluate_gives_quadcl_evals_numbers(root):
    task, episodes, seed = "crash:FL", 8, 3
    rust = eval_json(root, "--task", task, "--episodes", str(episodes), "--seed", str(seed))
    policy = quadcl.load_policy(root / POLICY, task)
    native = quadcl.evaluate(policy, task, episodes=episodes, seed=seed)
    # Through the Python callback path too: the same actions, so the same figures.
    python = quadcl.evaluate(lambda obs: policy(obs), task, episodes=episodes, seed=seed, env_toml=policy.env_toml)
    for key in ("performance", "mean_return", "lin_vel_err", "ang_vel_err", "fall_rate", "survival_s", "episodes"):
        assert native[key] == rust[key], (key, native[key], rust[key])
        assert python[key] == rust[key], (key, python[key], rust[key])
