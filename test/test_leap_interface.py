"""LeapInterface: getters, reset on hand loss, origin / rotation, thread safety."""
import math
import threading
import time

import numpy as np
import pytest

from leap_teleop.hands.frame import Frame
from leap_teleop.hands.gestures import GestureRecognizer
from leap_teleop.hands.leap_interface import LeapInterface
from leap_teleop.hands.rendered_hand import render_hand, rpy_to_basis
from leap_teleop.hands.sources.source import HandSource
from leap_teleop.hands.tracker import DEAD_BANDS, dead_band, hand_angles


def per_frame():
    """Single-frame checks: no temporal filtering."""
    return GestureRecognizer(stateless=True)


def frame(i, *hands):
    return Frame(id=i, timestamp=100.0 + i * 0.01, hands=list(hands))


def test_getters_exist_for_both_sides_and_read_the_latest_frame():
    li = LeapInterface(recognizer_factory=per_frame)
    li.on_frame(frame(1, render_hand('right', 'fist', [10, 200, 5]),
                      render_hand('left', 'open', [-10, 180, 0])))
    assert li.get_is_right_hand() and li.get_is_left_hand()
    assert li.get_right_hand_palmpos() == (10.0, 200.0, 5.0)
    assert li.get_left_hand_palmpos() == (-10.0, 180.0, 0.0)
    assert li.get_right_hand_fist() and not li.get_left_hand_fist()
    names = ('thumb_up', 'pinch', 'pinch_value', 'origin_frame', 'set_origin_frame_detected',
             'rotate_value', 'turn_value', 'swing_value')

    def read(side):
        return {name: getattr(li, 'get_%s_hand_%s' % (side, name))() for name in names}
    idle = dict.fromkeys(names, False) | dict.fromkeys(('pinch_value', 'rotate_value',
                                                        'turn_value', 'swing_value'), 0.0)
    assert read('right') == idle and read('left') == idle
    # The next frame: a right pinch, a left rock (which sets the origin).
    li.on_frame(frame(2, render_hand('right', 'pinch', [10, 200, 5], pinch_value=0.5),
                      render_hand('left', 'rock', [-10, 180, 0])))
    assert read('right') == idle | {'pinch': True, 'pinch_value': pytest.approx(0.5)}
    assert read('left') == idle | {'origin_frame': True, 'set_origin_frame_detected': True}
    assert not li.get_right_hand_fist()


def test_every_flag_clears_when_the_hand_leaves():
    li = LeapInterface(recognizer_factory=per_frame)
    li.on_frame(frame(1, render_hand('right', 'rock', [0, 200, 0])))
    li.on_frame(frame(2, render_hand('right', 'pinch', [5, 200, 0], pinch_value=0.5)))
    state = li.get_right_hand_state()
    assert state.origin_set and state.pinch and state.pinch_value == pytest.approx(0.5)
    li.on_frame(frame(3))
    state = li.get_right_hand_state()
    assert not state.present
    assert not (state.fist or state.thumb_up or state.pinch or state.rock or state.open
                or state.origin_set)
    assert state.pinch_value == state.rotate == state.turn == state.swing == 0.0
    assert state.palm_position == (0.0, 0.0, 0.0)
    assert [e.gesture for e in state.events] == ['hand_lost']
    # Back again: the origin must be set anew.
    li.on_frame(frame(4, render_hand('right', 'open', [0, 200, 0])))
    assert not li.get_right_hand_origin_frame()
    assert 'hand_found' in [e.gesture for e in li.get_right_hand_state().events]


def test_rotation_since_origin_applies_the_dead_bands():
    li = LeapInterface(recognizer_factory=per_frame)
    li.on_frame(frame(1, render_hand('right', 'rock', [0, 200, 0])))
    normal, direction = rpy_to_basis(0.0, 0.0, math.radians(40), 'right')   # yaw 40 deg
    li.on_frame(frame(2, render_hand('right', 'open', [0, 200, 0], normal, direction)))
    assert li.get_right_hand_turn_value() == pytest.approx(math.radians(40) - 0.35, abs=1e-6)
    assert li.get_right_hand_rotate_value() == pytest.approx(0.0, abs=1e-6)
    normal, direction = rpy_to_basis(math.radians(-20), 0.0, 0.0, "right")  # roll -20 deg
    li.on_frame(frame(3, render_hand('right', 'open', [0, 200, 0], normal, direction)))
    assert li.get_right_hand_rotate_value() == pytest.approx(0.0, abs=1e-6)   # inside +-0.40
    normal, direction = rpy_to_basis(math.radians(-60), 0.0, 0.0, 'right')
    li.on_frame(frame(4, render_hand('right', 'open', [0, 200, 0], normal, direction)))
    assert abs(li.get_right_hand_rotate_value()) == pytest.approx(math.radians(60) - 0.40, abs=1e-6)


