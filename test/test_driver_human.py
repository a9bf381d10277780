"""The leap_motion driver's interface without a master: bones from joints (skeleton), the
filter node's low-pass (lowpass), Frame + HandState -> DriverHuman (conversions) and the
visualizer's markers (visualization)."""
import math

import numpy as np
import pytest

from leap_teleop.control.lowpass import LowPass
from leap_teleop.hands import skeleton
from leap_teleop.hands.frame import Finger, Frame
from leap_teleop.hands.gestures import HandEvent
from leap_teleop.hands.leap_interface import LeapInterface
from leap_teleop.hands.rendered_hand import render_hand
from leap_teleop.hands.sources import leapjs
from leap_teleop.hands.tracker import HandState
from leap_teleop.ros import hand_conversions
from leap_teleop.ros.markers import driver_markers


# --- skeleton ----------------------------------------------------------------------------
def test_bones_run_knuckle_to_tip_and_the_metacarpal_has_no_length():
    hand = render_hand('right', 'open', [0.0, 200.0, 0.0])
    joints = skeleton.hand_joints(hand)
    assert joints.shape == (5, 4, 3)
    starts, ends = skeleton.bone_ends(joints)
    f = hand.fingers[1]
    np.testing.assert_array_equal(starts[1], [f.mcp, f.mcp, f.pip, f.dip])
    np.testing.assert_array_equal(ends[1], [f.mcp, f.pip, f.dip, f.tip])
    assert np.all(np.linalg.norm(ends[:, 0] - starts[:, 0], axis=1) == 0.0)
    assert np.all(np.linalg.norm(ends[:, 1:] - starts[:, 1:], axis=2) > 5.0)     # mm


@pytest.mark.parametrize('broken', [
    lambda f: Finger(tip=f.tip, direction=f.direction),                     # no joints
    lambda f: Finger(tip=f.tip, direction=f.direction, mcp=f.mcp, pip=f.pip,
                     dip=np.array([math.nan, 0.0, 0.0])),                   # a NaN joint
    lambda f: Finger(tip=f.tip, direction=f.direction, mcp=f.mcp, pip=[1.0, 2.0], dip=f.dip),
])
def test_a_finger_without_usable_joints_gives_no_bones(broken):
    hand = render_hand('left', 'fist', [0.0, 200.0, 0.0])
    hand.fingers = hand.fingers[:2] + (broken(hand.fingers[2]),) + hand.fingers[3:]
    assert skeleton.hand_joints(hand) is None
    hand.fingers = hand.fingers[:4]
    assert skeleton.hand_joints(hand) is None


# --- lowpass -----------------------------------------------------------------------------
def test_lowpass_starts_at_the_input_and_settles_on_a_step():
    lp = LowPass(4.0)
    assert lp('a', [1.0, 2.0]).tolist() == [1.0, 2.0]
    out = [lp('a', [3.0, 2.0])[0] for _ in range(60)]
    assert 1.0 < out[0] < 1.2                          # slow start: smoothing
    assert out[-1] == pytest.approx(3.0, abs=1e-3)     # unit gain at rest
    assert max(out) < 3.1                              # barely overshoots (Butterworth)


def test_lowpass_matches_the_second_order_difference_equation():
    c = 2.5
    lp = LowPass(c)
    rng = np.random.default_rng(3)
    xs = rng.normal(size=50)
    x = [xs[0]] * 3
    y = [xs[0]] * 2
    for v in xs:
        x = [v] + x[:2]
        want = (x[0] + 2 * x[1] + x[2] - (c * c - math.sqrt(2) * c + 1) * y[1]
                - (2 - 2 * c * c) * y[0]) / (1 + c * c + math.sqrt(2) * c)
        y = [want, y[0]]
        assert lp('k', [v])[0] == pytest.approx(want, abs=1e-12)


def test_lowpass_keys_are_independent_and_reset_restarts():
    lp = LowPass(4.0)
    lp('right', [0.0])
    lp('left', [10.0])
    assert lp('right', [0.0])[0] == 0.0 and lp('left', [10.0])[0] == 10.0
    lp.reset('right')
    assert lp('right', [5.0])[0] == 5.0


@pytest.mark.parametrize('bad', [0.0, -1.0, math.nan, math.inf, 'x'])
def test_lowpass_refuses_a_cutoff_that_is_not_a_positive_number(bad):
    lp = LowPass(3.0)
    with pytest.raises(ValueError):
        lp.set_cutoff(bad)
    assert lp.cutoff == 3.0


def test_a_live_cutoff_change_never_mixes_old_and_new_coefficients():
    # The three coefficients were assigned one by one on dynamic_reconfigure's thread: a
    # frame between them was filtered with a gain other than 1 (71 of 1600 frames of a
    # constant input left it when threads switched every 10 us).
    import sys
    import threading
    lp = LowPass(4.0)
    x = np.array([100.0, -50.0, 7.0])
    lp('hand', x)
    stop = threading.Event()

    def slider():
        k = 0
        while not stop.is_set():
            lp.set_cutoff(1.0 + (k % 50) / 10.0)
            k += 1
    interval = sys.getswitchinterval()
    sys.setswitchinterval(1e-5)
    thread = threading.Thread(target=slider)
    thread.start()
    try:
        worst = max(float(np.abs(lp('hand', x) - x).max()) for _ in range(20000))
    finally:
        stop.set()
        thread.join()
        sys.setswitchinterval(interval)
    assert worst < 1e-9


