"""A kinematic hand that renders named poses into Leap-like TrackedHand objects.

Used by the scripted source (and by tests) so synthetic hands carry the same
geometry a real Leap frame does: fingertips, joints, directions, SDK-style flags.
"""
import functools
import math

import numpy as np

from leap_teleop.hands.frame import FINGER_NAMES, Finger, TrackedHand, vec3
from leap_teleop.vectors import cross3

# pose -> (extended fingers, grab strength, pinch strength): the SDK-style flags.
POSES = {
    'open':      ({'thumb', 'index', 'middle', 'ring', 'pinky'}, 0.0, 0.0),
    'fist':      (set(), 1.0, 0.0),
    'thumbs_up': ({'thumb'}, 1.0, 0.0),
    'rock':      ({'index', 'pinky'}, 0.4, 0.1),
    'pinch':     ({'middle', 'ring', 'pinky'}, 0.0, None),   # strength from the value
    'point':     ({'index'}, 0.6, 0.0),
    'two':       ({'index', 'middle'}, 0.5, 0.0),
    'gun':       ({'thumb', 'index'}, 0.5, 0.0),
}
PALM_DOWN = (vec3((0, -1, 0)), vec3((0, 0, -1)))
# Thumbs-up is shown with the palm facing inward and the thumb up.
_THUMBS_UP_NORMAL = {'right': vec3((-1, 0, 0)), 'left': vec3((1, 0, 0))}

# Joint positions (mcp, pip, dip, tip) of each finger, thumb..pinky, in the hand frame
# (toward the thumb, along the palm normal, along the hand direction), mm from the palm
# centre, for a hand 53 mm across the knuckles: the median hand of each pose over the
# real Leap captures of 12 people (GTI-UPM static poses; thumbs-up: their fist with the
# thumb out; gun: their L), so that scripted hands look like people's to the pose model.
_K = ((17.1, 5.3, -46.9), (20.5, -1.8, 20.4), (2.5, -3.5, 20.5), (-15.4, -3.5, 15.2),
      (-31.2, 0.0, 8.6))
_CURLED = {'thumb': ((33.9, 19.7, -12.5), (33.4, 32.6, 10.8), (25.2, 38.5, 19.9)),
           'index': ((20.4, 33.3, 20.1), (17.6, 35.4, 0.8), (16.2, 30.2, -8.2)),
           'middle': ((8.3, 35.4, 19.7), (8.5, 37.4, -3.3), (7.6, 31.4, -13.4)),
           'ring': ((-8.1, 32.2, 15.4), (-4.4, 34.0, -6.8), (-4.1, 27.9, -16.8)),
           'pinky': ((-22.1, 27.1, 11.9), (-17.0, 29.0, -2.8), (-16.0, 24.5, -12.2))}
_STRAIGHT = {'thumb': ((42.4, 7.1, -15.8), (61.6, 8.0, 3.3), (75.1, 5.7, 9.0)),
             'index': ((28.5, -5.7, 53.3), (33.1, -6.4, 72.1), (35.9, -5.9, 82.3)),
             'middle': ((1.3, -8.6, 59.0), (0.8, -9.9, 81.9), (0.7, -9.6, 93.5)),
             'ring': ((-24.3, -7.1, 49.7), (-29.5, -7.8, 71.3), (-32.1, -7.3, 82.6)),
             'pinky': ((-48.3, -2.0, 31.3), (-57.3, -1.5, 44.0), (-63.1, -0.3, 52.6))}
