"""Bones from the joints a hand source tracks, in the Leap SDK's bone model, and
the bounds of a source's joints and sizes. Pure numpy.

Every finger has four bones, wrist to tip: metacarpal, proximal, intermediate, distal. A
frame.Finger carries the knuckle (mcp), pip, dip and tip joints, so the proximal,
intermediate and distal bones are known; the metacarpal runs from the carpal joint where the
source measures it (the Leap SDKs, LeapJS recordings), else it is reported with its start at
its end (the knuckle) and length 0 (the Leap's own thumb metacarpal has length 0 too). Units
follow the input (frames: millimetres).

A joint or size beyond its bound (MAX_JOINT, MAX_SIZE, MAX_TIME_VISIBLE_S) is a tracking
error or a corrupt recording's value, not a hand: none, and never a message's float32.
"""
import numpy as np

from leap_teleop.hands.frame import measured, measured3

BONE_NAMES = ('metacarpal', 'proximal', 'intermediate', 'distal')
FINGER_JOINT_NAMES = ('mcp', 'pip', 'dip', 'tip')
# mm from the device: the tracker's bound of a palm (tracker.MAX_PALM_MM, kept equal by a
# test; the recording reader imports this, not the tracker's gesture models). leapros and
# the driver's Human both take a joint beyond it for none.
MAX_JOINT = 2000.0
MAX_SIZE = MAX_JOINT            # mm: a palm, finger or bone width, a sphere's radius
MAX_TIME_VISIBLE_S = 1e7        # s a hand is tracked (116 days)


def hand_joints(hand):
    """(5, 4, 3) float array: each finger's mcp, pip, dip, tip (FINGER_NAMES order); None
    unless the hand has five fingers with every joint known and finite."""
    if len(hand.fingers) < 5:
        return None
    try:
        joints = np.array([[getattr(f, name) for name in FINGER_JOINT_NAMES] for f in hand.fingers[:5]],
                          dtype=float)
    except (TypeError, ValueError):     # a joint is None or not a 3-vector
        return None
    # Beyond the tracking volume (and far inside float32, which bone messages carry: a joint
    # of 1e300 ended the sender).
    if joints.shape != (5, 4, 3) or not np.all(np.abs(joints) <= MAX_JOINT):
        return None
    return joints


def hand_carpals(hand, joints):
    """(5, 3) float array: each finger's carpal joint where its source measured one within
    MAX_JOINT, else its knuckle (from `joints`, hand_joints' array), so that metacarpal has
    length 0 as before."""
    out = np.array(joints[:, 0, :], dtype=float)
    for i, f in enumerate(hand.fingers[:5]):
        carpal = bounded_point(getattr(f, 'carpal', None))
        if carpal is not None:
            out[i] = carpal
    return out


def bone_ends(joints, carpals=None):
    """(starts, ends), each (..., 4, 3): the four bones (BONE_NAMES order) of fingers given
    as (..., 4, 3) joints (mcp, pip, dip, tip). The metacarpal starts at `carpals` ((..., 3),
    hand_carpals') when given, else at the mcp (length 0); it ends at the mcp."""
    joints = np.asarray(joints, dtype=float)
    starts = joints[..., [0, 0, 1, 2], :]
    if carpals is not None:
        starts[..., 0, :] = np.asarray(carpals, dtype=float)
    return starts, joints[..., [0, 1, 2, 3], :]


def bounded_size(value):
    """A source's size (mm) as a float; None when absent or not a number in [0, MAX_SIZE]."""
    x = measured(value)
    return x if x is not None and x <= MAX_SIZE else None


def bounded_point(value):
    """A source's 3-vector (mm) as a float (3,) array; None when absent, not finite or
    beyond MAX_JOINT on an axis."""
    v = measured3(value)
    return v if v is not None and np.all(np.abs(v) <= MAX_JOINT) else None


def bounded_time(value):
    """A source's time visible (s) as a float; None when absent or not in
    [0, MAX_TIME_VISIBLE_S]."""
    x = measured(value)
    return x if x is not None and x <= MAX_TIME_VISIBLE_S else None
