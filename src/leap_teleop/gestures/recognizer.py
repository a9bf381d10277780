"""GestureRecognizer: one hand's stream of frames -> held gestures and events.

Geometry (geometry.py) -> per-frame pose rules (pose.py) -> temporal filter and events
(temporal.py), plus circles (circles.py). Frames below `min_confidence` do not count;
a frame without a usable timestamp is placed 10 ms after the previous one.
GestureRecognizer(stateless=True) classifies every frame on its own.
"""
import math
from collections import deque

from .circles import CircleDetector
from .geometry import hand_geometry, num
from .pose import classify_geometry
from .temporal import HELD_GESTURES, GestureState, HeldFilter

MIN_CONFIDENCE = 0.1               # below: the frame does not count (SDK fists go to ~0.15)
# Minimum time a gesture must be seen before it turns on (besides on_frames).
ON_TIME_S = {}
# Thumbs-up arms a robot, and every fist -> open unfold passes ~0.1 s through a fist with
# the thumb out: no thumbs-up starts while the mean finger curl has opened by more than
# OPENING_CHORD (chord ratio; OPENING_DEG of bend without joints) within OPENING_WINDOW_S.
OPENING_CHORD = 0.15
OPENING_DEG = 25.0
OPENING_WINDOW_S = 0.15
_isfinite = math.isfinite


class GestureRecognizer:
    """Stream recognizer for one hand (either side): geometry rules, temporal filter,
    events. update(hand, timestamp) -> GestureState; reset() when the hand leaves."""

    def __init__(self, stateless=False, on_frames=3, off_frames=3,
                 min_confidence=MIN_CONFIDENCE, circles=True, on_time=None):
        self.stateless = stateless
        self.filter = HeldFilter(1 if stateless else on_frames, 1 if stateless else off_frames,
                                 {} if stateless else (ON_TIME_S if on_time is None else on_time))
        self.min_confidence = float(min_confidence)
        self.circles = CircleDetector() if circles and not stateless else None
        self.reset()

    def reset(self):
        self.filter.reset()
        self._curl_hist = deque(maxlen=64)
        self._prev = GestureState()
        self._prev_t = 0.0
        if self.circles is not None:
            self.circles.reset()

    def _opening(self, g, timestamp):
        """Whether the fingers opened fast within the last OPENING_WINDOW_S."""
        c = g.chord
        mean = (c[1] + c[2] + c[3] + c[4]) * 0.25
        scale = OPENING_CHORD
        if mean != mean:
            b = g.bend
            mean = -(b[1] + b[2] + b[3] + b[4]) * 0.25
            scale = OPENING_DEG
            if mean != mean:
                return False
        hist = self._curl_hist
        while hist and not (0.0 <= timestamp - hist[0][0] <= OPENING_WINDOW_S
                            and hist[0][2] == scale):
            hist.popleft()
        hist.append((timestamp, mean, scale))
        return mean - min(h[1] for h in hist) > scale

    def update(self, hand, timestamp):
        try:
            timestamp = float(timestamp)
        except (TypeError, ValueError):
            timestamp = math.nan
        if not _isfinite(timestamp):
            timestamp = self._prev_t + 0.01
        g = hand_geometry(hand)
        confidence = num(hand.confidence, 1.0)
        usable = g is not None and confidence >= self.min_confidence
        stateless = self.stateless
        prev = self._prev
        filt = self.filter
        if usable:
            if stateless:
                raw = classify_geometry(g, hand)
                active = {n for n in HELD_GESTURES if raw[n]}
            else:
                raw = classify_geometry(g, hand, filt.active, self._opening(g, timestamp))
                active = filt.update(raw, timestamp)
            extended = raw['extended']
            pinch_value = raw['pinch_value']
            if 'pinch' in active and pinch_value == 0.0 and not raw['pinch']:
                pinch_value = prev.pinch_value      # held through the off-filter
        else:
            active = set() if stateless else filt.unusable(timestamp)
            extended = prev.finger_extended
            pinch_value = prev.pinch_value
        pinch = 'pinch' in active
        state = GestureState('fist' in active, 'thumb_up' in active, pinch,
                             min(max(float(pinch_value), 0.0), 0.8) if pinch else 0.0,
                             'rock' in active, 'open' in active, extended, [],
                             'thumb_down' in active)
        if not stateless:
            if (state.fist != prev.fist or state.thumb_up != prev.thumb_up or pinch != prev.pinch
                    or state.rock != prev.rock or state.open != prev.open
                    or state.thumb_down != prev.thumb_down):
                state.events = filt.events(state, prev)
            if self.circles is not None and usable:
                circle = self.circles.update(hand, timestamp, g, extended)
                if circle is not None:
                    state.events.append(circle)
        self._prev = state
        self._prev_t = timestamp
        return state
