"""The mirrored original system's per-frame rules: the evaluation's baseline, not used to
drive anything. Grab strength > 0.5 is a fist, or a thumbs-up when the SDK's thumb flag
says extended; pinch strength > 0.2 a pinch; the flags' thumb + index + pinky a rock;
every flag extended with grab < 0.5 an open hand."""
from leap_teleop.hands.gestures import PINCH_THRESHOLD, GestureState
from leap_teleop.hands.gestures.geometry import num


def _flags(hand):
    return tuple(bool(f.extended) for f in hand.fingers) if len(hand.fingers) == 5 else (False,) * 5


class OriginalRules:
    """The original system's rules, frame by frame (the baseline to beat)."""

    def classify(self, hand):
        ext = _flags(hand)
        grab = num(hand.grab_strength)
        pinch = num(hand.pinch_strength)
        state = GestureState(finger_extended=ext)
        if grab > 0.5:
            state.thumb_up = ext[0]
            state.fist = not ext[0]
        state.pinch = pinch > PINCH_THRESHOLD
        state.pinch_value = min(pinch - PINCH_THRESHOLD, 0.8) if state.pinch else 0.0
        state.rock = ext[0] and ext[1] and not ext[2] and not ext[3] and ext[4]
        state.open = all(ext) and grab < 0.5
        return state
