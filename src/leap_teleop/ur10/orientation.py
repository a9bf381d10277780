"""Hand rotation since the origin -> tool orientation (numpy only).

The leapcobot messages carry the hand's rotation since the origin as three angles,
measured as the Leap SDK measures roll, yaw and pitch (hands.tracker.hand_angles):
rotate (about z, from the palm normal), turn (about y, from the hand direction) and
swing (about x, from the hand direction). hand_rotation() rebuilds the rotation matrix
whose palm normal and direction give exactly these angles from a flat hand pointing
away from the user; everything after that (filtering, mapping, limits) works on
rotation matrices and rotation vectors, never on the angles.
"""
import math

import numpy as np

from leap_teleop.ur10 import kinematics as kin

# A flat hand pointing away from the user: palm normal down, direction -z (Leap axes).
_NEUTRAL = np.array([[-1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, -1.0]]).T   # columns


def _basis(normal, direction):
    return np.stack([np.cross(normal, direction), normal, direction], axis=1)


def hand_rotation(rotate, turn, swing):
    """Rotation (3x3, Leap axes) taking the neutral hand to one whose roll, yaw and
    pitch are rotate, turn and swing (rad)."""
    cy, sy, cp, sp = math.cos(turn), math.sin(turn), math.cos(swing), math.sin(swing)
    d = np.array([sy * cp, sp * cy, -cy * cp])
    d /= np.linalg.norm(d)
    # The normal lies in the plane normal to d and in the vertical plane through the
    # roll direction (sin r, -cos r, 0), the plane with normal m.
    n_roll = np.array([math.sin(rotate), -math.cos(rotate), 0.0])
    m = np.array([-math.cos(rotate), -math.sin(rotate), 0.0])
    n = np.cross(d, m)
    norm = float(np.linalg.norm(n))
    if norm < 1e-9:                     # the hand points along m: roll undefined
        n = n_roll - d * float(n_roll @ d)
        norm = float(np.linalg.norm(n))
    n /= norm
    if n @ n_roll < 0:
        n = -n
    return _basis(n, d) @ _basis(_NEUTRAL[:, 1], _NEUTRAL[:, 2]).T


def axis_rotation(axis_map):
    """The orthogonal part of an axis map (polar decomposition): mapping a rotation R
    of the hand to A R A^T turns it about the mapped axes, whatever the map's scale."""
    u, _, vt = np.linalg.svd(np.asarray(axis_map, dtype=float))
    return u @ vt


def map_rotation(R_leap, A):
    """A hand rotation (Leap axes) as a rotation about the arm base's axes."""
    return A @ R_leap @ A.T


def scale_rotation(R, scale):
    return kin.rotation_from_vector(kin.rotation_vector(R) * scale)
