"""Checks of what Python hands to the simulator: clear exceptions before any
environment steps, so a bad call changes nothing."""

import numpy as np


def as_actions(actions, shape):
    """``actions`` as a C-contiguous float32 array of ``shape``; a non-float dtype
    is a TypeError, a wrong shape or a non-finite value a ValueError."""
    a = np.asarray(actions)
    if not (np.issubdtype(a.dtype, np.floating)):
        raise TypeError(f"actions must be a floating-point array, got dtype {a.dtype}")
    if a.shape != tuple(shape):
        raise ValueError(f"actions of shape {a.shape}: expected {tuple(shape)}")
    a = np.ascontiguousarray(a, dtype=np.float32)
    bad = ~np.isfinite(a)
    if bad.any():
        index = tuple(int(i) for i in np.argwhere(bad)[0])
        raise ValueError(f"actions must be finite: actions{list(index)} is {a[index]} (nothing was stepped)")
    return a


def seed_of(seed, np_random):
    """An explicit seed as given (a non-negative int), else one drawn from ``np_random``."""
    if seed is None:
        return int(np_random.integers(0, 2**63 - 1))
    if isinstance(seed, (bool, np.bool_)) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ValueError(f"seed must be a non-negative integer, got {seed!r}")
    return int(seed)


RENDER_MODES = ("rgb_array",)


def check_render(render_mode, width, height):
    """``render_mode`` None or one of ``RENDER_MODES``, and a picture size of positive ints."""
    if render_mode is not None and render_mode not in RENDER_MODES:
        raise ValueError(
            f"render_mode {render_mode!r} is not supported: quadcl renders {list(RENDER_MODES)} "
            "(frames as (height, width, 3) uint8, drawn on the CPU) or None"
        )
    for name, v in (("width", width), ("height", height)):
        if isinstance(v, (bool, np.bool_)) or not isinstance(v, (int, np.integer)) or v < 1:
            raise ValueError(f"{name} must be a positive integer, got {v!r}")


def closed(what):
    """The error of a call on a closed environment."""
    return RuntimeError(f"this {what} is closed: make a new one to step, reset or render again")
