"""SDK-independent hand frames: what every hand source yields.

Units and axes are the Leap Motion's: millimetres, right-handed, origin at the
device, +x to the user's right, +y up, +z toward the user.
"""
import math
from dataclasses import dataclass, field
from typing import List, Optional, Tuple

import numpy as np

FINGER_NAMES = ('thumb', 'index', 'middle', 'ring', 'pinky')
SIDES = ('right', 'left')


def vec3(values=None):
    """A float (3,) array; None -> zeros."""
    if values is None:
        return np.zeros(3)
    return np.asarray(values, dtype=float).reshape(3)


def measured(value):
    """A source's size or duration as a float; None when absent or not a finite number
    >= 0 (the field then stays unmeasured rather than a made-up 0)."""
    if value is None or isinstance(value, bool):
        return None
    try:
        x = float(value)
    except (TypeError, ValueError, OverflowError):
        return None
    return x if math.isfinite(x) and x >= 0.0 else None


def measured3(value):
    """A source's 3-vector as a float (3,) array; None when absent or not finite."""
    if value is None:
        return None
    try:
        v = np.asarray([value.x, value.y, value.z] if hasattr(value, 'x') else value, dtype=float)
    except (TypeError, ValueError, OverflowError):
        return None
    return v if v.shape == (3,) and np.all(np.isfinite(v)) else None


@dataclass
class Finger:
    """One finger. Joint positions are optional; sources fill what they have."""
    tip: np.ndarray = field(default_factory=vec3)          # mm
    direction: np.ndarray = field(default_factory=vec3)    # unit, tip direction
    extended: Optional[bool] = None                         # the SDK's flag, None when absent
    mcp: Optional[np.ndarray] = None                        # knuckle, mm
    pip: Optional[np.ndarray] = None                        # mm
    dip: Optional[np.ndarray] = None                        # mm
    # The SDK's sizes where the source measures them (LeapJS: width; the SDKs: bones too).
    width: Optional[float] = None                           # mm
    bone_widths: Optional[Tuple[float, ...]] = None         # mm, metacarpal .. distal
    # The carpal joint (the metacarpal's base, nearer the wrist) where the source measures
    # it (the Leap SDKs, LeapJS carpPosition); None for scripted and camera hands.
    carpal: Optional[np.ndarray] = None                     # mm


@dataclass
class TrackedHand:
    side: str                                               # 'right' | 'left'
    palm_position: np.ndarray = field(default_factory=vec3)  # mm
    palm_velocity: np.ndarray = field(default_factory=vec3)  # mm/s
    palm_normal: np.ndarray = field(default_factory=lambda: vec3((0.0, -1.0, 0.0)))
    direction: np.ndarray = field(default_factory=lambda: vec3((0.0, 0.0, -1.0)))
    grab_strength: float = 0.0                              # 0..1
    pinch_strength: float = 0.0                             # 0..1
    confidence: float = 1.0                                 # 0..1
    fingers: Tuple[Finger, ...] = ()                        # FINGER_NAMES order, 5 or none
    id: int = 0
    # Camera sources: the 21 landmarks as seen in the picture ((21, 2) pixels, y down,
    # MediaPipe order), which the keypoint pose model reads; None for other trackers.
    image_landmarks: Optional[np.ndarray] = None
    # The SDK's own measures where the source has them (LeapJS recordings, the Leap SDKs);
    # None for scripted and camera hands. time_visible: s the tracker has followed the hand.
    palm_width: Optional[float] = None                      # mm
    sphere_radius: Optional[float] = None                   # mm
    sphere_center: Optional[np.ndarray] = None              # mm
    time_visible: Optional[float] = None                    # s

    def finger(self, name):
        i = FINGER_NAMES.index(name)
        return self.fingers[i] if len(self.fingers) > i else None


@dataclass
class Frame:
    """One tracking frame. timestamp: capture time in seconds on the source's clock
    (wall time for live and scripted sources, recorded time for recordings)."""
    id: int
    timestamp: float
    hands: List[TrackedHand] = field(default_factory=list)
    gestures: List[dict] = field(default_factory=list)      # SDK gesture events, if any

    def hand(self, side):
        """The first hand of that side, or None."""
        for h in self.hands:
            if h.side == side:
                return h
        return None
