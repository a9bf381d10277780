"""One hand side across frames: recognized gestures, the origin and the rotation since
it, as an immutable HandState per frame. No threads, no ROS (LeapInterface runs these
over a source)."""
import logging
import math
from dataclasses import dataclass
from typing import Tuple

import numpy as np

from leap_teleop.hands.gestures import HELD_GESTURES, GestureRecognizer, HandEvent
from leap_teleop.hands.gestures.bindings import Bindings
from leap_teleop.vectors import wrap_angle

log = logging.getLogger(__name__)

# Rotation since the origin: (dead band low, high) in rad, per DESIGN.md section 3.
DEAD_BANDS = {'rotate': (-0.40, 0.40), 'turn': (-0.15, 0.35), 'swing': (-0.05, 0.45)}
MAX_PALM_MM = 2000.0     # beyond this a palm position is a tracking error, not a hand
MAX_PALM_SPEED_MM_S = 20000.0    # beyond this a palm velocity is one too (20 m/s): zero


def dead_band(angle, low, high):
    """angle minus the crossed bound; 0 inside [low, high]."""
    if angle > high:
        return angle - high
    if angle < low:
        return angle - low
    return 0.0


def hand_angles(normal, direction):
    """(roll, yaw, pitch) as the Leap SDK defines them: about z, y, x."""
    roll = math.atan2(normal[0], -normal[1])
    yaw = math.atan2(direction[0], -direction[2])
    pitch = math.atan2(direction[1], -direction[2])
    return roll, yaw, pitch


@dataclass(frozen=True)
class HandState:
    """Everything known about one hand after one frame. Immutable: share freely."""
    side: str
    present: bool = False
    timestamp: float = 0.0
    frame_id: int = 0
    palm_position: Tuple[float, float, float] = (0.0, 0.0, 0.0)   # mm, Leap axes
    palm_velocity: Tuple[float, float, float] = (0.0, 0.0, 0.0)   # mm/s
    palm_normal: Tuple[float, float, float] = (0.0, 0.0, 0.0)
    direction: Tuple[float, float, float] = (0.0, 0.0, 0.0)
    grab_strength: float = 0.0
    pinch_strength: float = 0.0
    confidence: float = 0.0
    finger_extended: Tuple[bool, ...] = (False,) * 5
    finger_tips: Tuple[Tuple[float, float, float], ...] = ((0.0, 0.0, 0.0),) * 5   # mm
    # fist, thumb_up, pinch (+ value), rock: the arm's stop, arm, gripper, origin actions
    # (their gestures by default; see gestures.bindings)
    fist: bool = False
    thumb_up: bool = False
    pinch: bool = False
    pinch_value: float = 0.0
    rock: bool = False
    open: bool = False
    origin_set: bool = False
    thumb_down: bool = False
    pose_class: str = ''                 # the pose model's winning class and probability
    pose_probability: float = 0.0
    origin_palm: Tuple[float, float, float] = (0.0, 0.0, 0.0)
    rotate: float = 0.0
    turn: float = 0.0
    swing: float = 0.0
    events: Tuple[HandEvent, ...] = ()
    # the gestures the recognizer holds (built-in, then the user's own), whatever the
    # bindings make of them: the flags above are actions (arm bound to a V sign sets
    # thumb_up while a V sign is held); not published, shown on the camera view
    held: Tuple[str, ...] = ()


def held_names(g):
    """The names of the gestures a GestureState holds: built-in ones, then the user's."""
    return tuple(name for name in HELD_GESTURES if getattr(g, name, False) is True) + tuple(g.user)


def _finite_tuple(v, limit=None):
    """(x, y, z) floats of a 3-vector; None when not finite or beyond +-limit."""
    if v.__class__ is np.ndarray and v.shape == (3,):
        x, y, z = v.tolist()            # plain floats: numpy per-call costs dominate here
        x, y, z = float(x), float(y), float(z)
    else:
        x, y, z = np.asarray(v, dtype=float).reshape(3).tolist()
    if not (math.isfinite(x) and math.isfinite(y) and math.isfinite(z)):
        return None
    if limit is not None and (abs(x) > limit or abs(y) > limit or abs(z) > limit):
        return None
    return (x, y, z)


def _unit_tuple(v):
    """A palm normal or direction scaled to length 1; None when not finite or of a length
    no tracker sends (a zero vector's angles are atan2 of zeros: pi, a full-scale turn)."""
    v = _finite_tuple(v)
    if v is None:
        return None
    n = math.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
    if not 0.5 <= n <= 2.0:
        return None
    return (v[0] / n, v[1] / n, v[2] / n)


def hand_placement(hand):
    """(palm, palm normal, direction) as plain tuples, the last two of length 1; None for
    a hand that cannot be placed (not finite, a palm beyond MAX_PALM_MM, a vector of no
    length): treated as gone, by the sender and classify_frames alike."""
    palm = _finite_tuple(hand.palm_position, MAX_PALM_MM)
    normal = _unit_tuple(hand.palm_normal)
    direction = _unit_tuple(hand.direction)
    if palm is None or normal is None or direction is None:
        return None
    return palm, normal, direction


