"""The examples under examples/python run as their docstrings say, so they do
not rot: the shipped policy's script scores every task the policy recalls,
and the CleanRL-style PPO trains, evaluates and exports (where PyTorch is
installed; CI does not install it)."""

import subprocess
import sys

import pytest

import quadcl

SHIPPED = "policies/sequence-a1-adapter/checkpoints/step-03-crash_FR"


def run_example(root, name, *args):
    return subprocess.run([sys.executable, str(root / "examples/python" / name), *args], cwd=root, check=True,
                          capture_output=True, text=True, timeout=600).stdout


def test_the_shipped_policy_example_scores_every_task_it_recalls(root):
    out = run_example(root, "eval_shipped.py", "--episodes", "2")
    rows = {line.split()[0]: line.split()[1:] for line in out.splitlines()[2:] if line and not line.startswith(("task", SHIPPED))}
    tasks = quadcl.load_policy(root / SHIPPED, "none").tasks
    assert set(tasks) <= set(rows), out
    for task in tasks:
        performance, fall_rate = float(rows[task][0]), float(rows[task][1])
        assert 0.0 < performance <= 1.0 and 0.0 <= fall_rate <= 1.0, (task, rows[task])
    assert f"{tasks[-1]}, stepped by hand: returns" in out


def test_the_cleanrl_example_trains_evaluates_and_exports_its_actor(root, tmp_path):
    torch = pytest.importorskip("torch")
    saved = tmp_path / "actor.pt"
    out = run_example(root, "ppo_cleanrl.py", "--iterations", "2", "--envs", "8", "--steps", "8", "--log-every", "1",
                      "--threads", "1", "--save", str(saved))
    assert "iteration     2" in out and "evaluation: {'task': 'none', 'episodes': 32" in out, out
    actor = torch.jit.load(str(saved))
    actions = actor(torch.zeros((3, quadcl.HISTORY_LEN * quadcl.OBS_DIM)))
    assert tuple(actions.shape) == (3, quadcl.ACT_DIM) and bool(torch.isfinite(actions).all())