@pytest.mark.parametrize('new', [0.5, 0.2, 0.05, 8.0, 16.0])
def test_a_live_cutoff_change_on_a_moving_hand_neither_jumps_nor_rings(new):
    # The old history under lighter coefficients: the filtered palm stepped 16-142 mm a
    # frame, back and forth, ahead of the hand, while the hand moved 2.7 mm a frame; a
    # heavier filter restarted at rest stalled it (0.04 mm a frame).
    lp = LowPass(4.0)
    out = [lp('hand', [2.7 * k])[0] for k in range(60)]
    lp.set_cutoff(new)
    out += [lp('hand', [2.7 * k])[0] for k in range(60, 120)]
    steps = np.diff(out)
    assert steps.max() < 4 * 2.7 and steps[59:].min() > (0.0 if new < 4 else 0.5 * 2.7)  # no leap, ringing, stall
    assert all(y <= 2.7 * k + 1.5 for k, y in enumerate(out))     # not ahead of the hand (was 14 mm)
    assert out[-1] == pytest.approx(2.7 * 119, abs=1.5 if new < 4 else 35.0)   # the new filter's lag


# --- DriverHuman -------------------------------------------------------------------------
def run(frames, builder=None, lowpass=None):
    """[(raw, filtered)] per frame through a LeapInterface and the builder."""
    builder = builder or hand_conversions.DriverHumanBuilder()
    out = []
    li = LeapInterface()
    li.add_listener(lambda f, s: out.append(builder.human_msgs(f, s, lowpass=lowpass)))
    for f in frames:
        li.on_frame(f)
    return out


def test_human_is_in_metres_and_radians_with_the_drivers_frame():
    right = render_hand('right', 'open', [12.0, 210.0, -30.0], velocity=[100.0, 0.0, -50.0],
                        hand_id=7)
    (human, filtered), = run([Frame(id=42, timestamp=100.25, hands=[right])])
    assert filtered is None
    assert human.header.frame_id == 'leap_hands'
    assert human.header.stamp.to_sec() == pytest.approx(100.25)
    assert (human.lmc_frame_id, human.nr_of_hands, human.nr_of_fingers) == (42, 1, 5)
    h = human.right_hand
    assert h.is_present and not human.left_hand.is_present
    assert h.lmc_hand_id == 7
    palm = (h.palm_center.x, h.palm_center.y, h.palm_center.z)
    assert palm == pytest.approx((0.012, 0.21, -0.03))
    assert list(h.palm_velocity) == pytest.approx([0.1, 0.0, -0.05])
    n, d = right.palm_normal, right.direction
    assert h.roll == pytest.approx(math.atan2(n[0], -n[1]))
    assert h.pitch == pytest.approx(math.atan2(d[1], -d[2]))
    assert h.yaw == pytest.approx(math.atan2(d[0], -d[2]))
    assert [f.type for f in h.finger_list] == [0, 1, 2, 3, 4]
    assert [f.lmc_finger_id for f in h.finger_list] == [70, 71, 72, 73, 74]
    index = h.finger_list[1]
    tip = index.bone_list[3].bone_end.position
    assert (tip.x, tip.y, tip.z) == pytest.approx(tuple(right.fingers[1].tip / 1000.0))
    assert index.length == pytest.approx(sum(b.length for b in index.bone_list))
    assert index.bone_list[3].bone_end.orientation.w == 1.0
    # Empty where no source measures it; the arm's poses are valid (identity).
    assert (h.palm_width, h.sphere_radius, list(h.sphere_center)) == (0.0, 0.0, [])
    assert h.arm.wrist.orientation.w == 1.0


def test_time_visible_and_the_frame_rate_follow_the_stamps():
    frames = [Frame(id=i, timestamp=10.0 + i / 50.0,
                    hands=[render_hand('left', 'fist', [0.0, 200.0, 0.0])] if i != 5 else [])
              for i in range(12)]
    out = [h for h, _ in run(frames)]
    assert out[4].left_hand.time_visible == pytest.approx(4 / 50.0)
    assert not out[5].left_hand.is_present
    assert out[6].left_hand.time_visible == 0.0           # found again
    assert out[11].left_hand.time_visible == pytest.approx(5 / 50.0)
    assert out[-1].current_frames_per_second == pytest.approx(50.0, rel=1e-3)


def test_a_recordings_sphere_widths_and_time_visible_reach_the_driver_hand():
    # LeapJS frames carry the SDK's sphere fit, time visible and finger widths: the driver
    # fills them, and a grasp detector reading sphere_radius got 0.
    from leap_teleop.hands.sources import leapjs
    d = leapjs.frame_to_dict(Frame(id=5, timestamp=2.0, hands=[
        render_hand('right', 'open', [10.0, 200.0, 0.0], hand_id=3)]))
    d['hands'][0].update(sphereRadius=80.5, sphereCenter=[1.0, 150.0, -20.0], timeVisible=12.25,
                         palmWidth=85.0)
    for i, p in enumerate(d['pointables']):
        p['width'] = 15.0 + i
    frame = leapjs.frame_from_dict(d)
    (raw, smooth), = run([frame], lowpass=LowPass(4.0))
    for h in (raw.right_hand, smooth.right_hand):
        assert h.sphere_radius == pytest.approx(0.0805)
        assert list(h.sphere_center) == pytest.approx([0.001, 0.15, -0.02])
        assert h.palm_width == pytest.approx(0.085)
        assert h.time_visible == pytest.approx(12.25)            # the SDK's, in s
        assert [f.width for f in h.finger_list] == pytest.approx([0.015, 0.016, 0.017, 0.018, 0.019])
        assert {b.width for f in h.finger_list for b in f.bone_list} == {0.0}   # not recorded
    back = leapjs.frame_to_dict(frame)
    assert {k: back['hands'][0][k] for k in ('sphereRadius', 'sphereCenter', 'timeVisible', 'palmWidth')} \
        == {'sphereRadius': 80.5, 'sphereCenter': [1.0, 150.0, -20.0], 'timeVisible': 12.25, 'palmWidth': 85.0}
    assert [p['width'] for p in back['pointables']] == [15.0, 16.0, 17.0, 18.0, 19.0]
    # LeapJS Playback 0.1 wrote the frame's timestamp (s) as timeVisible in every other frame:
    # not a measure, so time_visible goes on from the last one.
    later = dict(d, id=6, timestamp=2_010_000, hands=[dict(d['hands'][0], timeVisible=2.01)])
    h = run([frame, leapjs.frame_from_dict(later)])[1][0].right_hand
    assert h.time_visible == pytest.approx(12.26)
    # Values that are no measure stay unmeasured: 0 / empty, time_visible counted here.
    d['hands'][0].update(sphereRadius=-1.0, sphereCenter=[1.0, 'x'], timeVisible=None, palmWidth=True)
    d['pointables'][0]['width'] = [1]
    h = run([leapjs.frame_from_dict(d)])[0][0].right_hand
    assert (h.sphere_radius, list(h.sphere_center), h.palm_width, h.time_visible) == (0.0, [], 0.0, 0.0)
    assert h.finger_list[0].width == 0.0 and h.finger_list[1].width == pytest.approx(0.016)


