"""What the sender's ~params build, without a ROS master: the hand source, the recognizers
and their retuning, the ~freq throttle; and the arm's joint_states lookup."""
import os
import sys

import pytest
from test_sources_recording import _fake_leap_v2, _fake_leapc, _take

from leap_teleop.hands.sender_params import SENDER_PARAMS, SENDER_RECONFIGURABLE
from leap_teleop.hands.sender_setup import (
    PeriodThrottle,
    build_source,
    check_outputs,
    checked_bindings,
    recognizer_factory,
    retune_recognizers,
    retune_sender,
)
from leap_teleop.hands.sources import SourceError
from leap_teleop.params import check_params
from leap_teleop.ur10.joint_states import JointStateIndex
from leap_teleop.ur10.kinematics import JOINT_NAMES

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
WAVE = os.path.join(ROOT, 'config', 'gestures', 'wave_hello.yaml')


def params(**values):
    return check_params(SENDER_PARAMS, values)


def test_the_scripted_source_defaults_to_the_given_script_and_runs_on_the_clock():
    source = build_source(params(realtime=False), lambda: 0.0, WAVE)
    assert type(source).__name__ == 'ScriptedSource'
    other = build_source(params(script=os.path.join(ROOT, 'config', 'gestures', 'sender_script.yaml'),
                                realtime=False), lambda: 0.0, '/no/such/default.yaml')
    assert type(other).__name__ == 'ScriptedSource'


def test_a_scripted_source_is_told_the_sides_the_sender_publishes(caplog, tmp_path):
    # A script with no hand of a published side plays nothing there, with no word: the
    # source warns, once it knows the sides.
    single = tmp_path / 'right_only.yaml'
    single.write_text('hands:\n  right:\n    - {pose: open, duration: 1.0}\n')
    with caplog.at_level('WARNING'):
        build_source(params(script=str(single), sides=['left'], realtime=False), lambda: 0.0, WAVE)
    assert any('has no left hand' in r.getMessage() for r in caplog.records), caplog.records


@pytest.mark.parametrize('name, module, fake', [('leap', 'Leap', _fake_leap_v2),
                                                ('leapc', 'leap', _fake_leapc)])
def test_a_device_source_stamps_its_frames_on_the_senders_clock(name, module, fake, monkeypatch):
    # Under /use_sim_time the sender's clock is the graph's; the devices stamped with
    # time.time(), decades away from it.
    monkeypatch.setitem(sys.modules, module, fake())
    ticks = iter(range(10 ** 6))
    source = build_source(params(source=name), lambda: 1234.5 + 0.001 * next(ticks), WAVE)
    frames = _take(source, 5)
    assert len(frames) == 5 and all(1234.5 <= f.timestamp < 1240.0 for f in frames)


@pytest.mark.parametrize('values, says', [({'source': 'recording'}, 'needs ~recording'),
                                          ({'source': 'video'}, 'needs ~video'),
                                          ({'source': 'webcam', 'width': 0}, '~width 0 and ~height 480')])
def test_a_source_missing_its_file_says_which_parameter(values, says):
    asked = []
    with pytest.raises(SourceError) as e:
        build_source(params(**values), lambda: 0.0, WAVE, camera_model=lambda: asked.append(1))
    assert says in str(e.value) and not asked     # no CameraInfo wait for a bad parameter


def test_leapros_must_carry_a_published_side():
    check_outputs(params(leapros_topic='leapmotion/data', sides=['right']))
    with pytest.raises(ValueError, match='leapros_side'):
        check_outputs(params(leap_topic='leapmotion/raw', sides=['left']))


def test_a_side_twice_or_two_outputs_on_one_topic_are_refused():
    # both were taken: two message types on one topic, or one hand published twice
    with pytest.raises(ValueError, match=r"~sides \['right', 'right'\]: each side once"):
        check_outputs(params(sides=['right', 'right']))
    with pytest.raises(ValueError, match="~leapcobot_topic_right and ~hand_topic_right are both"):
        check_outputs(params(leapcobot_topic_right='samepub', hand_topic_right='samepub'))
    with pytest.raises(ValueError, match='~hand_topic_left and ~leapros_topic are both'):
        check_outputs(params(leapros_topic='leapmotion/hand_left'))
    # a side not published may share its topic name: nothing goes out on it
    check_outputs(params(sides=['right'], hand_topic_left='leapmotion/hand_right'))


