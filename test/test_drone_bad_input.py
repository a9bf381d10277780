"""The pilot against bad input: stale or far-future gesture events, absurd circles, hands
whose direction is no unit vector, unknown gestures and sides (no ROS master)."""
from types import SimpleNamespace

import pytest

from leap_teleop.drone.pilot import DronePilot, PilotInput, PilotParams

T = 1.7e9           # the pilot's clock (s): ROS time, as a live sender stamps


def drain(pilot):
    out, mono = [], 1e6
    while True:
        mono += 1.0
        cmd, _ = pilot.pop(mono)
        if cmd is None:
            return out
        out.append(cmd)


def pilot_with_hands(state, lag=0.01, stamp_offset=0.0, **cfg):
    """A pilot seeing navdata `state` at 1 m and a centred hand stream (stamps `lag` s
    before arrival, plus stamp_offset: a replayed bag's old stamps), up to time T."""
    warnings = []
    pilot = DronePilot(PilotParams(navdata_timeout=10.0, **cfg),
                       warn=lambda key, text: warnings.append(text))
    pilot.on_navdata(state, 1000, T)
    for k in range(5):
        t = T - 0.04 + 0.01 * k
        assert pilot.on_hand(PilotInput(True, (0.0, 0.2, 0.0), stamp=t - lag + stamp_offset), t) is None
    return pilot, warnings


def test_stale_or_far_future_gesture_events_never_fly_the_drone():
    pilot, warnings = pilot_with_hands(2)
    pilot.on_gesture('unfold', True, T, stamp=T - 3600.0)            # an hour old
    pilot.on_gesture('unfold', True, T, stamp=T - 1.0)               # held up for 1 s
    pilot.on_gesture('unfold', True, T, stamp=T + 3600.0)            # far ahead
    assert drain(pilot) == []
    assert pilot.rejected_inputs == 3
    assert any('late' in w and 'unfold' in w for w in warnings)
    assert any('ahead' in w for w in warnings)
    pilot.on_gesture('unfold', True, T, stamp=T - 0.012)             # on time: takes off
    assert [c.kind for c in drain(pilot)] == ['takeoff']

    pilot, warnings = pilot_with_hands(4)                            # hovering at 1 m
    for stamp in (1.0, T - 1.0, T + 3600.0):                         # secs=1, late, ahead
        pilot.on_gesture('circle_cw', True, T, 0.05, stamp=stamp)
    assert drain(pilot) == []
    pilot.on_gesture('circle_cw', True, T, 0.05, stamp=T - 0.01)
    assert [c.kind for c in drain(pilot)] == ['flip']
    # a fold lands however late it comes: landing is the safe thing it asks for
    pilot.on_gesture('fold', True, T, stamp=T - 3600.0)
    assert [c.kind for c in drain(pilot)] == ['land']


def test_a_first_event_with_no_hand_stream_is_judged_by_this_clock():
    warnings = []
    pilot = DronePilot(PilotParams(), warn=lambda key, text: warnings.append(text))
    pilot.on_navdata(2, 0, T)
    pilot.on_gesture('unfold', True, T, stamp=T - 3600.0)
    pilot.on_navdata(4, 1000, T)
    pilot.on_gesture('circle_cw', True, T, 0.05, stamp=1.0)
    assert drain(pilot) == []
    assert sum('no stamped Hand to judge it by' in w for w in warnings) == 2


def test_an_unfold_with_no_fresh_hand_does_not_take_off():
    pilot, warnings = pilot_with_hands(2)
    pilot.on_gesture('unfold', True, T + 1.0)                 # the hand silent for 1 s
    assert drain(pilot) == [] and 'no fresh Hand input' in warnings[-1]


def test_a_circle_with_no_fresh_hand_does_not_flip():
    pilot, warnings = pilot_with_hands(4)                     # hovering at 1 m
    pilot.on_navdata(4, 1000, T + 1.0)
    pilot.on_gesture('circle_cw', True, T + 1.0, 0.05)        # the hand silent for 1 s
    assert drain(pilot) == [] and 'circle_cw: no flip, no fresh Hand input' in warnings[-1]


def test_a_replayed_bag_with_old_stamps_still_flies():
    # Hands and gestures both stamped an hour back: judged against the stream, on time.
    pilot, _ = pilot_with_hands(2, stamp_offset=-3600.0)
    pilot.on_gesture('unfold', True, T, stamp=T - 3600.01)
    assert [c.kind for c in drain(pilot)] == ['takeoff']
    pilot.on_navdata(4, 1000, T)
    pilot.on_gesture('circle_ccw', True, T, 0.05, stamp=T - 3600.01)
    assert [c.kind for c in drain(pilot)] == ['flip']
    pilot.on_gesture('circle_ccw', True, T, 0.05, stamp=T - 3601.0)  # late within the bag
    assert drain(pilot) == []


