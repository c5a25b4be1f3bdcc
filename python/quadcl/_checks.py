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
