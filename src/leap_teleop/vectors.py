"""Small numeric helpers every level shares: angle wrapping, unit vectors and URDF
rotations (numpy only).

The 3-vector helpers do plain float arithmetic, in the order numpy does it, so they give
the same floats as np.cross / np.linalg.norm at a fraction of their per-call cost (which
dominates on 3 numbers)."""
import math

import numpy as np


def wrap_angle(a):
    """`a` (rad) brought into [-pi, pi)."""
    return (a + math.pi) % (2.0 * math.pi) - math.pi


def norm3(v):
    """|v| of a 3-vector (any sequence of 3 numbers): np.linalg.norm's float."""
    x, y, z = v
    return math.sqrt(x * x + y * y + z * z)


def cross3(a, b):
    """a x b of two 3-vectors as a tuple of floats: np.cross's values."""
    a0, a1, a2 = a
    b0, b1, b2 = b
    return (a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0)


def unit(v, fallback=None):
    """`v` scaled to length 1; `fallback` (default: NaNs, which the callers reject as an
    unusable hand) when `v` has no direction."""
    if v.__class__ is np.ndarray and v.shape == (3,) and v.dtype == np.float64:
        n = norm3(v.tolist())
    else:
        n = float(np.linalg.norm(v))
    if n > 1e-9:
        return v / n
    return np.full(np.shape(v), np.nan) if fallback is None else fallback


def rpy_matrix(roll, pitch, yaw):
    """The rotation of URDF / ROS roll, pitch, yaw, Rz(yaw) Ry(pitch) Rx(roll), as a
    row-major 9-tuple of floats (cheap in a physics loop; np.reshape(.., (3, 3)) for a
    matrix)."""
    cr, sr, cp, sp, cy, sy = (math.cos(roll), math.sin(roll), math.cos(pitch),
                              math.sin(pitch), math.cos(yaw), math.sin(yaw))
    return (cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr,
            sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr,
            -sp, cp * sr, cp * cr)