def test_rotation_since_origin_without_dead_bands_is_the_raw_rotation():
    li = LeapInterface(recognizer_factory=per_frame, dead_bands=None)
    li.on_frame(frame(1, render_hand('right', 'rock', [0, 200, 0])))
    normal, direction = rpy_to_basis(math.radians(-20), math.radians(10), math.radians(40),
                                     'right')
    li.on_frame(frame(2, render_hand('right', 'open', [0, 200, 0], normal, direction)))
    angles = hand_angles(normal, direction)
    assert li.get_right_hand_rotate_value() == pytest.approx(angles[0], abs=1e-6)
    assert li.get_right_hand_turn_value() == pytest.approx(angles[1], abs=1e-6)
    assert li.get_right_hand_swing_value() == pytest.approx(angles[2], abs=1e-6)
    assert abs(angles[0]) > 0.3 and abs(angles[2]) > 0.1      # inside the bands otherwise


@pytest.mark.parametrize('angle, expected', [(0.3, 0.0), (0.5, 0.05), (-0.1, -0.05), (0.0, 0.0)])
def test_dead_band_swing(angle, expected):
    assert dead_band(angle, *DEAD_BANDS['swing']) == pytest.approx(expected)


@pytest.mark.parametrize('palm', [[float('nan'), 200, 0], [0, float('inf'), 0], [1e9, 0, 0]])
def test_unplaceable_hands_are_treated_as_absent(palm):
    li = LeapInterface(recognizer_factory=per_frame)
    li.on_frame(frame(1, render_hand('right', 'fist', [0, 200, 0])))
    hand = render_hand('right', 'fist', [0, 200, 0])
    hand.palm_position = np.array(palm, dtype=float)
    li.on_frame(frame(2, hand))
    state = li.get_right_hand_state()
    assert not state.present and not state.fist


def test_out_of_range_strengths_are_clamped():
    li = LeapInterface(recognizer_factory=per_frame)
    hand = render_hand('right', 'open', [0, 200, 0])
    hand.grab_strength, hand.pinch_strength, hand.confidence = 7.0, float('nan'), -3.0
    li.on_frame(frame(1, hand))
    s = li.get_right_hand_state()
    assert (s.grab_strength, s.pinch_strength, s.confidence) == (1.0, 0.0, 0.0)
    assert not s.pinch and s.pinch_value == 0.0          # a NaN pinch strength is no pinch


class _CountingSource(HandSource):
    """Frame i puts both palms at x = i / 2, so a torn read shows as a mismatch."""

    def __init__(self, n):
        self.n = n

    def frames(self):
        for i in range(1, self.n + 1):
            if self.stopped:
                return
            yield frame(i, render_hand('right', 'open', [i / 2, 200, 0]),
                        render_hand('left', 'fist', [i / 2, 150, 0]))


def test_snapshots_are_consistent_under_a_concurrent_writer():
    li = LeapInterface(_CountingSource(2000))
    errors, reads, checked = [], [0], [0]

    def reader():
        last = 0
        while not li.finished.is_set():
            both = li.snapshot()
            right, left = both['right'], both['left']
            if right.present:
                checked[0] += 1
                if not (right.frame_id == left.frame_id == 2 * right.palm_position[0]
                        == 2 * left.palm_position[0]):
                    errors.append((right.frame_id, left.frame_id, right.palm_position))
                if right.frame_id < last:
                    errors.append(('went back', last, right.frame_id))
                last = right.frame_id
            reads[0] += 1
            time.sleep(0)   # let the writer run

    readers = [threading.Thread(target=reader) for _ in range(3)]
    for t in readers:
        t.start()
    li.start()
    li.finished.wait(30)
    for t in readers:
        t.join(5)
    assert li.error is None and li.frames_seen == 2000
    # the consistency check ran on many snapshots with both hands in them
    assert reads[0] > 100 and checked[0] > 100 and not errors, (checked, errors[:5])


def test_listeners_get_every_frame_in_order_and_source_errors_are_reported():
    class Broken(HandSource):
        def frames(self):
            yield frame(1)
            raise ValueError('device unplugged')

    li = LeapInterface(Broken())
    seen = []
    li.add_listener(lambda f, states: seen.append((f.id, sorted(states))))
    li.start()
    assert li.finished.wait(5)
    assert seen == [(1, ['left', 'right'])]
    assert isinstance(li.error, ValueError)


