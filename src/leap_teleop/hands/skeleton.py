"""Bones from the joints a hand source tracks, in the Leap SDK's bone model. Pure numpy.

Every finger has four bones, wrist to tip: metacarpal, proximal, intermediate, distal. A
frame.Finger carries the knuckle (mcp), pip, dip and tip joints, so the proximal,
intermediate and distal bones are known; no source's frames carry the carpal joints, so the
metacarpal is reported with its start at its end (the knuckle) and length 0 (the Leap's own
thumb metacarpal has length 0 too). Units follow the input (frames: millimetres).
"""
import numpy as np

BONE_NAMES = ('metacarpal', 'proximal', 'intermediate', 'distal')
FINGER_JOINT_NAMES = ('mcp', 'pip', 'dip', 'tip')
MAX_JOINT = 1e6


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
    # Beyond any tracking volume in any unit (and far inside float32, which bone messages
    # carry: a joint of 1e300 ended the sender).
    if joints.shape != (5, 4, 3) or not np.all(np.abs(joints) <= MAX_JOINT):
        return None
    return joints


def bone_ends(joints):
    """(starts, ends), each (..., 4, 3): the four bones (BONE_NAMES order) of fingers given
    as (..., 4, 3) joints (mcp, pip, dip, tip). The metacarpal starts and ends at the mcp."""
    joints = np.asarray(joints, dtype=float)
    return joints[..., [0, 0, 1, 2], :], joints[..., [0, 1, 2, 3], :]