def test_two_outputs_are_compared_as_the_node_resolves_their_topics():
    # In the root namespace '/leapmotion/data_right' and 'leapmotion/data_right' are one
    # topic (rospy would put Hand and leapcobot messages on it); elsewhere they are two.
    import rospy.names
    values = dict(hand_topic_right='/leapmotion/data_right', leapcobot_topic_right='leapmotion/data_right')
    check_outputs(params(**values))                                        # names as given
    with pytest.raises(ValueError, match="both '/leapmotion/data_right'"):
        check_outputs(params(**values), lambda t: rospy.names.ns_join('/', t))
    check_outputs(params(**values), lambda t: rospy.names.ns_join('/robot1', t))


def test_a_static_tf_from_a_frame_to_itself_is_refused():
    # it was taken, and tf2 listeners then complained of TF_SELF_TRANSFORM
    with pytest.raises(ValueError, match="~world_frame and ~frame_id are both 'world'"):
        check_outputs(params(frame_id='world', world_frame='world'))
    with pytest.raises(ValueError, match='both'):
        check_outputs(params(frame_id='/world', world_frame='world'))
    check_outputs(params(frame_id='world', world_frame='world', publish_tf=False))


def test_recognizers_are_built_and_retuned_from_the_params():
    make = recognizer_factory(params(recognizer_on_frames=5, recognizer_min_confidence=0.2))
    a, b = make(), make()
    assert a is not b and a.filter.on_frames == 5 and a.min_confidence == 0.2
    retune_recognizers([a, b], {'recognizer_off_frames': 7, 'recognizer_min_confidence': 0.6,
                                'filter_cutoff': 3.0})
    assert all(r.filter.off_frames == 7 and r.min_confidence == 0.6 for r in (a, b))
    assert a.filter.on_frames == 5
    assert set(SENDER_RECONFIGURABLE) == {'recognizer_on_frames', 'recognizer_off_frames',
                                          'recognizer_min_confidence', 'filter_cutoff'}


def test_the_senders_retune_reaches_the_recognizers_and_the_driver_filter():
    from leap_teleop.control.lowpass import LowPass
    make = recognizer_factory(params())
    recognizers, lowpass = [make(), make()], LowPass(4.0)
    retune_sender(recognizers, lowpass, {'recognizer_on_frames': 9})
    assert all(r.filter.on_frames == 9 for r in recognizers) and lowpass.cutoff == 4.0
    retune_sender(recognizers, lowpass, {'filter_cutoff': 1.5})
    assert lowpass.cutoff == 1.5


def test_the_period_throttle_lets_one_frame_per_period_and_key():
    t = PeriodThrottle(0.1)
    got = [(key, ts) for ts in (0.0, 0.05, 0.1, 0.12, 0.25) for key in ('right', 'left')
           if t.due(key, ts)]
    assert got == [('right', 0.0), ('left', 0.0), ('right', 0.1), ('left', 0.1),
                   ('right', 0.25), ('left', 0.25)]
    every = PeriodThrottle(0.0)
    assert all(every.due('right', 0.0) for _ in range(3))


def test_the_period_throttle_starts_afresh_when_time_goes_back():
    # A /clock that restarts: the frames after it were held back for as long as the
    # clock had run before.
    t = PeriodThrottle(0.25)
    stamps = [100.0, 100.125, 100.25, 5.0, 5.125, 5.25, 5.5]
    assert [ts for ts in stamps if t.due('right', ts)] == [100.0, 100.25, 5.0, 5.25, 5.5]


def test_joint_states_are_found_by_name_prefix_and_order():
    index = JointStateIndex()
    names = ['ur10_1_gripper_joint'] + ['ur10_1_' + n for n in reversed(JOINT_NAMES)]
    positions = [9.0] + [float(i) for i in range(6)]
    assert index.positions(names, positions) == [5.0, 4.0, 3.0, 2.0, 1.0, 0.0]
    assert index.positions(['arm/' + n for n in JOINT_NAMES], list(range(6))) == list(range(6))
    with pytest.raises(KeyError) as e:
        index.positions(JOINT_NAMES[:5], list(range(5)))
    assert e.value.args[0] == JOINT_NAMES[5]
    # Velocities in the same order, or None when the message carries none.
    velocities = [0.5] + [0.1 * i for i in range(6)]
    assert index.velocities(names, velocities) == pytest.approx([0.5, 0.4, 0.3, 0.2, 0.1, 0.0])
    assert index.velocities(names, []) is None
    # a list as long as the last one with other names is looked up afresh (it was taken
    # for the last one's order)
    other = ['ur10_1_' + n for n in JOINT_NAMES] + ['ur10_1_gripper_joint']
    assert index.positions(other, [float(i) for i in range(7)]) == [0.0, 1.0, 2.0, 3.0, 4.0, 5.0]
    # fewer positions than names: an error that says so (it was an IndexError, or the
    # wrong joints when the missing ones came last)
    with pytest.raises(ValueError, match='7 names but 3 positions'):
        index.positions(other, [0.0, 1.0, 2.0])
    # one error for all that is wrong with a message, as the arm node logs it
    with pytest.raises(ValueError, match='^it lacks shoulder_pan_joint$'):
        index.state(['gripper'], [0.0], [])
    assert index.state(other, [float(i) for i in range(7)], []) == ([0.0, 1.0, 2.0, 3.0, 4.0,
                                                                     5.0], None)