def _vec(v):
    import types
    return types.SimpleNamespace(x=float(v[0]), y=float(v[1]), z=float(v[2]))


def test_the_leap_sdks_sizes_and_time_visible_reach_the_driver_hand():
    import types

    from leap_teleop.hands.sources import leap_sdk, leapc
    ns = types.SimpleNamespace
    src = render_hand('left', 'open', [0.0, 200.0, 0.0])

    def sdk_finger(t, f):
        joints = {0: f.mcp, 1: f.mcp, 2: f.pip, 3: f.dip}
        return ns(type=t, tip_position=_vec(f.tip), direction=_vec(f.direction), is_extended=True,
                  width=18.0, bone=lambda kind: ns(prev_joint=_vec(joints[kind]), width=20.0 - kind))

    Leap = ns(Bone=ns(TYPE_METACARPAL=0, TYPE_PROXIMAL=1, TYPE_INTERMEDIATE=2, TYPE_DISTAL=3))
    sdk = leap_sdk.convert_hand(Leap, ns(
        is_right=False, id=4, palm_position=_vec(src.palm_position), palm_velocity=_vec((0, 0, 0)),
        palm_normal=_vec(src.palm_normal), direction=_vec(src.direction), grab_strength=0.0,
        pinch_strength=0.0, confidence=1.0, palm_width=84.0, sphere_radius=70.0,
        sphere_center=_vec((5.0, 180.0, 10.0)), time_visible=3.5,
        fingers=[sdk_finger(t, f) for t, f in enumerate(src.fingers)]))

    def bone(a, b, w):
        return ns(prev_joint=_vec(a), next_joint=_vec(b), width=w)

    c = leapc.convert_hand(ns(HandType=ns(Left=0, Right=1)), ns(
        type=0, id=6, grab_strength=0.0, pinch_strength=0.0, confidence=1.0, visible_time=2_500_000,
        palm=ns(position=_vec(src.palm_position), velocity=_vec((0, 0, 0)), normal=_vec(src.palm_normal),
                direction=_vec(src.direction), width=82.0),
        digits=[ns(is_extended=True, metacarpal=bone(f.mcp, f.mcp, 21.0), proximal=bone(f.mcp, f.pip, 20.0),
                   intermediate=bone(f.pip, f.dip, 19.0), distal=bone(f.dip, f.tip, 18.0))
                for f in src.fingers]))
    h = run([Frame(id=1, timestamp=1.0, hands=[sdk])])[0][0].left_hand
    assert (h.palm_width, h.sphere_radius) == pytest.approx((0.084, 0.07))
    assert list(h.sphere_center) == pytest.approx([0.005, 0.18, 0.01])
    assert h.time_visible == pytest.approx(3.5)
    assert h.finger_list[2].width == pytest.approx(0.018)
    assert [b.width for b in h.finger_list[2].bone_list] == pytest.approx([0.02, 0.019, 0.018, 0.017])
    h = run([Frame(id=1, timestamp=1.0, hands=[c])])[0][0].left_hand
    assert h.palm_width == pytest.approx(0.082) and h.time_visible == pytest.approx(2.5)
    assert (h.sphere_radius, list(h.sphere_center)) == (0.0, [])          # LeapC has no sphere
    assert h.finger_list[0].width == 0.0                                    # nor a digit width
    assert [b.width for b in h.finger_list[0].bone_list] == pytest.approx([0.021, 0.02, 0.019, 0.018])


class FakePublisher:
    """A rospy.Publisher of the driver topics without a master: serialises what it is given
    (as rospy does with a subscriber) and keeps it; `listening` says whether anyone
    subscribes."""

    listening = True

    def __init__(self, topic, msg_type, queue_size=None):
        self.resolved_name = '/' + topic.lstrip('/')
        self.sent = []

    def get_num_connections(self):
        return int(self.listening)

    def publish(self, msg):
        serialized(msg)
        self.sent.append(msg)


def driver_topics(monkeypatch, **topics):
    """A LeapMotionTopics publishing on FakePublishers: the sender's defaults but `topics`."""
    import rospy

    from leap_teleop.hands.sender_params import SENDER_PARAMS
    from leap_teleop.ros.leap_motion_topics import LeapMotionTopics
    monkeypatch.setattr(rospy, 'Publisher', FakePublisher)
    p = {name: param.default for name, param in SENDER_PARAMS.items()}
    p.update(human_topic='', filtered_human_topic='', driver_marker_topic='')
    p.update(topics)
    return LeapMotionTopics(p, 1)


