"""GestureRecognizer: one hand's stream of frames -> held gestures and events.

Per frame: geometry (geometry.py) and the learned pose model with its guards (pose.py);
over time: the temporal filter and its events (temporal.py), plus circles (circles.py).
Frames below `min_confidence` do not count; a frame without a usable timestamp is placed
10 ms after the previous one. GestureRecognizer(stateless=True) classifies every frame on
its own.

The models: the shipped Leap-family model (3-D joints) and keypoint model (a camera's
image landmarks), or a user's (`model` / `keypoint_model`: paths). A hand carrying image
landmarks is judged by the keypoint model, any other by the Leap one.
"""
import math

from leap_teleop.hands.gestures.circles import CircleDetector
from leap_teleop.hands.gestures.classifier import BUILT_IN_CLASSES, ModelError, load_model
from leap_teleop.hands.gestures.geometry import hand_geometry, num
from leap_teleop.hands.gestures.pose import classify_pose
from leap_teleop.hands.gestures.temporal import GestureState, HeldFilter

MIN_CONFIDENCE = 0.1               # below: the frame does not count (SDK fists go to ~0.15)
# Minimum time a gesture must be seen before it turns on (besides on_frames).
ON_TIME_S = {}
_isfinite = math.isfinite


class GestureRecognizer:
    """Stream recognizer for one hand (either side): pose model, temporal filter,
    events. update(hand, timestamp) -> GestureState; reset() when the hand leaves."""

    def __init__(self, stateless=False, on_frames=3, off_frames=3,
                 min_confidence=MIN_CONFIDENCE, circles=True, on_time=None, model=None,
                 keypoint_model=None):
        self.stateless = stateless
        self.models = {'leap': load_model(model, 'leap'),
                       'keypoints': load_model(keypoint_model, 'keypoints')}
        for m in self.models.values():
            missing = [c for c in BUILT_IN_CLASSES if c not in m.classes]
            if missing:
                # Without them every hand reads as one of its own classes: an open hand
                # arms what a user class is bound to, and the fist never stops.
                raise ModelError('%s: a %s pose model of the classes %s lacks the built-in ones '
                                 '%s: retrain it with the shared data (train_gestures --data DIR)'
                                 % (m.path or 'the model', m.family, ', '.join(m.classes),
                                    ', '.join(missing)))
        # a hand is judged by its family's model only: a class of the other never fires for it
        self.user_gestures_of = {f: tuple(sorted(c for c in m.classes if c not in BUILT_IN_CLASSES))
                                 for f, m in self.models.items()}
        self.user_gestures = tuple(sorted(set().union(*self.user_gestures_of.values())))
        self.filter = HeldFilter(1 if stateless else on_frames, 1 if stateless else off_frames,
                                 {} if stateless else (ON_TIME_S if on_time is None else on_time),
                                 extra=self.user_gestures)
        self.min_confidence = float(min_confidence)
        self.circles = CircleDetector() if circles and not stateless else None
        self.reset()

    def reset(self):
        self.filter.reset()
        self._prev = GestureState()
        self._prev_t = 0.0
        if self.circles is not None:
            self.circles.reset()

    def update(self, hand, timestamp):
        try:
            timestamp = float(timestamp)
        except (TypeError, ValueError):
            timestamp = math.nan
        if not _isfinite(timestamp):
            timestamp = self._prev_t + 0.01
        g = hand_geometry(hand)
        confidence = num(hand.confidence, 1.0)
        camera = getattr(hand, 'image_landmarks', None) is not None
        usable = (g is not None or camera) and confidence >= self.min_confidence
        stateless = self.stateless
        prev = self._prev
        filt = self.filter
        label, probability = '', 0.0
        if usable:
            raw = classify_pose(hand, g, self.models['keypoints' if camera else 'leap'])
            label, probability = raw['label'], raw['probability']
            if stateless:
                active = {n for n in filt.names if raw.get(n)}
            else:
                active = filt.update(raw, timestamp)
            extended = raw['extended']
            pinch_value = raw['pinch_value']
            if 'pinch' in active and not raw['pinch']:
                pinch_value = prev.pinch_value      # held through the off-filter
        else:
            active = set() if stateless else filt.unusable(timestamp)
            extended = prev.finger_extended
            pinch_value = prev.pinch_value
        pinch = 'pinch' in active
        state = GestureState('fist' in active, 'thumb_up' in active, pinch,
                             min(max(float(pinch_value), 0.0), 0.8) if pinch else 0.0,
                             'rock' in active, 'open' in active, extended, [],
                             'thumb_down' in active, label, probability,
                             tuple(sorted(n for n in active if n in self.user_gestures))
                             if self.user_gestures else (), usable)
        if not stateless:
            state.unseen = filt.carried() if usable else ()
            shown = None if not usable else 'fist' if raw.get('fist') else 'open' if raw.get('open') else None
            state.events = filt.events(state, prev, timestamp, usable, shown)
            if self.circles is not None and usable and g is not None:
                circle = self.circles.update(hand, timestamp, g, extended)
                if circle is not None:
                    state.events.append(circle)
        self._prev = state
        self._prev_t = timestamp
        return state
