"""One quadcl environment as a ``gymnasium.Env`` (registered as
``quadcl/Quadruped-v0``): a batch of one, so it is the very environment
``make_vec`` steps. An episode ends by a fall (terminated) or at the
configured length (truncated); call ``reset`` then, as Gymnasium expects."""

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from . import _native
from ._checks import RENDER_MODES, as_actions, check_render, closed, seed_of
from .vector import WIDTH, env_settings


class QuadrupedEnv(gym.Env):
    """A single quadcl environment: observation (225,) float32, action (12,) float32.

    render_mode: None, or ``"rgb_array"``: ``render()`` returns the robot as it stands,
    (height, width, 3) uint8, drawn on the CPU from a tracking camera (``quadcl record``'s).
    """

    metadata = {"render_modes": list(RENDER_MODES), "render_fps": 50}

    def __init__(self, robot=None, task="none", config=None, render_mode=None, width=480, height=360):
        check_render(render_mode, width, height)
        self.render_mode = render_mode
        self.width, self.height = int(width), int(height)
        self.env_toml = env_settings(robot, config)
        self._native = _native.NativeVecEnv(self.env_toml, str(task), 1, 0, 1)
        self.task = self._native.task
        self.metadata = {**self.metadata, "render_fps": round(1.0 / self._native.control_dt)}
        clip = self._native.clip_actions
        self.observation_space = spaces.Box(-np.inf, np.inf, (WIDTH,), np.float32)
        self.action_space = spaces.Box(-clip, clip, (_native.ACT_DIM,), np.float32)

    def _env(self):
        if self._native is None:
            raise closed("environment")
        return self._native

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        if options:
            raise ValueError(f"reset takes no options (got {sorted(options)})")
        obs, privileged = self._env().reset(seed_of(seed, self.np_random))
        return obs[0], {"privileged_obs": privileged[0]}

    def step(self, action):
        env = self._env()
        a = as_actions(action, (_native.ACT_DIM,))
        obs, rewards, terminated, truncated, privileged, final_obs, episodes = env.step(a[None, :])
        info = {"privileged_obs": privileged[0]}
        if episodes:
            e = episodes[0]
            info["episode"] = {"r": e["return"], "l": e["steps"], **{k: e[k] for k in ("performance", "lin_vel_err", "ang_vel_err", "fell")}}
        return (obs if final_obs is None else final_obs)[0], float(rewards[0]), bool(terminated[0]), bool(truncated[0]), info

    def render(self):
        """The robot as it stands, (height, width, 3) uint8 (``render_mode="rgb_array"``); None
        without a render mode, as Gymnasium's environments do."""
        env = self._env()
        if self.render_mode is None:
            return None
        return env.render(self.width, self.height, [0])[0]

    def close(self):
        self._native = None