def test_time_visible_and_the_rate_restart_after_a_time_without_subscribers(monkeypatch):
    # While nobody subscribes the builder sees no frames: a hand that left and came back
    # meanwhile was reported visible since its first appearance, and the rate averaged the gap.
    topics = driver_topics(monkeypatch, human_topic='human')
    pub = topics.pubs['raw']
    li = LeapInterface()
    li.add_listener(topics.on_frame)
    for i in range(522):        # 100 Hz; gone 0.1 .. 5.1 s, back unheard until 5.2 s
        pub.listening = not 10 <= i < 520
        hands = [] if 10 <= i < 510 else [render_hand('right', 'open', [0.0, 200.0, 0.0], hand_id=5)]
        li.on_frame(Frame(id=i, timestamp=i / 100.0, hands=hands))
    first, second = pub.sent[-2:]
    assert (first.lmc_frame_id, second.lmc_frame_id) == (520, 521)
    assert first.right_hand.time_visible == 0.0 and first.current_frames_per_second == 0.0
    assert second.right_hand.time_visible == pytest.approx(0.01)
    assert second.current_frames_per_second == pytest.approx(100.0)


def test_a_frame_that_cannot_be_serialised_is_dropped_with_a_warning_not_the_sender(monkeypatch):
    # OverflowError from publish() (a float beyond float32) went up the source's thread and
    # ended the sender; now that frame's message is dropped, with a rate-limited warning.
    from leap_teleop.ros import leap_motion_topics
    topics = driver_topics(monkeypatch, human_topic='human', filtered_human_topic='smooth',
                           driver_marker_topic='markers')
    warned = []
    monkeypatch.setattr(leap_motion_topics.rospy, 'logwarn', lambda fmt, *a: warned.append(fmt % a))
    li = LeapInterface()
    li.add_listener(topics.on_frame)
    for i in range(6):
        hand = render_hand('right', 'open', [0.0, 200.0, 0.0], hand_id=5)
        frame = Frame(id=i, timestamp=1.0 + i / 100.0, hands=[hand])
        # A frame rate beyond float32 (no source's stamps give one) in frames 2 and 3.
        topics.builder._fps, topics.builder._last_stamp = (1e300 if i in (2, 3) else 0.0), None
        li.on_frame(frame)
    for kind in ('raw', 'filtered'):
        assert [m.lmc_frame_id for m in topics.pubs[kind].sent] == [0, 1, 4, 5], kind
    assert len(topics.pubs['markers'].sent) == 6
    assert len(warned) == 2 and 'frame 2 dropped from /human: it cannot be serialised' in warned[0]


class CapturedConnection:
    """What rospy's publisher writes to one subscriber's connection, kept in order."""

    endpoint_id = 'captured'
    cleanup_cb = None

    def __init__(self):
        self.data = b''

    def set_cleanup_callback(self, cb):
        self.cleanup_cb = cb

    def fileno(self):
        return None

    def write_data(self, data):
        self.data += bytes(data)

    def close(self):
        pass


@pytest.mark.filterwarnings('ignore:The publisher should be created')    # queue_size=None: synchronous
def test_a_dropped_message_leaves_the_next_ones_whole_on_the_wire(monkeypatch):
    # rospy serialises into one buffer per publisher and clears it only after a message
    # went out: the bytes of one that failed half-way went out in front of the next, and
    # every subscriber's connection was broken for good while the sender ran on.
    import struct

    import rospy
    import rospy.topics

    from leap_teleop.ros.hand_conversions import DriverHuman
    monkeypatch.setattr(rospy.topics, 'is_initialized', lambda: True)
    real = rospy.Publisher('/captured_human', DriverHuman, queue_size=None)
    wire = CapturedConnection()
    real.impl.add_connection(wire)
    try:
        topics = driver_topics(monkeypatch, human_topic='human')
        topics.pubs['raw'] = real
        li = LeapInterface()
        li.add_listener(topics.on_frame)
        for i in range(5):
            hand = render_hand('right', 'open', [0.0, 200.0, 0.0], hand_id=5)
            topics.builder._fps, topics.builder._last_stamp = (1e300 if i == 2 else 0.0), None
            li.on_frame(Frame(id=i, timestamp=1.0 + i / 100.0, hands=[hand]))
        data, ids = wire.data, []
        while data:
            (size,) = struct.unpack('<I', data[:4])
            ids.append(DriverHuman().deserialize(data[4:4 + size]).lmc_frame_id)
            data = data[4 + size:]
        assert ids == [0, 1, 3, 4]
    finally:
        real.unregister()


def test_recorded_sdk_gestures_go_to_their_hand_typed_and_staged():
    right = render_hand('right', 'open', [0.0, 200.0, 0.0], hand_id=3)
    left = render_hand('left', 'open', [50.0, 200.0, 0.0], hand_id=4)
    gestures = [{'id': 9, 'type': 'keyTap', 'state': 'stop', 'duration': 1500,
                 'handIds': [4], 'pointableIds': [41]},
                {'id': 10, 'type': 'swipe', 'state': 'update', 'handIds': [3]},
                {'id': 11, 'type': 'unknownType', 'state': 'start', 'handIds': [3]},
                {'id': 12, 'type': 'circle', 'state': 'start', 'handIds': [99]}]
    (human, _), = run([Frame(id=1, timestamp=1.0, hands=[right, left], gestures=gestures)])
    (key,) = human.left_hand.gesture_list
    assert (key.lmc_gesture_id, key.gesture_type, key.gesture_state) == (9, 6, 3)
    assert (key.duration_us, key.duration_s, list(key.pointable_ids)) == (1500, 0.0015, [41])
    (swipe,) = human.right_hand.gesture_list
    assert (swipe.gesture_type, swipe.gesture_state, swipe.is_valid) == (1, 2, True)
    assert human.nr_of_gestures == 2
    assert human.left_hand.valid_gestures and human.right_hand.valid_gestures


def serialized(msg):
    import io
    buf = io.BytesIO()
    msg.serialize(buf)
    return buf.getvalue()