@pytest.mark.parametrize('stamp', [-1.0, float('nan'), float('inf'), None])
def test_frames_without_a_valid_capture_time_are_dropped(stamp):
    li = LeapInterface(recognizer_factory=per_frame)
    seen = []
    li.add_listener(lambda f, s: seen.append(f.id))
    li.on_frame(frame(1, render_hand('right', 'fist', [0, 200, 0])))
    bad = Frame(id=2, timestamp=stamp, hands=[render_hand('right', 'open', [9, 200, 0])])
    assert li.on_frame(bad) is None
    assert li.rejected_frames == 1 and seen == [1]
    assert li.get_right_hand_fist()                    # the last good frame stands


def test_a_palm_normal_or_direction_of_no_length_is_no_hand_and_others_are_made_unit():
    # A zero normal's angles are atan2 of zeros: with an origin set, one such frame sent
    # rotate -2.74, turn -2.99, swing -3.09 rad, and zero 'unit' vectors were published.
    from leap_teleop.hands.tracker import HandTracker
    tracker = HandTracker('right')
    good = render_hand('right', 'rock', [0.0, 200.0, 0.0])
    state = tracker.update(good, 1.0, 1)
    zero = render_hand('right', 'open', [0.0, 200.0, 0.0])
    zero.palm_normal = np.zeros(3)
    state = tracker.update(zero, 1.01, 2)
    assert not state.present and tracker.rejected_frames == 1
    assert (state.rotate, state.turn, state.swing) == (0.0, 0.0, 0.0)
    long = render_hand('right', 'open', [0.0, 200.0, 0.0], velocity=[3e4, 0.0, 0.0])
    long.palm_normal = long.palm_normal * 1.5
    long.fingers[1].tip[0] = 1e200
    state = tracker.update(long, 1.02, 3)
    assert state.present and math.hypot(*state.palm_normal) == pytest.approx(1.0)
    assert state.palm_velocity == (0.0, 0.0, 0.0) and state.finger_tips[1] == (0.0, 0.0, 0.0)


def test_two_hands_typed_alike_the_followed_one_stays_and_a_new_one_starts_afresh():
    # Both hands typed right, listed in either order: the first listed was taken, and the
    # right hand jumped 90 mm from frame to frame with no hand_lost.
    li = LeapInterface(recognizer_factory=per_frame)
    seen = []
    li.add_listener(lambda f, states: seen.append(len([h for h in f.hands if h.side == 'right'])))
    a = render_hand('right', 'open', [50.0, 200.0, 0.0], hand_id=23, confidence=0.6)
    b = render_hand('right', 'open', [-40.0, 200.0, 0.0], hand_id=10, confidence=0.9)
    palms, events = [], []
    li.on_frame(frame(1, a))
    for i in range(2, 30):
        states = li.on_frame(frame(i, *((a, b) if i % 3 else (b, a))))
        palms.append(states['right'].palm_position[0])
        events += [e.gesture for e in states['right'].events]
    assert palms == [50.0] * len(palms) and events == [] and set(seen) == {1}
    # The followed hand leaves: the other one is a new hand, after one frame without.
    states = li.on_frame(frame(30, b))
    assert not states['right'].present and [e.gesture for e in states['right'].events] == ['hand_lost']
    states = li.on_frame(frame(31, b))
    assert states['right'].present and states['right'].palm_position[0] == -40.0
    assert [e.gesture for e in states['right'].events] == ['hand_found']
    # An id of 0 is none known: a hand going from 0 to an id, or back, is the same hand.
    li = LeapInterface(recognizer_factory=per_frame)
    li.on_frame(frame(1, render_hand('right', 'open', [0.0, 200.0, 0.0], hand_id=0)))
    for i, hid in enumerate((5, 0, 5)):
        states = li.on_frame(frame(2 + i, render_hand('right', 'open', [0.0, 200.0, 0.0], hand_id=hid)))
        assert states['right'].present and not states['right'].events
    # With none followed, the most confident of two alike is taken.
    li = LeapInterface(recognizer_factory=per_frame)
    assert li.on_frame(frame(1, a, b))['right'].palm_position[0] == -40.0


def test_a_frame_without_a_hand_id_keeps_the_followed_one():
    # one id-less frame overwrote the id followed: the next, different hand was not seen
    # as new, and the first hand's open plus its fist made a fold
    from leap_teleop.hands.tracker import HandTracker
    tracker, events, t = HandTracker('right', GestureRecognizer()), [], 0.0
    for pose, hand_id, n in (('open', 5, 120), ('open', 0, 1), ('fist', 7, 60)):
        for _ in range(n):
            hand = render_hand('right', pose, (0.0, 200.0, 0.0), hand_id=hand_id)
            events += [e.gesture for e in tracker.update(hand, t, 0).events]
            t += 1 / 120
    assert 'fold' not in events and events.count('hand_lost') == 1