def test_an_arm_finds_its_own_joints_in_a_list_of_two_arms():
    # joint_states remapped to a merged topic: ur10_2's arm took ur10_1's positions (the
    # first name ending in the joint's), and planned from the other arm's pose.
    names = ['ur10_1_' + n for n in JOINT_NAMES] + ['ur10_2_' + n for n in JOINT_NAMES]
    positions = [float(i) for i in range(12)]
    assert JointStateIndex('ur10_2_').positions(names, positions) == positions[6:]
    assert JointStateIndex('ur10_1_').positions(names, positions) == positions[:6]
    # without a prefix the list is refused, not read as the first arm's
    with pytest.raises(ValueError, match='shoulder_pan_joint comes 2 times .*set ~joint_prefix'):
        JointStateIndex().state(names, positions, [])
    # a prefix and a driver that publishes bare names: still found
    assert JointStateIndex('ur10_1_').positions(list(JOINT_NAMES), list(range(6))) == list(range(6))
    with pytest.raises(ValueError, match='it lacks shoulder_pan_joint'):
        JointStateIndex('ur10_3_').state(names, positions, [])


def test_a_throttled_sender_still_sends_every_gesture_event_and_every_hand_that_comes_or_goes():
    # With ~freq a frame inside the period was dropped whole: its fold or hand_lost event
    # with it, and the one hand-less frame between a recording's passes.
    import types

    from leap_teleop.hands.gestures import HandEvent
    from leap_teleop.hands.tracker import HandState
    from leap_teleop.ros import hand_conversions
    from leap_teleop.ros.hand_topics import HandTopics
    sent = []
    pub = types.SimpleNamespace(publish=sent.append)
    topics = types.SimpleNamespace(
        pubs={'right': {'leapcobot': pub, 'hand': pub, 'gesture': pub}},
        ages=types.SimpleNamespace(add=lambda *a: None), clock=lambda: 0.0,
        throttle=PeriodThrottle(0.25), _present_sent={}, p={'frame_id': 'leap'},
        _leapcobot={'right': hand_conversions.LEAPCOBOT_TYPES['right']()},
        leapros_side='', published=0)
    states = [HandState('right', True, 0.01 * i, i, palm_position=(0.0, 200.0, 0.0))
              for i in range(10)]
    states[3] = HandState('right', True, 0.03, 3, palm_position=(0.0, 200.0, 0.0),
                          events=(HandEvent('fold'),))
    states[6] = HandState('right', False, 0.06, 6, events=())
    for state in states:
        HandTopics.on_hand(topics, types.SimpleNamespace(timestamp=state.timestamp), state)
    hands = [m for m in sent if type(m).__name__ == 'Hand']
    gestures = [m.gesture for m in sent if type(m).__name__ == 'GestureEvent']
    assert gestures == ['fold']
    assert [(round(m.header.stamp.to_sec(), 2), m.present) for m in hands] == [
        (0.0, True), (0.03, True), (0.06, False), (0.07, True)]