# Fingers whose shape differs from both in a pose (a finger alone out points ahead).
_SHAPED = {
    # (the thumb: the captures' knuckle, then a thumb raised 40 deg ahead of the thumb
    # side, as the real thumbs-up takes hold it)
    'thumbs_up': {'thumb': ((37.9, 10.0, -13.0), (50.7, 12.5, -2.1), (60.5, 14.4, 6.2)),
                  'index': ((20.8, 31.7, 31.0), (19.3, 44.7, 20.6), (18.5, 48.5, 11.5)),
                  'middle': ((7.7, 33.8, 32.1), (9.9, 49.2, 19.7), (10.5, 53.2, 10.6)),
                  'ring': ((-10.3, 30.1, 28.6), (-5.3, 46.1, 18.7), (-3.4, 50.4, 10.1)),
                  'pinky': ((-25.2, 25.2, 21.4), (-19.1, 35.9, 15.6), (-15.7, 39.8, 9.2))},
    'rock': {'thumb': ((18.1, 22.2, -10.4), (10.6, 35.9, 11.1), (0.6, 41.8, 17.0)),
             'index': ((20.5, 1.4, 54.8), (20.1, 10.0, 72.2), (20.0, 15.5, 81.5)),
             'middle': ((8.0, 34.5, 29.2), (9.3, 42.6, 8.3), (8.9, 39.8, -2.6)),
             'ring': ((-9.6, 31.5, 23.9), (-4.8, 39.4, 4.3), (-3.9, 36.7, -6.6)),
             'pinky': ((-38.4, 10.3, 33.6), (-41.0, 18.7, 46.5), (-41.6, 25.3, 54.5))},
    'pinch': {'thumb': ((30.6, 24.4, -14.3), (33.0, 39.4, 8.0), (30.0, 46.6, 18.4)),
              'index': ((22.9, 28.4, 38.0), (20.7, 41.1, 25.4), (18.9, 41.6, 14.8)),
              'middle': ((4.1, 6.3, 58.1), (5.9, 16.8, 78.8), (7.1, 23.1, 88.2)),
              'ring': ((-16.8, 1.9, 50.3), (-16.9, 8.0, 71.4), (-16.8, 12.2, 82.1)),
              'pinky': ((-35.4, -0.2, 36.0), (-36.7, 1.6, 50.9), (-37.1, 3.7, 60.8))},
    'point': {'index': ((18.9, 4.0, 54.8), (18.1, 10.7, 73.3), (17.5, 15.5, 82.8)),
              'thumb': ((26.0, 21.3, -11.3), (21.1, 34.7, 11.8), (10.2, 41.2, 18.6))},
    'two': {'index': ((28.3, 1.2, 54.0), (32.7, 4.1, 72.7), (35.0, 6.1, 82.7)),
            'middle': ((-5.7, 1.7, 58.3), (-10.3, 6.3, 80.3), (-12.5, 9.2, 91.4)),
            'thumb': ((16.1, 21.4, -9.8), (8.6, 34.3, 12.4), (0.3, 40.7, 20.1))},
    'gun': {'thumb': ((39.8, 5.3, -14.1), (59.2, 3.0, 5.1), (71.1, -0.2, 10.1)),
            'index': ((18.7, 6.0, 54.3), (17.6, 13.3, 72.3), (17.0, 18.5, 81.8))},
}


def _local_joints(pose):
    """(5, 4, 3) joint positions (mcp, pip, dip, tip) in the hand frame for a pose."""
    extended = POSES[pose][0]
    joints = np.empty((5, 4, 3))
    for i, name in enumerate(FINGER_NAMES):
        rest = _SHAPED.get(pose, {}).get(name) or (
            _STRAIGHT[name] if name in extended else _CURLED[name])
        joints[i, 0] = _K[i]
        joints[i, 1:] = rest
    return joints


_LOCAL_JOINTS = {pose: _local_joints(pose) for pose in POSES}
# The OK sign's thumb and index tips (above) meet here; the scripted pinch value moves
# them apart by up to PINCH_GAP_MM.
_PINCH_MEET = np.array([24.5, 44.1, 16.6])
PINCH_GAP_MM = 12.0