def _unit_interval(x):
    try:
        x = float(x)
    except (TypeError, ValueError):
        return 0.0
    return min(max(x, 0.0), 1.0) if math.isfinite(x) else 0.0


class HandTracker:
    """State of one side across frames: gestures, origin, rotation since origin.
    `bindings` (gestures.bindings.Bindings, default: the defaults) turn the recognizer's
    gestures into the actions the consumers read: the fist / thumb_up / rock / pinch
    flags and the pilot's events (BindingError when they name a gesture the recognizer
    cannot report)."""

    def __init__(self, side, recognizer=None, dead_bands=DEAD_BANDS, bindings=None):
        self.side = side
        self.recognizer = recognizer or GestureRecognizer()
        self.actions = (bindings or Bindings()).applier(
            getattr(self.recognizer, 'user_gestures', ()))
        self.dead_bands = dead_bands    # None: the raw rotation since the origin
        self.state = HandState(side)
        self._origin_angles = None
        self.rejected_frames = 0
        self.hand_id = None             # the id of the hand followed, while present

    def _lost(self, timestamp, frame_id):
        was_present = self.state.present
        self.recognizer.reset()
        self._origin_angles = None
        self.hand_id = None
        events = (HandEvent('hand_lost'),) if was_present else ()
        self.state = HandState(self.side, timestamp=timestamp, frame_id=frame_id, events=events)
        return self.state

    def update(self, hand, timestamp, frame_id):
        """Advance with this frame's hand of our side (None when absent)."""
        if hand is None:
            return self._lost(timestamp, frame_id)
        placed = hand_placement(hand)
        if placed is None:
            # A hand we cannot place is treated as gone: consumers hold still.
            self.rejected_frames += 1
            if self.rejected_frames in (1, 10, 100) or self.rejected_frames % 1000 == 0:
                log.warning('%s hand: rejected %d frame(s) with a non-finite or out-of-range '
                            'palm (|p| > %g mm) or a palm normal or direction of no length',
                            self.side, self.rejected_frames, MAX_PALM_MM)
            return self._lost(timestamp, frame_id)
        palm, normal, direction = placed
        was_present = self.state.present
        if was_present and hand.id != self.hand_id and hand.id and self.hand_id:
            # Another hand took this side (the SDK re-found one, or typed two alike): the
            # one followed is gone, and this one is new from the next frame, with no origin
            # or gesture of the other's (its palm was 90 mm away, with no hand_lost). An id
            # of 0 is none known: no change is seen in it.
            lost = self._lost(timestamp, frame_id)
            self.hand_id = hand.id
            return lost
        if hand.id:                     # an id-less frame keeps the one followed
            self.hand_id = hand.id
        g = self.recognizer.update(hand, timestamp)
        arm, origin, stop, gripper, gripper_value = self.actions.flags(g)
        events = list(self.actions.events(g.events))
        if not was_present:
            events.insert(0, HandEvent('hand_found'))

        angles = hand_angles(normal, direction)
        if origin:
            self._origin_angles = angles
            origin_palm = palm
        else:
            origin_palm = self.state.origin_palm
        rotation = {'rotate': 0.0, 'turn': 0.0, 'swing': 0.0}
        if self._origin_angles is not None:
            for key, now, ref in zip(('rotate', 'turn', 'swing'), angles, self._origin_angles):
                angle = wrap_angle(now - ref)
                rotation[key] = (angle if self.dead_bands is None
                                 else dead_band(angle, *self.dead_bands[key]))
        tips = tuple((_finite_tuple(f.tip, MAX_PALM_MM) or (0.0, 0.0, 0.0)) for f in hand.fingers[:5])
        tips = tips + ((0.0, 0.0, 0.0),) * (5 - len(tips))
        velocity = _finite_tuple(hand.palm_velocity, MAX_PALM_SPEED_MM_S) or (0.0, 0.0, 0.0)
        self.state = HandState(
            side=self.side, present=True, timestamp=timestamp, frame_id=frame_id,
            palm_position=palm, palm_velocity=velocity, palm_normal=normal,
            direction=direction, grab_strength=_unit_interval(hand.grab_strength),
            pinch_strength=_unit_interval(hand.pinch_strength),
            confidence=_unit_interval(hand.confidence),
            finger_extended=tuple(bool(x) for x in g.finger_extended), finger_tips=tips,
            fist=stop, thumb_up=arm, pinch=gripper,
            pinch_value=min(max(float(gripper_value), 0.0), 0.8) if gripper else 0.0,
            rock=origin, open=g.open, thumb_down=g.thumb_down, origin_set=self._origin_angles is not None,
            pose_class=g.label, pose_probability=float(g.probability),
            origin_palm=origin_palm, events=tuple(events), held=held_names(g), **rotation)
        return self.state
