"""Per-hand gesture recognition.

OriginalRules reproduces the mirrored design's per-frame rules (DESIGN.md section 4);
GestureRecognizer adds what a stream needs: edge events (start / stop of held
gestures, unfold / fold) and a reset when the hand leaves.
"""
from dataclasses import dataclass, field
from typing import List, Tuple

from .frame import FINGER_NAMES

PINCH_THRESHOLD = 0.2   # pinch when strength > 0.2; pinch_value = strength - 0.2
HELD_GESTURES = ('fist', 'thumb_up', 'pinch', 'rock', 'open')


@dataclass
class GestureEvent:
    gesture: str
    active: bool = True
    value: float = 0.0


@dataclass
class GestureState:
    fist: bool = False
    thumb_up: bool = False
    pinch: bool = False
    pinch_value: float = 0.0           # 0..0.8
    rock: bool = False
    open: bool = False
    finger_extended: Tuple[bool, ...] = (False,) * 5
    events: List[GestureEvent] = field(default_factory=list)


def _flags(hand):
    return tuple(bool(f.extended) for f in hand.fingers) if len(hand.fingers) == 5 else (False,) * 5


class OriginalRules:
    """The original system's rules, frame by frame (the baseline to beat)."""

    def classify(self, hand):
        ext = _flags(hand)
        grab = hand.grab_strength
        state = GestureState(finger_extended=ext)
        if grab > 0.5:
            state.thumb_up = ext[0]
            state.fist = not ext[0]
        state.pinch = hand.pinch_strength > PINCH_THRESHOLD
        state.pinch_value = hand.pinch_strength - PINCH_THRESHOLD if state.pinch else 0.0
        state.rock = ext[0] and ext[1] and not ext[2] and not ext[3] and ext[4]
        state.open = all(ext) and grab < 0.5
        return state


class GestureRecognizer:
    """Stream recognizer for one hand: per-frame rules plus events on transitions."""

    def __init__(self, rules=None):
        self.rules = rules or OriginalRules()
        self._prev = GestureState()
        self._last_shape = None          # 'fist' or 'open', for fold / unfold

    def reset(self):
        self._prev = GestureState()
        self._last_shape = None

    def update(self, hand, timestamp):
        state = self.rules.classify(hand)
        events = []
        for name in HELD_GESTURES:
            now, before = getattr(state, name), getattr(self._prev, name)
            if now != before:
                value = state.pinch_value if name == 'pinch' else 0.0
                events.append(GestureEvent(name, now, value))
        shape = 'fist' if state.fist else 'open' if state.open else None
        if shape and shape != self._last_shape:
            if self._last_shape == 'fist' and shape == 'open':
                events.append(GestureEvent('unfold'))
            elif self._last_shape == 'open' and shape == 'fist':
                events.append(GestureEvent('fold'))
            self._last_shape = shape
        state.events = events
        self._prev = state
        return state


__all__ = ['FINGER_NAMES', 'GestureEvent', 'GestureRecognizer', 'GestureState',
           'OriginalRules', 'PINCH_THRESHOLD']