@pytest.mark.parametrize('freq', [0.0, 0.1])
def test_leapros_and_leap_keep_the_last_pose_seen_while_their_hand_is_away(freq):
    # The classic sender went on publishing the pose it had last seen; here the palm dropped
    # to (0, 0, 0) at the device, with zero directions, the moment the hand left; and with
    # ~freq the pose held was the last one sent, up to a period old.
    import types

    from leap_teleop.hands.tracker import HandState
    from leap_teleop.ros import hand_conversions
    from leap_teleop.ros.hand_topics import HandTopics
    sent = []
    pub = types.SimpleNamespace(publish=sent.append)
    topics = types.SimpleNamespace(
        pubs={'right': {'leapcobot': pub, 'hand': pub, 'gesture': pub}},
        ages=types.SimpleNamespace(add=lambda *a: None), clock=lambda: 0.0,
        throttle=PeriodThrottle(freq), _present_sent={}, p={'frame_id': 'leap'},
        _leapcobot={'right': hand_conversions.LEAPCOBOT_TYPES['right']()}, published=0,
        leapros_side='right', leapros=pub, leap=pub, _classic_last=None)
    topics._publish_classic = lambda state: HandTopics._publish_classic(topics, state)
    states = [HandState('right', False, 0.0, 0)]
    states += [HandState('right', True, 0.01 * k, k, palm_position=(20.0, 200.0 + k, 30.0),
                         direction=(0.0, 0.0, -1.0), palm_normal=(0.0, -1.0, 0.0)) for k in range(1, 6)]
    states += [HandState('right', False, 0.06, 6), HandState('right', False, 0.2, 7)]
    for state in states:
        HandTopics.on_hand(topics, types.SimpleNamespace(timestamp=state.timestamp, hand=lambda side: None),
                           state)
    leapros = [m for m in sent if type(m).__name__ == 'leapros']
    old = [m for m in sent if type(m).__name__ == 'leap']
    assert leapros[0].palmpos.y == 0.0                               # none seen yet: the header only
    away = [m for m in leapros if m.header.stamp.to_sec() >= 0.06]
    assert [m.palmpos.y for m in away] == [205.0] * len(away) and len(away) >= 1
    assert [tuple(m.normal.__getstate__()) for m in away] == [(0.0, -1.0, 0.0)] * len(away)
    assert old[-1].hand_palm_pos[1] == 205.0


def test_the_driver_topics_carry_every_frame_whatever_freq():
    # ~freq (the old sender's throttle) thinned the driver's topics too, which the driver
    # publishes per frame: its filter then ran on the thinned stream and lagged more.
    import types

    from leap_teleop.ros.leap_motion_topics import LeapMotionTopics
    built = []
    topics = types.SimpleNamespace(
        pubs={'raw': types.SimpleNamespace(publish=lambda msg: None)}, _wanted=lambda kind: kind == 'raw',
        lowpass=types.SimpleNamespace(reset=lambda: None),
        builder=types.SimpleNamespace(human_msgs=lambda frame, states, raw, lowpass: (
            built.append(frame.timestamp), (None, None))[1]))
    for i in range(10):
        frame = types.SimpleNamespace(timestamp=0.01 * i, hands=[types.SimpleNamespace(side='right')],
                                      gestures=[])
        LeapMotionTopics.on_frame(topics, frame, {'right': types.SimpleNamespace(events=())})
    assert len(built) == 10


@pytest.mark.parametrize('fps', [110.0, 120.0, 200.0])
def test_the_period_throttle_keeps_the_originals_rate(fps):
    # The first frame a period after the last one sent: freq 0.01 halved 110-120 Hz to
    # 55-60 Hz, where the original's sleep of 0.01 s gave about 100 Hz.
    t = PeriodThrottle(0.01)
    sent = [k / fps for k in range(int(10 * fps)) if t.due('right', k / fps)]
    assert len(sent) == pytest.approx(1000, abs=2)
    assert max(b - a for a, b in zip(sent, sent[1:])) <= 0.01 + 1.0 / fps + 1e-9


def test_the_period_throttle_after_a_gap_starts_its_schedule_again():
    t = PeriodThrottle(0.1)
    stamps = [0.0, 0.1, 0.2, 1.05, 1.1, 1.16, 1.2, 1.26]     # frames lost between 0.2 and 1.05
    assert [ts for ts in stamps if t.due('right', ts)] == [0.0, 0.1, 0.2, 1.05, 1.16, 1.26]


def test_the_leap_rotation_is_a_checked_unit_quaternion():
    from leap_teleop.hands.sender_params import LEAP_IN_WORLD_XYZW, leap_rotation
    from leap_teleop.params import ParamError
    p = params()
    assert p['leap_rotation_xyzw'] == list(LEAP_IN_WORLD_XYZW)
    assert leap_rotation(p['leap_rotation_xyzw']) == list(LEAP_IN_WORLD_XYZW)
    # The driver's 4-digit 0.707s are taken, normalised.
    q = leap_rotation(params(leap_rotation_xyzw=[0.707, 0, 0, 0.707])['leap_rotation_xyzw'])
    assert q == pytest.approx([0.5 ** 0.5, 0.0, 0.0, 0.5 ** 0.5], abs=1e-12)
    for bad in ([1.0, 1.0, 0.0, 0.0], [0.0, 0.0, 0.0, 0.0], [0.5, 0.5, 0.5, 0.4]):
        with pytest.raises(ParamError, match='not a unit quaternion'):
            leap_rotation(bad)
    for bad in ([0.0, 0.0, 1.0], [2.0, 0.0, 0.0, 0.0], [float('nan'), 0.0, 0.0, 1.0]):
        with pytest.raises(ParamError):
            params(leap_rotation_xyzw=bad)