def test_only_hand_sized_circles_flip_huge_ones_neither():
    pilot, warnings = pilot_with_hands(4)
    for radius in (1e30, 0.6, 1.0):
        pilot.on_gesture('circle_cw', True, T, radius)
    assert drain(pilot) == []
    assert len(warnings) == 3 and all('not a hand-sized circle' in w for w in warnings)
    for radius in (0.1, 0.3, 0.5):          # a bound flip's 0.1 m, the recognizer's largest
        pilot.on_gesture('circle_cw', True, T, radius)
        pilot.on_navdata(4, 1000, T)
    assert [c.kind for c in drain(pilot)] == ['flip'] * 3


@pytest.mark.parametrize('field, vector', [('direction', (0.0, 0.0, 0.0)),
                                           ('direction', (1e-9, 0.0, 0.0)),
                                           ('direction', (0.0, 0.0, -1.2)),
                                           ('normal', (0.0, 0.0, 0.0)),
                                           ('normal', (0.0, -0.5, 0.0))])
def test_a_hand_whose_direction_or_normal_is_no_unit_vector_is_refused(field, vector):
    pilot, warnings = pilot_with_hands(2)
    pilot.on_gesture('unfold', True, T)
    pilot.on_navdata(4, 1000, T)
    drain(pilot)
    why = pilot.on_hand(PilotInput(True, (0.0, 0.2, 0.0), stamp=T + 0.01, **{field: vector}),
                        T + 0.02)
    assert why and 'unit vectors' in why and 'unit vectors' in warnings[-1]
    assert drain(pilot) == [] and pilot.rejected_inputs == 1
    # nearly unit (a float32 message, a rounded recording): steers, no yaw
    assert pilot.on_hand(PilotInput(True, (0.0, 0.2, 0.0), direction=(0.0, 0.0, -0.995),
                                    stamp=T + 0.02), T + 0.03) is None
    assert [c.twist for c in drain(pilot)] == [(0.0,) * 6]


def test_paper_mode_never_commands_beyond_the_drivers_range():
    pilot = DronePilot(PilotParams(mode='paper', paper_scale=100.0, navdata_timeout=10.0))
    pilot.on_navdata(4, 1000, T)
    capture = dict(normal=(0.6, -0.8, 0.0), direction=(0.0, 0.6, -0.8))     # pitch, roll 37
    pilot.on_hand(PilotInput(True, (0.9, 0.2, 0.9), **capture), T)
    pilot.on_hand(PilotInput(True, (-0.9, 0.2, -0.9)), T + 0.01)
    twist = [c.twist for c in drain(pilot)][-1]
    assert all(abs(v) <= 1.0 for v in twist[:3]) and twist[:2] == (1.0, 1.0)
    assert twist[3:5] == (900.0, 900.0)      # the paper's raw mm: an auto-hover switch only


def test_unknown_gesture_names_and_sides_are_warned_about(monkeypatch):
    pilot, warnings = pilot_with_hands(2)
    # built-in ones not acted on, and a user model's class (a sender publishes it too)
    for name in ('fist', 'open', 'hand_found', 'thumb_down', 'two'):
        pilot.on_gesture(name, True, T)
    assert warnings == []
    for name in ('', 'no such gesture!', 'x' * 65):
        pilot.on_gesture(name, True, T)
    assert len(warnings) == 3 and "'no such gesture!'" in warnings[1]

    from leap_teleop.msg import GestureEvent
    from leap_teleop.ros.nodes.drone_pilot import DronePilotNode
    said, seen = [], []
    node = SimpleNamespace(side=0, name='drone/drone_pilot',
                           log=SimpleNamespace(warn=lambda key, fmt, *a: said.append(fmt % a)),
                           pilot=SimpleNamespace(on_gesture=lambda *a: seen.append(a)))
    DronePilotNode.on_gesture(node, GestureEvent(side=7, gesture='unfold', active=True))
    DronePilotNode.on_gesture(node, GestureEvent(side=1, gesture='unfold', active=True))
    assert seen == [] and len(said) == 1 and 'side 7' in said[0] and "'unfold'" in said[0]
    monkeypatch.setattr('rospy.get_time', lambda: T)
    DronePilotNode.on_gesture(node, GestureEvent(side=0, gesture='unfold', active=True))
    assert len(seen) == 1