@functools.lru_cache(maxsize=64)
def _pinch_joints(pinch):
    """The pinch pose's joints (as _local_joints) at this pinch strength, once per value."""
    # Thumb and index tips meet as in a real OK sign; the gap closes from PINCH_GAP_MM
    # (value 0) to 0 (value 0.8), so every pinch value is a pinch and pinch strength =
    # 0.2 + value round-trips.
    gap = PINCH_GAP_MM * (1.0 - (pinch - 0.2) / 0.8)
    local = _LOCAL_JOINTS['pinch'].copy()
    shift = np.array([[gap / 2.0, 0.0, 0.0], [-gap / 2.0, 0.0, 0.0]]) \
        + (_PINCH_MEET - 0.5 * (local[0, 3] + local[1, 3]))
    local[:2, 1:] += shift[:, None, :]
    local.flags.writeable = False
    return local


def _unit(v):
    """The 3 floats v scaled to length 1; v itself when it has no direction."""
    x, y, z = v
    length = math.sqrt(x * x + y * y + z * z)
    if length > 1e-9:
        return (x / length, y / length, z / length)
    return v


def rpy_to_basis(roll, pitch, yaw, side):
    """Palm normal and hand direction after rotating the palm-down pose by Leap-SDK
    style roll (about -z), pitch (about x), yaw (about y), radians."""
    from math import cos, sin
    rz = np.array([[cos(-roll), -sin(-roll), 0], [sin(-roll), cos(-roll), 0], [0, 0, 1]])
    rx = np.array([[1, 0, 0], [0, cos(pitch), -sin(pitch)], [0, sin(pitch), cos(pitch)]])
    ry = np.array([[cos(-yaw), 0, sin(-yaw)], [0, 1, 0], [-sin(-yaw), 0, cos(-yaw)]])
    r = ry @ rx @ rz
    return r @ PALM_DOWN[0], r @ PALM_DOWN[1]


def render_hand(side, pose, palm, normal=None, direction=None, pinch_value=0.0,
                velocity=None, confidence=1.0, hand_id=None):
    """A TrackedHand of `side` in `pose` with the palm at `palm` (mm).

    pinch_value follows the leapcobot meaning (pinch strength - 0.2, 0..0.8).
    """
    if pose not in POSES:
        raise ValueError('unknown pose %r; known: %s' % (pose, ', '.join(sorted(POSES))))
    extended, grab, pinch = POSES[pose]
    if normal is None or direction is None:
        normal, direction = PALM_DOWN
        if pose == 'thumbs_up':
            normal = _THUMBS_UP_NORMAL[side]
    # The hand frame in plain floats (a scripted source renders every frame): numpy's
    # arithmetic, in its order, without its per-call cost on 3-vectors.
    n = _unit(vec3(normal).tolist())
    d = _unit(vec3(direction).tolist())
    along = d[0] * n[0] + d[1] * n[1] + d[2] * n[2]
    d = _unit((d[0] - n[0] * along, d[1] - n[1] * along, d[2] - n[2] * along))
    t = cross3(d, n)
    if side != 'right':
        t = (-t[0], -t[1], -t[2])
    # columns: hand frame axes (thumbward, normal, direction) in Leap axes
    basis = np.array([[t[0], n[0], d[0]], [t[1], n[1], d[1]], [t[2], n[2], d[2]]])
    n, d = np.array(n), np.array(d)
    palm = vec3(palm)
    if pinch is None:
        pinch = 0.2 + float(np.clip(pinch_value, 0.0, 0.8))

    local = _pinch_joints(pinch) if pose == 'pinch' else _LOCAL_JOINTS[pose]

    # Every joint of every finger to Leap axes in one product: (5, 4, 3) = mcp, pip, dip, tip.
    world = local @ basis.T + palm
    tip_dirs = world[:, 3] - world[:, 2]
    tip_dirs /= np.linalg.norm(tip_dirs, axis=1, keepdims=True)
    out = tuple(Finger(tip=w[3], direction=u, extended=name in extended, mcp=w[0], pip=w[1],
                       dip=w[2])
                for name, w, u in zip(FINGER_NAMES, world, tip_dirs))
    return TrackedHand(side=side, palm_position=palm, palm_velocity=vec3(velocity),
                palm_normal=n, direction=d, grab_strength=float(grab),
                pinch_strength=float(pinch), confidence=float(confidence),
                fingers=out, id=hand_id if hand_id is not None else (1 if side == 'right' else 2))
