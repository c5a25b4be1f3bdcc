"""Learned policies from Python, and quadcl's own evaluation of any policy.

``load_policy(path, task)`` recalls a task of a policy directory (every form
``quadcl eval --policy`` takes) through the Rust masked network: calling it on
observations gives the action means the Rust recall gives, bit for bit.
``evaluate(policy, task)`` runs one episode per environment and returns the
figures ``quadcl eval --json`` prints and ``metrics.json`` keeps, so a method
written in Python is scored exactly as the Rust ones."""

import numpy as np

from . import _native
from .vector import WIDTH, env_settings


class Policy:
    """A learned task's deterministic policy: (N, 225) or (225,) float32 observations
    to (N, 12) or (12,) action means.

    ``task`` is the task asked for; ``recalls`` the learned task whose network acts: the same
    task when the policy learned it, else (zero-shot: a base policy on a perturbation, a
    checkpoint from before the task) its last learned task."""

    def __init__(self, path, task):
        self._native = _native.NativePolicy(str(path), str(task))
        self.path = self._native.path
        self.task = self._native.task
        self.recalls = self._native.recalls
        self.tasks = self._native.tasks
        self.env_toml = self._native.env_toml

    def __call__(self, obs):
        x = np.asarray(obs)
        if not np.issubdtype(x.dtype, np.floating):
            raise TypeError(f"observations must be a floating-point array, got dtype {x.dtype}")
        single = x.ndim == 1
        x = np.ascontiguousarray(x[None, :] if single else x, dtype=np.float32)
        if x.ndim != 2 or x.shape[1] != WIDTH:
            raise ValueError(f"observations of shape {np.shape(obs)}: a policy takes (N, {WIDTH}) or ({WIDTH},)")
        actions = self._native.act(x)
        return actions[0] if single else actions

    def __repr__(self):
        return f"Policy({self.path!r}, task={self.task!r}, recalls={self.recalls!r}, tasks={self.tasks})"


def load_policy(path, task):
    """The policy that ``path`` (a policy directory or a run's checkpoint) learned for ``task``;
    for a task it never learned, its last learned task's (``Policy.recalls`` names it)."""
    return Policy(path, task)


def evaluate(policy, task, episodes=32, seed=0, robot=None, config=None, env_toml=None):
    """One episode on each of ``episodes`` environments of ``task``, seeded from ``seed``,
    acting with ``policy``: a :class:`Policy` (run in Rust) or any callable from
    observations (N, 225) float32 to actions (N, 12). The environment settings are the
    policy's own for a :class:`Policy`, else those of ``robot``, ``config`` or ``env_toml``
    (the ``[env]`` settings as TOML text, e.g. a Policy's); default the A1's.

    Returns a dict: performance (mean return over the largest possible), mean_return,
    return_std, lin_vel_err, ang_vel_err, fall_rate, survival_s, episodes, seed, task,
    physics_resets: the figures of ``quadcl eval --json``."""
    if env_toml is not None and (robot is not None or config is not None):
        raise ValueError("give robot, config or env_toml, not several: each sets the [env] settings")
    if env_toml is None and (robot is not None or config is not None or not isinstance(policy, Policy)):
        env_toml = env_settings(robot, config)
    if isinstance(policy, Policy):
        return _native.evaluate(policy._native, str(task), int(episodes), int(seed), env_toml)
    if not callable(policy):
        raise TypeError(f"policy must be a quadcl Policy or a callable, got {type(policy).__name__}")
    return _native.evaluate(policy, str(task), int(episodes), int(seed), env_toml)
