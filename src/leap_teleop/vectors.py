"""Small numeric helpers every level shares: angle wrapping and unit vectors (numpy only)."""
import math

import numpy as np


def wrap_angle(a):
    """`a` (rad) brought into [-pi, pi)."""
    return (a + math.pi) % (2.0 * math.pi) - math.pi


def unit(v, fallback=None):
    """`v` scaled to length 1; `fallback` (default: NaNs, which the callers reject as an
    unusable hand) when `v` has no direction."""
    n = float(np.linalg.norm(v))
    if n > 1e-9:
        return v / n
    return np.full(np.shape(v), np.nan) if fallback is None else fallback
