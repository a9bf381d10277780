"""Per-hand gesture recognition (public API).

GestureRecognizer decides each frame with a learned pose model fitted on real people
(classifier, features) and explicit guards beside it (pose), then over time with a
temporal filter that emits start / stop, fold / unfold events (temporal) and circles
traced by the palm or a fingertip (circles).
"""
from leap_teleop.hands.frame import FINGER_NAMES
from leap_teleop.hands.gestures.circles import CircleDetector, fit_circle
from leap_teleop.hands.gestures.classifier import ModelError, PoseClassifier, load_model
from leap_teleop.hands.gestures.geometry import HandGeometry, hand_geometry
from leap_teleop.hands.gestures.pose import PINCH_THRESHOLD, classify_pose, geometric_pinch_strength
from leap_teleop.hands.gestures.recognizer import GestureRecognizer
from leap_teleop.hands.gestures.temporal import HELD_GESTURES, GestureState, HandEvent

__all__ = ['FINGER_NAMES', 'HELD_GESTURES', 'CircleDetector', 'HandEvent',
           'GestureRecognizer', 'GestureState', 'HandGeometry', 'ModelError', 'PINCH_THRESHOLD',
           'PoseClassifier', 'classify_pose', 'fit_circle', 'geometric_pinch_strength',
           'hand_geometry', 'load_model']