def test_recorded_values_of_any_shape_or_size_still_make_a_message():
    # Each of these ended the sender's source thread (one frame ended the session): a
    # gesture type or state that is a list or an object (unhashable), a duration beyond
    # int64 microseconds, and a velocity, tip or joint beyond float32.
    hand = render_hand('right', 'open', [0.0, 200.0, 0.0], velocity=[1e40, -1e40, 0.0], hand_id=3)
    index = hand.fingers[1]
    hand.fingers = hand.fingers[:1] + (Finger(tip=np.array([1e200, 0.0, 0.0]),
                                              direction=index.direction, mcp=np.array([1e300, 0.0, 0.0]),
                                              pip=index.pip, dip=index.dip),) + hand.fingers[2:]
    gestures = [{'id': 1, 'type': ['swipe'], 'state': 'stop', 'handIds': [3]},
                {'id': 2, 'type': 'swipe', 'state': {'a': 1}, 'handIds': [3]},
                {'id': 3, 'type': 'keyTap', 'state': 'stop', 'duration': 2 ** 63, 'handIds': [3]},
                {'id': 4, 'type': 'keyTap', 'state': 'stop', 'duration': 10 ** 400, 'handIds': [3]},
                {'id': 5, 'type': 'keyTap', 'state': 'stop', 'duration': math.inf, 'handIds': [3]}]
    (human, _), = run([Frame(id=1, timestamp=1.0, hands=[hand], gestures=gestures)])
    assert serialized(human)
    h = human.right_hand
    assert h.is_present and list(h.palm_velocity) == [0.0, 0.0, 0.0]    # no speed of 1e37 m/s
    assert h.finger_list == []                                       # no usable joints
    assert [(g.lmc_gesture_id, g.gesture_state, g.duration_us) for g in h.gesture_list] == [
        (2, -1, 0), (3, 3, 2 ** 63 - 1), (4, 3, 2 ** 63 - 1), (5, 3, 0)]


def test_sizes_and_time_visible_beyond_any_hand_are_unmeasured_from_any_source():
    # A source's sphere radius (or centre, a width, time visible) of 1e300 was copied into
    # DriverHand's float32 fields: serialize() raised OverflowError and ended the sender.
    hand = render_hand('right', 'open', [0.0, 200.0, 0.0], hand_id=3)
    hand.palm_width, hand.sphere_radius, hand.time_visible = 1e300, 1e300, 1e300
    hand.sphere_center = np.array([0.0, 1e300, 0.0])
    hand.fingers[1].width, hand.fingers[2].bone_widths = 1e300, (10.0, 1e300, 9.0, 8.0)
    (raw, smooth), = run([Frame(id=1, timestamp=5.0, hands=[hand])], lowpass=LowPass(4.0))
    for human in (raw, smooth):
        assert serialized(human)
        h = human.right_hand
        assert (h.palm_width, h.sphere_radius, list(h.sphere_center), h.time_visible) == (0.0, 0.0, [], 0.0)
        assert h.finger_list[1].width == 0.0
        assert [b.width for b in h.finger_list[2].bone_list] == pytest.approx([0.01, 0.0, 0.009, 0.008])


def test_leapros_and_the_drivers_human_take_one_bound_for_a_joint():
    # A knuckle between 2000 mm and 1e6 mm was zero in leapros but a 50-500 m bone in the
    # driver's Human.
    from leap_teleop.hands.tracker import MAX_PALM_MM
    for x, kept in ((skeleton.MAX_JOINT, True), (skeleton.MAX_JOINT + 1.0, False), (5e4, False),
                    (5e5, False)):
        hand = render_hand('right', 'open', [0.0, 200.0, 0.0], hand_id=3)
        hand.fingers[1].mcp = np.array([x, 200.0, -20.0])
        s = LeapInterface().on_frame(Frame(id=1, timestamp=1.0, hands=[hand]))['right']
        leapros = hand_conversions.to_leapros(s, hand)
        (human, _), = run([Frame(id=1, timestamp=1.0, hands=[hand])])
        assert (leapros.index_proximal.x == x) is kept, x
        assert bool(human.right_hand.finger_list) is kept, x
        if kept:
            assert human.right_hand.finger_list[1].bone_list[1].bone_start.position.x == x / 1000.0
    assert skeleton.MAX_JOINT == MAX_PALM_MM        # the tracker's bound of a palm, too


def _huge_take():
    """LeapJS frame dicts of two hands with every field a recording can carry (sizes, sphere,
    time visible, an SDK gesture), and the path of each number in them."""
    d = leapjs.frame_to_dict(Frame(id=1, timestamp=5.0, hands=[
        render_hand('right', 'open', [0.0, 200.0, 0.0], hand_id=1),
        render_hand('left', 'fist', [80.0, 200.0, 0.0], hand_id=2)]))
    for h in d['hands']:
        h.update(palmWidth=85.0, sphereRadius=70.0, sphereCenter=[0.0, 180.0, 0.0], timeVisible=1.5)
    for p in d['pointables']:
        p.update(width=15.0, length=50.0)
    d['gestures'] = [{'id': 3, 'type': 'circle', 'state': 'update', 'duration': 1000, 'handIds': [1],
                      'pointableIds': [11], 'radius': 20.0, 'progress': 1.0, 'center': [0, 200, 0],
                      'normal': [0, 0, 1]}]

    def paths(obj, prefix=()):
        items = obj.items() if isinstance(obj, dict) else enumerate(obj) if isinstance(obj, list) else None
        if items is not None:
            for k, v in items:
                yield from paths(v, prefix + (k,))
        elif isinstance(obj, (int, float)) and not isinstance(obj, bool) and prefix != ('timestamp',):
            yield prefix
    return d, list(paths(d))