@pytest.mark.parametrize('server, cutoff, says', [
    ({}, 4.0, []),
    ({'/filter_cutoff': 1.5}, 1.5, ['info: ~filter_cutoff not set: using the leap_motion driver\'s '
                                    '/filter_cutoff = 1.5']),
    ({'/filter_cutoff': 1.5, '/leap_sender/filter_cutoff': 6.0}, 6.0,
     ['warn: the leap_motion driver\'s /filter_cutoff = 1.5 is ignored: ~filter_cutoff = 6 is set']),
    ({'/enable_filter': True}, 4.0, []),
    ({'/enable_filter': False}, 4.0, ['warn: the leap_motion driver\'s /enable_filter = False is ignored: '
                                      'the filtered Human is on leap_motion/filtered_values']),
])
def test_the_drivers_global_parameters_are_used_or_said_to_be_ignored(server, cutoff, says, monkeypatch):
    # The driver's nodes read /filter_cutoff and /enable_filter; the sender read only its own
    # ~names, so a setup tuned the driver's way was silently ignored.
    import rospy

    from leap_teleop.ros.leap_motion_topics import use_driver_globals
    private = {k.split('/')[-1]: v for k, v in server.items() if k.startswith('/leap_sender/')}
    said = []
    monkeypatch.setattr(rospy, 'has_param', lambda name: name in server or (
        name.startswith('~') and name[1:] in private))
    monkeypatch.setattr(rospy, 'get_param', lambda name: server[name])
    monkeypatch.setattr(rospy, 'loginfo', lambda fmt, *a: said.append('info: ' + fmt % a))
    monkeypatch.setattr(rospy, 'logwarn', lambda fmt, *a: said.append('warn: ' + fmt % a))
    p = params(filtered_human_topic='leap_motion/filtered_values', **private)
    use_driver_globals(p, SENDER_PARAMS)
    assert p['filter_cutoff'] == cutoff
    assert [s.replace('sender: ', '').split(' (~filtered')[0] for s in said] == says


def test_a_bad_global_filter_cutoff_is_a_bad_parameter(monkeypatch):
    import rospy

    from leap_teleop.params import ParamError
    from leap_teleop.ros.leap_motion_topics import use_driver_globals
    monkeypatch.setattr(rospy, 'has_param', lambda name: name == '/filter_cutoff')
    monkeypatch.setattr(rospy, 'get_param', lambda name: -2.0)
    with pytest.raises(ParamError, match='/filter_cutoff'):
        use_driver_globals(params(), SENDER_PARAMS)


def test_bindings_are_checked_against_the_model_that_judges_the_sources_hands(tmp_path):
    # a Leap model's 'two' bound with a webcam source was accepted and never fired
    import numpy as np

    from leap_teleop.hands.gestures import GestureRecognizer
    from leap_teleop.hands.gestures.bindings import BindingError
    from leap_teleop.hands.gestures.classifier import DEFAULT_MODELS
    with np.load(DEFAULT_MODELS['leap']) as z:
        arrays = {k: z[k] for k in z.files}
    arrays['classes'] = np.append(arrays['classes'], 'two')
    arrays['w1'] = np.hstack([arrays['w1'], arrays['w1'][:, :1]])
    arrays['b1'] = np.append(arrays['b1'], arrays['b1'][0] - 10.0)
    np.savez(tmp_path / 'two.npz', **arrays)
    (tmp_path / 'b.yaml').write_text('arm: {arm: two}\n')
    recognizer = GestureRecognizer(model=str(tmp_path / 'two.npz'))
    assert recognizer.user_gestures_of == {'leap': ('two',), 'keypoints': ()}
    bound = params(source='recording', gesture_bindings=str(tmp_path / 'b.yaml'))
    assert checked_bindings(bound, recognizer).actions['arm']['arm'] == ('two',)
    with pytest.raises(BindingError, match="unknown gesture 'two' .*: the webcam source's hands are "
                                           "judged by ~keypoint_model"):
        checked_bindings(dict(bound, source='webcam'), recognizer)
    # a recording of camera hands says so (its hand_family): the keypoint model judges them
    with pytest.raises(BindingError, match="the recording source's hands are judged by ~keypoint_model"):
        checked_bindings(bound, recognizer, 'keypoints')


