"""``make_vec``: a batch of quadcl environments as a Gymnasium 1.x ``VectorEnv``,
stepped in Rust in one call with the GIL released (the same batch the Rust
learner trains on: the task's fault, command sampling, the paper's rewards,
pushes and auto-reset as configured).

Auto-reset is Gymnasium's ``SAME_STEP`` mode: a row that ends in a step
returns the next episode's first observation, and the observation it ended
with is ``infos["final_obs"]`` (rows where ``infos["_final_obs"]``).
Finished episodes' figures are ``infos["episode"]`` (``r`` return, ``l``
length in steps, ``performance``, ``lin_vel_err``, ``ang_vel_err``,
``fell``; rows where ``infos["_episode"]``).
"""

import numpy as np
from gymnasium import spaces
from gymnasium.utils import seeding
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from . import _native
from ._checks import RENDER_MODES, as_actions, check_render, closed, seed_of

WIDTH = _native.HISTORY_LEN * _native.OBS_DIM


def env_settings(robot=None, config=None):
    """The ``[env]`` settings (TOML text) of a shipped robot, a URDF file, or a run
    file's or training config's ``[env]`` table."""
    return _native.env_settings(robot, None if config is None else str(config))


class QuadrupedVectorEnv(VectorEnv):
    """N quadcl environments on one task (see the module's docs for the layout)."""

    metadata = {"autoreset_mode": AutoresetMode.SAME_STEP, "render_modes": list(RENDER_MODES), "render_fps": 50}

    def __init__(
        self,
        robot=None,
        task="none",
        num_envs=128,
        seed=0,
        config=None,
        num_threads=None,
        env_toml=None,
        render_mode=None,
        width=480,
        height=360,
    ):
        check_render(render_mode, width, height)
        self.render_mode = render_mode
        self.width, self.height = int(width), int(height)
        if env_toml is not None and (robot is not None or config is not None):
            raise ValueError("give robot, config or env_toml, not several: each sets the [env] settings")
        self.env_toml = env_settings(robot, config) if env_toml is None else str(env_toml)
        # No seed: one drawn from fresh entropy, as Gymnasium does.
        self._np_random, _ = seeding.np_random(None if seed is None else seed_of(seed, None))
        seed = seed_of(seed, self._np_random)
        self._native = _native.NativeVecEnv(self.env_toml, str(task), int(num_envs), seed, num_threads)
        self.num_envs = self._native.num_envs
        self.task = self._native.task
        self.control_dt = self._native.control_dt
        self.metadata = {**self.metadata, "render_fps": round(1.0 / self.control_dt)}
        self.max_episode_return = self._native.max_episode_return
        clip = self._native.clip_actions
        self.single_observation_space = spaces.Box(-np.inf, np.inf, (WIDTH,), np.float32)
        self.single_action_space = spaces.Box(-clip, clip, (_native.ACT_DIM,), np.float32)
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.action_space = batch_space(self.single_action_space, self.num_envs)

    def reset(self, *, seed=None, options=None):
        """Reseeds and resets every environment: env i from (seed, i). Without a seed,
        one is drawn from the generator the last seed set."""
        if options:
            raise ValueError(f"reset takes no options (got {sorted(options)})")
        env = self._env()
        if seed is not None:
            self._np_random, _ = seeding.np_random(seed_of(seed, None))
        obs, privileged = env.reset(seed_of(seed, self._np_random))
        return obs, {"privileged_obs": privileged}

    def step(self, actions):
        env = self._env()
        a = as_actions(actions, (self.num_envs, _native.ACT_DIM))
        obs, rewards, terminated, truncated, privileged, final_obs, episodes = env.step(a)
        infos = {"privileged_obs": privileged}
        if final_obs is not None:
            infos["final_obs"] = final_obs
            infos["_final_obs"] = terminated | truncated
        if episodes:
            infos["episode"], infos["_episode"] = _episode_arrays(episodes, self.num_envs)
        return obs, rewards, terminated, truncated, infos

    def render(self):
        """Every environment as it stands, a tuple of (height, width, 3) uint8 frames
        (``render_mode="rgb_array"``, drawn on the CPU, the batch's threads sharing the
        frames); None without a render mode."""
        env = self._env()
        if self.render_mode is None:
            return None
        return tuple(env.render(self.width, self.height))

    def _env(self):
        if self._native is None:
            raise closed("vector environment")
        return self._native

    def close_extras(self, **kwargs):
        self._native = None


def _episode_arrays(episodes, n):
    keys = ("r", "l", "performance", "lin_vel_err", "ang_vel_err", "fell")
    out = {k: np.zeros(n, dtype=np.bool_ if k == "fell" else (np.int64 if k == "l" else np.float64)) for k in keys}
    mask = np.zeros(n, dtype=np.bool_)
    for e in episodes:
        i = e["env"]
        mask[i] = True
        out["r"][i] = e["return"]
        out["l"][i] = e["steps"]
        for k in keys[2:]:
            out[k][i] = e[k]
    return out, mask


def make_vec(
    robot=None,
    task="none",
    num_envs=128,
    seed=0,
    config=None,
    num_threads=None,
    env_toml=None,
    render_mode=None,
    width=480,
    height=360,
    **kwargs,
):
    """A ``gymnasium.vector.VectorEnv`` of ``num_envs`` quadcl environments on ``task``.

    robot: a shipped robot (``"a1"``, the default; ``"aliengo"``, ``"anymal_c"``) or a URDF
        file; or else ``config``: a run file or training config whose ``[env]`` is used.
    task: ``"none"``, ``"crash:FL"``, ``"invert:RL"``, ``"noise:FR"``, combinations with ``+``.
    seed: env i is seeded from (seed, i), as in the Rust learner.
    num_threads: threads stepping the batch (None: every core, or ``RAYON_NUM_THREADS``; 1: the
        calling thread, in order, with the GIL released).
    env_toml: the ``[env]`` settings as TOML text instead (a ``Policy``'s or a ``Sequence``'s).
    render_mode: None, or ``"rgb_array"``: ``render()`` returns every env's frame of
        ``width`` x ``height`` (about 12 ms a frame at 320 x 240 on one core).
    """
    if kwargs:
        # gymnasium.make_vec passes its own bookkeeping; anything else is a mistake.
        raise TypeError(f"make_vec got unknown arguments {sorted(kwargs)}")
    return QuadrupedVectorEnv(
        robot=robot,
        task=task,
        num_envs=num_envs,
        seed=seed,
        config=config,
        num_threads=num_threads,
        env_toml=env_toml,
        render_mode=render_mode,
        width=width,
        height=height,
    )