@pytest.mark.parametrize('huge', [1e300, -1e300, 2 ** 70])
def test_huge_values_in_any_field_of_a_recording_leave_every_sent_message_serialisable(tmp_path, huge):
    # Each field of a recorded frame in turn holds a finite value beyond float32 (or an
    # integer beyond 64 bits), between clean frames, played by the recording source: every
    # message the sender publishes (leapcobot, Hand, GestureEvent, leapros, leap, the
    # driver's Human raw and filtered, its markers) must serialise. Sizes did not.
    import copy
    import io

    from leap_teleop.hands.sources import make_source
    base, paths = _huge_take()
    frames = []
    for k, path in enumerate(paths):
        clean, bad = copy.deepcopy(base), copy.deepcopy(base)
        obj = bad
        for key in path[:-1]:
            obj = obj[key]
        obj[path[-1]] = huge
        for i, f in enumerate((clean, bad)):
            f.update(id=2 * k + i + 1, timestamp=5_000_000 + (2 * k + i) * 10_000)
            frames.append(f)
    leapjs.save(str(tmp_path / 'huge.json'), frames)
    source = make_source('recording', path=str(tmp_path / 'huge.json'), realtime=False, clock=lambda: 100.0)
    builder, lowpass, failed = hand_conversions.DriverHumanBuilder(), LowPass(4.0), set()

    def on_frame(frame, states):
        raw, smooth = builder.human_msgs(frame, states, lowpass=lowpass)
        msgs = [('human', raw), ('filtered human', smooth), ('markers', driver_markers(smooth))]
        for side, state in states.items():
            msgs += list(hand_conversions.hand_messages(state))
            msgs += [('leapros', hand_conversions.to_leapros(state, frame.hand(side))),
                     ('leap', hand_conversions.to_leap(state))]
        for kind, msg in msgs:
            try:
                msg.serialize(io.BytesIO())
            except Exception as e:
                failed.add((kind, paths[(frame.id - 1) // 2], type(e).__name__))

    li = LeapInterface()
    li.add_listener(on_frame)
    n = 0
    for frame in source.frames():
        li.on_frame(frame)
        n += 1
    assert n == 2 * len(paths) and source.bad_frames == 0
    assert not failed, sorted(failed)


def test_the_recognizers_circles_are_the_drivers_circle_others_have_no_gesture():
    builder = hand_conversions.DriverHumanBuilder()
    hand = render_hand('right', 'open', [0.0, 200.0, 0.0], hand_id=5)
    frame = Frame(id=1, timestamp=1.0, hands=[hand])
    events = tuple(HandEvent(g) for g in ('circle_cw', 'fold', 'hand_found', 'circle_ccw'))
    state = HandState('right', present=True, timestamp=1.0, frame_id=1,
                      palm_position=(0.0, 200.0, 0.0), palm_normal=(0.0, -1.0, 0.0),
                      direction=(0.0, 0.0, -1.0), events=events)
    human, _ = builder.human_msgs(frame, {'right': state})
    got = human.right_hand.gesture_list
    assert [(g.gesture_type, g.gesture_state) for g in got] == [(4, 3), (4, 3)]
    assert got[0].lmc_gesture_id != got[1].lmc_gesture_id
    assert list(got[0].pointable_ids) == [51]              # the index finger


def test_a_side_that_is_not_published_or_not_placeable_is_absent():
    right = render_hand('right', 'open', [0.0, 200.0, 0.0])
    bad = render_hand('left', 'open', [0.0, 200.0, 0.0])
    bad.palm_position = np.array([math.nan, 0.0, 0.0])
    out = []
    li = LeapInterface(sides=['left'])
    builder = hand_conversions.DriverHumanBuilder()
    li.add_listener(lambda f, s: out.append(builder.human_msgs(f, s)[0]))
    li.on_frame(Frame(id=1, timestamp=1.0, hands=[right, bad]))
    assert not out[0].right_hand.is_present and not out[0].left_hand.is_present
    assert out[0].nr_of_hands == 0


def test_a_hand_without_joints_has_no_fingers_but_its_palm():
    hand = render_hand('right', 'open', [0.0, 200.0, 0.0])
    hand.fingers = tuple(Finger(tip=f.tip, direction=f.direction) for f in hand.fingers)
    (human, filtered), = run([Frame(id=1, timestamp=1.0, hands=[hand])], lowpass=LowPass())
    for msg in (human, filtered):
        assert msg.right_hand.is_present and msg.right_hand.finger_list == []
        assert msg.nr_of_fingers == 0
        assert msg.right_hand.palm_center.y == pytest.approx(0.2)


def test_filtered_human_smooths_palm_and_joints_and_keeps_bones_chained():
    frames = [Frame(id=i, timestamp=i / 100.0,
                    hands=[render_hand('right', 'open', [0.0 if i < 5 else 40.0, 200.0, 0.0])])
              for i in range(30)]
    out = run(frames, lowpass=LowPass(4.0))
    raw, smooth = zip(*out)
    assert smooth[0].right_hand.palm_center == raw[0].right_hand.palm_center
    assert 0.0 < smooth[6].right_hand.palm_center.x < raw[6].right_hand.palm_center.x
    assert smooth[-1].right_hand.palm_center.x == pytest.approx(0.04, abs=1e-4)
    for f in smooth[6].right_hand.finger_list:
        for prev, bone in zip(f.bone_list, f.bone_list[1:]):
            assert bone.bone_start.position == prev.bone_end.position
    # The raw message is untouched by the filter.
    assert raw[6].right_hand.palm_center.x == pytest.approx(0.04)


def test_leap_message_is_leap_mm_and_degrees_as_the_leapros():
    s = LeapInterface().on_frame(Frame(id=1, timestamp=2.0, hands=[
        render_hand('right', 'open', [10.0, 220.0, -5.0], normal=[0.3, -0.9, 0.1],
                    direction=[0.2, 0.3, -0.9])]))['right']
    msg = hand_conversions.to_leap(s)
    assert list(msg.hand_palm_pos) == [10.0, 220.0, -5.0]
    n, d = s.palm_normal, s.direction
    # The classic sender's: roll and pitch of the direction, yaw of the normal.
    assert (msg.hand_roll, msg.hand_pitch, msg.hand_yaw) == pytest.approx(tuple(
        math.degrees(a) for a in (math.atan2(d[0], -d[1]), math.atan2(d[1], -d[2]),
                                  math.atan2(n[0], -n[2]))))
    ypr = hand_conversions.to_leapros(s).ypr
    assert (msg.hand_yaw, msg.hand_pitch, msg.hand_roll) == pytest.approx((ypr.x, ypr.y, ypr.z))
    absent = hand_conversions.to_leap(HandState('right', timestamp=3.0))
    assert list(absent.hand_palm_pos) == [0.0, 0.0, 0.0] and absent.header.stamp.to_sec() == 3.0


# --- the visualizer's markers --------------------------------------------------------------
def test_driver_markers_draw_palm_knuckles_bones_and_joints_per_present_hand():
    (human, _), = run([Frame(id=1, timestamp=1.0, hands=[
        render_hand('left', 'open', [0.0, 200.0, 0.0])])])
    markers = driver_markers(human).markers
    names = {(m.ns, m.id) for m in markers}
    assert ('Left', 0) in names and ('Left', 1) in names
    assert not any(m.ns.startswith('Right') for m in markers)
    for finger in ('Thumb', 'Index', 'Middle', 'Ring', 'Pinky'):
        assert ('Left_' + finger, 0) in names and ('Left_' + finger, 1) in names
    palm = next(m for m in markers if (m.ns, m.id) == ('Left', 0))
    assert palm.pose.position.y == pytest.approx(0.2)
    assert all(m.header.frame_id == 'leap_hands' and m.lifetime.to_sec() == pytest.approx(0.1)
               for m in markers)
    index = next(m for m in markers if (m.ns, m.id) == ('Left_Index', 0))
    assert len(index.points) == 8                          # four bones, two ends each
    joints = next(m for m in markers if (m.ns, m.id) == ('Left_Index', 1))
    assert len(joints.points) == 4                         # mcp, pip, dip, tip


def test_driver_markers_refuse_non_finite_points():
    (human, _), = run([Frame(id=1, timestamp=1.0, hands=[
        render_hand('right', 'open', [0.0, 200.0, 0.0])])])
    human.right_hand.finger_list[2].bone_list[3].bone_end.position.x = math.nan
    with pytest.raises(ValueError):
        driver_markers(human)


# --- the carpal joint: the metacarpal's base ---------------------------------------------
CARPAL_OFFSET = np.array([0.0, -20.0, 60.0])      # mm from the knuckle, toward the wrist


def _carpal_hand(x=0.0, side='right', hand_id=3):
    """A hand whose fingers but the thumb have a carpal joint (a Leap's thumb: none apart)."""
    hand = render_hand(side, 'open', [x, 200.0, 0.0], hand_id=hand_id)
    for f in hand.fingers[1:]:
        f.carpal = f.mcp + CARPAL_OFFSET
    return hand


def _bone(bone):
    s, e = bone.bone_start.position, bone.bone_end.position
    return np.array([s.x, s.y, s.z]), np.array([e.x, e.y, e.z])


def test_the_carpal_joint_starts_the_metacarpal_raw_and_filtered():
    # The driver's metacarpal runs from the carpal joint (prevJoint) to the knuckle, with its
    # length; every one here had length 0 where the source measured the carpal joint.
    hand = _carpal_hand()
    (raw, smooth), = run([Frame(id=1, timestamp=1.0, hands=[hand])], lowpass=LowPass(4.0))
    for human in (raw, smooth):
        fingers = human.right_hand.finger_list
        for i in (1, 2, 3, 4):
            start, end = _bone(fingers[i].bone_list[0])
            np.testing.assert_allclose(start, hand.fingers[i].carpal / 1000.0)
            np.testing.assert_allclose(end, hand.fingers[i].mcp / 1000.0)
            assert fingers[i].bone_list[0].length == pytest.approx(np.linalg.norm(CARPAL_OFFSET) / 1000.0)
            assert fingers[i].length == pytest.approx(sum(b.length for b in fingers[i].bone_list))
            assert fingers[i].bone_list[0].to_string == 'metacarpal bone length:63.2 mm'
        # Unknown (the thumb here): as before, the knuckle, length 0.
        start, end = _bone(fingers[0].bone_list[0])
        assert start.tolist() == end.tolist() and fingers[0].bone_list[0].length == 0.0
        assert serialized(human)
    # The skeleton alone: a hand without carpal joints keeps today's bones exactly.
    plain = render_hand('right', 'open', [0.0, 200.0, 0.0], hand_id=3)
    joints = skeleton.hand_joints(plain)
    for a, b in zip(skeleton.bone_ends(joints), skeleton.bone_ends(joints, skeleton.hand_carpals(plain, joints))):
        assert np.array_equal(a, b)


def test_a_carpal_joint_that_is_no_joint_leaves_that_metacarpal_at_the_knuckle():
    hand = _carpal_hand()
    hand.fingers[1].carpal = np.array([0.0, 1e300, 0.0])
    hand.fingers[2].carpal = np.array([math.nan, 0.0, 0.0])
    hand.fingers[3].carpal = np.array([skeleton.MAX_JOINT + 1.0, 0.0, 0.0])
    hand.fingers[4].carpal = [1.0, 2.0]
    (raw, smooth), = run([Frame(id=1, timestamp=1.0, hands=[hand])], lowpass=LowPass(4.0))
    for human in (raw, smooth):
        assert serialized(human)
        assert [f.bone_list[0].length for f in human.right_hand.finger_list] == [0.0] * 5
        assert human.right_hand.finger_list[1].bone_list[1].length > 0.0     # the rest stays
    s = LeapInterface().on_frame(Frame(id=1, timestamp=1.0, hands=[hand]))['right']
    msg = hand_conversions.to_leapros(s, hand)
    assert [(p.x, p.y, p.z) for p in (msg.index_metacarpal, msg.middle_metacarpal, msg.ring_metacarpal,
                                      msg.pinky_metacarpal)] == [(0, 0, 0)] * 4


def test_the_filtered_human_low_passes_the_carpal_joints_as_the_others():
    frames = [Frame(id=i, timestamp=i / 100.0, hands=[_carpal_hand(0.0 if i < 5 else 40.0)])
              for i in range(40)]
    raw, smooth = zip(*run(frames, lowpass=LowPass(4.0)))
    for k in range(40):
        for i in (1, 4):
            carpal = _bone(smooth[k].right_hand.finger_list[i].bone_list[0])[0]
            knuckle = _bone(smooth[k].right_hand.finger_list[i].bone_list[1])[0]
            raw_carpal = _bone(raw[k].right_hand.finger_list[i].bone_list[0])[0]
            if k == 6:          # on its way to the hand's new place, behind it (40 mm to go)
                assert 0.0 < carpal[0] - (raw_carpal[0] - 0.04) < 0.02
            # moved as its knuckle: the metacarpal keeps its length while it is filtered
            np.testing.assert_allclose(knuckle - carpal, CARPAL_OFFSET / -1000.0, atol=1e-9)
    last = _bone(smooth[-1].right_hand.finger_list[2].bone_list[0])[0]
    np.testing.assert_allclose(last, (frames[-1].hands[0].fingers[2].carpal) / 1000.0, atol=1e-4)


def test_the_leap_sdks_carpal_joint_reaches_the_frame_bounded():
    import types

    from leap_teleop.hands.sources import leap_sdk, leapc
    ns = types.SimpleNamespace
    src = render_hand('right', 'open', [0.0, 200.0, 0.0])
    carpals = [f.mcp + CARPAL_OFFSET for f in src.fingers]
    carpals[2] = np.array([0.0, 1e300, 0.0])                # beyond any hand: none
    carpals[3] = np.array([0.0, math.nan, 0.0])

    def sdk_finger(t, f):
        joints = {0: carpals[t], 1: f.mcp, 2: f.pip, 3: f.dip}
        return ns(type=t, tip_position=_vec(f.tip), direction=_vec(f.direction), is_extended=True,
                  width=18.0, bone=lambda kind: ns(prev_joint=_vec(joints[kind]), width=18.0))

    def bone(a, b):
        return ns(prev_joint=_vec(a), next_joint=_vec(b), width=18.0)

    Leap = ns(Bone=ns(TYPE_METACARPAL=0, TYPE_PROXIMAL=1, TYPE_INTERMEDIATE=2, TYPE_DISTAL=3))
    sdk = leap_sdk.convert_hand(Leap, ns(
        is_right=True, id=4, palm_position=_vec(src.palm_position), palm_velocity=_vec((0, 0, 0)),
        palm_normal=_vec(src.palm_normal), direction=_vec(src.direction), grab_strength=0.0,
        pinch_strength=0.0, confidence=1.0, fingers=[sdk_finger(t, f) for t, f in enumerate(src.fingers)]))
    c = leapc.convert_hand(ns(HandType=ns(Left=0, Right=1)), ns(
        type=1, id=6, grab_strength=0.0, pinch_strength=0.0, confidence=1.0,
        palm=ns(position=_vec(src.palm_position), velocity=_vec((0, 0, 0)), normal=_vec(src.palm_normal),
                direction=_vec(src.direction)),
        digits=[ns(is_extended=True, metacarpal=bone(carpals[t], f.mcp), proximal=bone(f.mcp, f.pip),
                   intermediate=bone(f.pip, f.dip), distal=bone(f.dip, f.tip))
                for t, f in enumerate(src.fingers)]))
    for hand in (sdk, c):
        got = [f.carpal for f in hand.fingers]
        assert got[2] is None and got[3] is None
        for i in (0, 1, 4):
            np.testing.assert_allclose(got[i], carpals[i])
        (human, _), = run([Frame(id=1, timestamp=1.0, hands=[hand])])
        lengths = [f.bone_list[0].length for f in human.right_hand.finger_list]
        assert lengths[2:4] == [0.0, 0.0]
        assert lengths[1] == pytest.approx(np.linalg.norm(CARPAL_OFFSET) / 1000.0)
    # A binding whose metacarpal bone fails keeps the other joints.
    def failing(t, f):
        finger = sdk_finger(t, f)
        inner = finger.bone
        finger.bone = lambda kind: (_ for _ in ()).throw(RuntimeError('no bone')) if kind == 0 else inner(kind)
        return finger
    sdk = leap_sdk.convert_hand(Leap, ns(
        is_right=True, id=4, palm_position=_vec(src.palm_position), palm_velocity=_vec((0, 0, 0)),
        palm_normal=_vec(src.palm_normal), direction=_vec(src.direction), grab_strength=0.0,
        pinch_strength=0.0, confidence=1.0, fingers=[failing(t, f) for t, f in enumerate(src.fingers)]))
    assert all(f.carpal is None and f.mcp is not None for f in sdk.fingers)
    assert skeleton.hand_joints(sdk) is not None


def test_the_carpal_joint_feeds_no_gesture():
    # The gesture models were fitted without it: the recognizer's states are the same.
    from leap_teleop.hands.gestures import GestureRecognizer
    a, b = GestureRecognizer(), GestureRecognizer()
    for i in range(30):
        plain = render_hand('right', 'fist' if i < 15 else 'open', [float(i), 200.0, 0.0], hand_id=3)
        with_carpals = _carpal_hand(float(i))
        with_carpals.fingers = tuple(Finger(**{**vars(f), 'carpal': g.carpal})
                                     for f, g in zip(plain.fingers, with_carpals.fingers))
        sa, sb = a.update(plain, i / 100.0), b.update(with_carpals, i / 100.0)
        assert repr(sa) == repr(sb)