def _two_model(tmp_path):
    """A Leap pose model with one more class, 'two' (the keypoint model has none)."""
    import numpy as np

    from leap_teleop.hands.gestures.classifier import DEFAULT_MODELS
    with np.load(DEFAULT_MODELS['leap']) as z:
        arrays = {k: z[k] for k in z.files}
    arrays['classes'] = np.append(arrays['classes'], 'two')
    arrays['w1'] = np.hstack([arrays['w1'], arrays['w1'][:, :1]])
    arrays['b1'] = np.append(arrays['b1'], arrays['b1'][0] - 10.0)
    np.savez(tmp_path / 'two.npz', **arrays)
    return str(tmp_path / 'two.npz')


def _sender_parts(monkeypatch, values):
    """The sender's sender_parts without a master; what it built or waited for, in order."""
    import rospy

    from leap_teleop.hands import sender_setup
    from leap_teleop.ros.nodes import sender
    done = []
    monkeypatch.setattr(rospy, 'has_param', lambda name: False)

    def camera_model(p):
        done.append('CameraInfo wait')
        raise SourceError('no sensor_msgs/CameraInfo on /cam/info within 10 s')
    make_source = sender_setup.make_source

    def built(name, **kwargs):
        done.append('built ' + name)
        if name in ('webcam', 'video', 'leap', 'leapc'):
            raise SourceError('%s: cannot open' % name)
        return make_source(name, **kwargs)
    monkeypatch.setattr(sender, 'camera_model', camera_model)
    monkeypatch.setattr(sender_setup, 'make_source', built)
    try:
        return sender.sender_parts(params(**values)), done
    except (SourceError, ValueError) as e:
        return e, done


@pytest.mark.parametrize('source', ['video', 'webcam', 'scripted', 'leap', 'leapc'])
def test_bad_bindings_are_refused_before_the_source_is_built_or_waits_for_camera_info(
        tmp_path, monkeypatch, source):
    # The check ran after build_source, which waits up to 10 s for ~camera_info_topic: a bad
    # bindings file was told late, or not at all when the camera failed.
    from leap_teleop.hands.gestures.bindings import BindingError
    (tmp_path / 'bad.yaml').write_text('arm: {arm: thumbs_upp}\n')
    (tmp_path / 'clip.mp4').write_bytes(b'')
    err, done = _sender_parts(monkeypatch, dict(
        source=source, video=str(tmp_path / 'clip.mp4'), camera_info_topic='/cam/info',
        gesture_bindings=str(tmp_path / 'bad.yaml')))
    assert isinstance(err, BindingError) and "unknown gesture 'thumbs_upp'" in str(err)
    assert done == []


def test_a_recording_is_read_before_its_bindings_are_checked_against_its_own_hands(
        tmp_path, monkeypatch):
    # A camera take's hands are keypoints (judged by ~keypoint_model), a Leap take's are
    # not: only the file tells, and reading it never waits.
    import numpy as np

    from leap_teleop.hands.frame import Frame
    from leap_teleop.hands.gestures.bindings import BindingError
    from leap_teleop.hands.rendered_hand import render_hand
    from leap_teleop.hands.sources import leapjs
    (tmp_path / 'b.yaml').write_text('arm: {arm: two}\n')
    for family in ('leap', 'keypoints'):
        hand = render_hand('right', 'open', [0.0, 200.0, 0.0], hand_id=1)
        if family == 'keypoints':
            hand.image_landmarks = np.tile([[320.0, 240.0]], (21, 1)) + np.arange(21)[:, None]
        path = str(tmp_path / ('%s.json' % family))
        leapjs.save(path, [leapjs.frame_to_dict(Frame(k + 1, 1.0 + k / 100.0, [hand])) for k in range(5)])
        got, done = _sender_parts(monkeypatch, dict(
            source='recording', recording=path, gesture_model=_two_model(tmp_path),
            gesture_bindings=str(tmp_path / 'b.yaml')))
        assert done == ['built recording'], family
        if family == 'leap':
            source, _, _, bindings = got
            assert source.hand_family == 'leap' and bindings.actions['arm']['arm'] == ('two',)
        else:
            assert isinstance(got, BindingError) and 'judged by ~keypoint_model' in str(got)
