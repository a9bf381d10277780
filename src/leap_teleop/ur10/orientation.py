"""Hand rotation since the origin -> tool orientation (numpy only).

The leapcobot messages carry the hand's rotation since the origin as three angles,
measured as the Leap SDK measures roll, yaw and pitch (hands.tracker.hand_angles):
rotate (about z, from the palm normal), turn (about y, from the hand direction) and
swing (about x, from the hand direction). hand_rotation() rebuilds the rotation matrix
whose palm normal and direction give exactly these angles from a flat hand pointing
away from the user; everything after that (filtering, mapping, limits) works on
rotation matrices and rotation vectors, never on the angles.
"""
import functools
import math

import numpy as np

from leap_teleop.vectors import cross3, norm3

# A flat hand pointing away from the user: palm normal down, direction -z (Leap axes).
_NEUTRAL = np.array([[-1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, -1.0]]).T   # columns


def _basis(normal, direction):
    return np.stack([np.cross(normal, direction), normal, direction], axis=1)


_NEUTRAL_BASIS_T = _basis(_NEUTRAL[:, 1], _NEUTRAL[:, 2]).T


def hand_rotation(rotate, turn, swing):
    """Rotation (3x3, Leap axes) taking the neutral hand to one whose roll, yaw and
    pitch are rotate, turn and swing (rad)."""
    # Plain floats (the arm runs this every control period): numpy's arithmetic, in its
    # order, without its per-call cost on 3-vectors.
    cy, sy, cp, sp = math.cos(turn), math.sin(turn), math.cos(swing), math.sin(swing)
    # Yaw and pitch both measure from -z: past the vertical (the fingers pointing back at
    # the user) both pass pi/2 and the direction's z changes sign with cos(pitch).
    d = (sy * cp, sp * cy, -cy * cp) if cp >= 0.0 else (-sy * cp, -sp * cy, cy * cp)
    d_norm = norm3(d)
    d = (d[0] / d_norm, d[1] / d_norm, d[2] / d_norm)
    # The normal lies in the plane normal to d and in the vertical plane through the
    # roll direction (sin r, -cos r, 0), the plane with normal m.
    n_roll = (math.sin(rotate), -math.cos(rotate), 0.0)
    m = (-math.cos(rotate), -math.sin(rotate), 0.0)
    n = cross3(d, m)
    norm = norm3(n)
    if norm < 1e-9:                     # the hand points along m: roll undefined
        along = n_roll[0] * d[0] + n_roll[1] * d[1] + n_roll[2] * d[2]
        n = (n_roll[0] - d[0] * along, n_roll[1] - d[1] * along, n_roll[2] - d[2] * along)
        norm = norm3(n)
    n = (n[0] / norm, n[1] / norm, n[2] / norm)
    if n[0] * n_roll[0] + n[1] * n_roll[1] + n[2] * n_roll[2] < 0:
        n = (-n[0], -n[1], -n[2])
    c = cross3(n, d)
    basis = np.array([[c[0], n[0], d[0]], [c[1], n[1], d[1]], [c[2], n[2], d[2]]])
    return basis @ _NEUTRAL_BASIS_T


def axis_rotation(axis_map):
    """The orthogonal part of an axis map (polar decomposition): mapping a rotation R
    of the hand to A R A^T turns it about the mapped axes, whatever the map's scale."""
    a = np.asarray(axis_map, dtype=float)
    return _axis_rotation(a.tobytes(), a.shape).copy()


@functools.lru_cache(maxsize=32)
def _axis_rotation(data, shape):
    """axis_rotation of the map with these bytes, once per map (every ArmTeleop takes it,
    and the SVD costs more than the rest of a construction)."""
    u, _, vt = np.linalg.svd(np.frombuffer(data).reshape(shape).copy())
    return u @ vt


def axis_map_rank(axis_map):
    """np.linalg.matrix_rank of an axis map, once per map (every validation checks it)."""
    a = np.asarray(axis_map, dtype=float)
    return _rank(a.tobytes(), a.shape)


@functools.lru_cache(maxsize=32)
def _rank(data, shape):
    return int(np.linalg.matrix_rank(np.frombuffer(data).reshape(shape).copy()))


def map_rotation(R_leap, A):
    """A hand rotation (Leap axes) as a rotation about the arm base's axes."""
    return A @ R_leap @ A.T
