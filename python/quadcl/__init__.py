"""quadcl from Python: the simulated quadruped's continual-learning tasks as
Gymnasium environments, its run files' sequences, and learned policies scored
exactly as ``quadcl eval`` and ``metrics.json`` score them.

    import quadcl
    envs = quadcl.make_vec(robot="a1", task="crash:FL", num_envs=128, seed=0)
    obs, infos = envs.reset(seed=0)                 # obs (128, 225) float32
    obs, rew, term, trunc, infos = envs.step(actions)  # actions (128, 12)

An observation is the environment's history of its last ``HISTORY_LEN``
observations of ``OBS_DIM`` values, oldest first: the last ``OBS_DIM`` columns
are the current observation. ``infos["privileged_obs"]`` holds what the Rust
learner's critic and context estimator read. See docs/python.md.
"""

from . import _native
from ._native import ACT_DIM, HISTORY_LEN, OBS_DIM, PRIV_OBS_DIM, SHIPPED_ROBOTS, __version__
from .env import QuadrupedEnv
from .policy import Policy, evaluate, load_policy
from .sequence import Sequence, SequenceTask
from .vector import QuadrupedVectorEnv, make_vec

__all__ = [
    "ACT_DIM",
    "HISTORY_LEN",
    "OBS_DIM",
    "PRIV_OBS_DIM",
    "SHIPPED_ROBOTS",
    "Policy",
    "QuadrupedEnv",
    "QuadrupedVectorEnv",
    "Sequence",
    "SequenceTask",
    "evaluate",
    "load_policy",
    "make_vec",
    "task_name",
    "__version__",
]

task_name = _native.task_name


def _register():
    import gymnasium

    if "quadcl/Quadruped-v0" not in gymnasium.registry:
        gymnasium.register(
            id="quadcl/Quadruped-v0",
            entry_point="quadcl.env:QuadrupedEnv",
            vector_entry_point="quadcl.vector:make_vec",
        )


_register()
