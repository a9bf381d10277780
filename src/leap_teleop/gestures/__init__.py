"""Per-hand gesture recognition from hand geometry (public API).

GestureRecognizer decides from where the fingertips and finger joints are relative to
the palm, in the hand's own units (geometry), with per-frame pose rules (pose), a
temporal filter that emits start / stop, fold / unfold events (temporal) and circles
traced by the palm or a fingertip (circles).
"""
from ..frame import FINGER_NAMES
from .circles import CircleDetector, fit_circle
from .geometry import HandGeometry, hand_geometry
from .pose import PINCH_THRESHOLD, classify_geometry, geometric_pinch_strength
from .recognizer import GestureRecognizer
from .temporal import HELD_GESTURES, GestureEvent, GestureState

__all__ = ['FINGER_NAMES', 'HELD_GESTURES', 'CircleDetector', 'GestureEvent',
           'GestureRecognizer', 'GestureState', 'HandGeometry', 'PINCH_THRESHOLD',
           'classify_geometry', 'fit_circle', 'geometric_pinch_strength', 'hand_geometry']
