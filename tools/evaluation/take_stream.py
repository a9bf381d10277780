"""A LeapJS take streamed through the gesture recognizer, as the live sender runs it: one
recognizer per hand side, fed every frame in order (the evaluations of the shared takes
all walk them this way), and the list of every shared take."""
from leap_teleop.hands.gestures import GestureRecognizer
from leap_teleop.hands.sources import leapjs

# Every shared take. The SDK reported circles on six of them; the same circle matching run
# over all of them shows what a user sees on hands that are not asked to circle (clapping,
# grabbing, splaying): no circle event is the target.
EVERY_TAKE = ('grab', 'pinch', 'gun', 'wave', 'three-claps', 'confidence2',
              'test-paddle-rightwards', 'Waiting-110fps', 'HandSplay-110fps', 'brian',
              'flapping', 'rollAndPitchCropped', 'finger-tap-54fps')


def recognize_take(dicts, make_recognizer=GestureRecognizer):
    """Per frame dict that reads as a frame: (index in `dicts`, Frame, [(hand, the
    recognizer's state after it)]) for the first hand of each side in the frame. A side
    absent from a frame has its recognizer reset (the hand left); frames that do not
    read are skipped and reset nothing."""
    recognizers = {}
    for k, d in enumerate(dicts):
        if d is None:
            continue
        try:
            frame = leapjs.frame_from_dict(d)
        except leapjs.FrameError:
            continue
        judged, seen = [], set()
        for hand in frame.hands:
            if hand.side in seen:
                continue
            seen.add(hand.side)
            rec = recognizers.get(hand.side)
            if rec is None:
                rec = recognizers[hand.side] = make_recognizer()
            judged.append((hand, rec.update(hand, frame.timestamp)))
        for side, rec in recognizers.items():
            if side not in seen:
                rec.reset()
        yield k, frame, judged
