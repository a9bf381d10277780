"""A kinematic hand that renders named poses into Leap-like Hand objects.

Used by the scripted source (and by tests) so synthetic hands carry the same
geometry a real Leap frame does: fingertips, joints, directions, SDK-style flags.
"""
import numpy as np

from .frame import FINGER_NAMES, Finger, Hand, vec3

# Knuckle (MCP) positions in the hand frame, mm: (toward thumb, along palm normal,
# along the hand direction). Finger lengths MCP -> tip in mm.
_MCP = {'thumb': (35.0, 5.0, 5.0), 'index': (25.0, 0.0, 55.0), 'middle': (7.0, 0.0, 60.0),
        'ring': (-11.0, 0.0, 55.0), 'pinky': (-28.0, 0.0, 45.0)}
_LENGTH = {'thumb': 55.0, 'index': 75.0, 'middle': 82.0, 'ring': 77.0, 'pinky': 62.0}
# Extended thumb points out sideways and forward; other fingers along the direction.
_EXTENDED_DIR = {'thumb': (0.8, 0.0, 0.6)}

# pose -> (extended fingers, grab strength, pinch strength, palm normal, direction) with
# orientation given for a right hand held palm-down; None keeps the segment's orientation.
POSES = {
    'open':      ({'thumb', 'index', 'middle', 'ring', 'pinky'}, 0.0, 0.0),
    'fist':      (set(), 1.0, 0.0),
    'thumbs_up': ({'thumb'}, 1.0, 0.0),
    'rock':      ({'thumb', 'index', 'pinky'}, 0.4, 0.1),
    'pinch':     ({'middle', 'ring', 'pinky'}, 0.0, None),   # strength from the value
    'point':     ({'index'}, 0.6, 0.0),
    'two':       ({'index', 'middle'}, 0.5, 0.0),
    'gun':       ({'thumb', 'index'}, 0.5, 0.0),
}
PALM_DOWN = (vec3((0, -1, 0)), vec3((0, 0, -1)))
# Thumbs-up is shown with the palm facing inward and the thumb up.
_THUMBS_UP_NORMAL = {'right': vec3((-1, 0, 0)), 'left': vec3((1, 0, 0))}


def _local_joints(extended):
    """(5, 4, 3) joint positions (mcp, pip, dip, tip) in the hand frame for a pose whose
    `extended` fingers are straight; the others curl (the thumb folds across the palm)."""
    joints = np.empty((5, 4, 3))
    for i, name in enumerate(FINGER_NAMES):
        mcp = np.array(_MCP[name])
        if name in extended:
            d = np.array(_EXTENDED_DIR.get(name, (0.0, 0.0, 1.0)))
            d = d * (_LENGTH[name] / np.linalg.norm(d))
            offsets = (0.45 * d, 0.75 * d, d)
        elif name == 'thumb':
            # Folded across the palm, over the curled fingers.
            offsets = ((-8.0, 12.0, 15.0), (-18.0, 18.0, 25.0), (-30.0, 22.0, 30.0))
        else:
            # Curled: proximal segment bends down, the tip comes back under the palm.
            offsets = ((0.0, 18.0, 22.0), (0.0, 35.0, 12.0), (0.0, 30.0, -8.0))
        joints[i, 0] = mcp
        joints[i, 1:] = mcp + np.array(offsets)
    return joints


_LOCAL_JOINTS = {pose: _local_joints(spec[0]) for pose, spec in POSES.items()}
_PINCH_MEET = np.array([20.0, 38.0, 62.0])    # where thumb and index tips meet, hand frame, mm


def _unit(v):
    n = np.linalg.norm(v)
    return v / n if n > 0 else v


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
    """A Hand of `side` in `pose` with the palm at `palm` (mm).

    pinch_value follows the leapcobot meaning (pinch strength - 0.2, 0..0.8).
    """
    if pose not in POSES:
        raise ValueError('unknown pose %r; known: %s' % (pose, ', '.join(sorted(POSES))))
    extended, grab, pinch = POSES[pose]
    if normal is None or direction is None:
        normal, direction = PALM_DOWN
        if pose == 'thumbs_up':
            normal = _THUMBS_UP_NORMAL[side]
    n = _unit(vec3(normal))
    d = _unit(vec3(direction))
    d = _unit(d - n * np.dot(d, n))
    thumbward = np.cross(d, n) if side == 'right' else -np.cross(d, n)
    basis = np.stack([thumbward, n, d], axis=1)       # columns: hand frame axes in Leap axes
    palm = vec3(palm)
    if pinch is None:
        pinch = 0.2 + float(np.clip(pinch_value, 0.0, 0.8))

    local = _LOCAL_JOINTS[pose]
    if pose == 'pinch':
        # Thumb and index tips meet below the index knuckle, the index curled down to the
        # thumb as on real captures; the gap closes from 30 mm (value 0) to 0 (value 0.8),
        # so every pinch value is a pinch and pinch strength = 0.2 + value round-trips.
        gap = 30.0 * (1.0 - (pinch - 0.2) / 0.8)
        local = local.copy()
        mcp = local[:2, 0]                                  # thumb, index
        tip = _PINCH_MEET + np.array([[gap / 2.0, 0.0, 0.0], [-gap / 2.0, 0.0, 0.0]])
        local[:2, 3] = tip
        local[:2, 2] = (mcp + 2 * tip) / 3.0 + (0.0, 8.0, 0.0)
        local[:2, 1] = (2 * mcp + tip) / 3.0 + (0.0, 6.0, 0.0)

    # Every joint of every finger to Leap axes in one product: (5, 4, 3) = mcp, pip, dip, tip.
    world = local @ basis.T + palm
    tip_dirs = world[:, 3] - world[:, 2]
    tip_dirs /= np.linalg.norm(tip_dirs, axis=1, keepdims=True)
    out = tuple(Finger(tip=w[3], direction=u, extended=name in extended, mcp=w[0], pip=w[1],
                       dip=w[2])
                for name, w, u in zip(FINGER_NAMES, world, tip_dirs))
    return Hand(side=side, palm_position=palm, palm_velocity=vec3(velocity),
                palm_normal=n, direction=d, grab_strength=float(grab),
                pinch_strength=float(pinch), confidence=float(confidence),
                fingers=out, id=hand_id if hand_id is not None else (1 if side == 'right' else 2))
