"""Hand -> RViz markers, the drone's primitive markers and the bounded path trail."""
import math

import pytest
import rospy
from visualization_msgs.msg import Marker

from leap_teleop.hands.frame import Frame
from leap_teleop.hands.gestures import GestureRecognizer
from leap_teleop.hands.leap_interface import LeapInterface
from leap_teleop.hands.rendered_hand import render_hand
from leap_teleop.ros import hand_conversions
from leap_teleop.ros import markers as viz

# needs a ROS master, a simulator, a subprocess or a build: not in make check
pytestmark = pytest.mark.integration

PALM_MM = (20.0, 200.0, -10.0)


def hand_msg(side, pose=None, palm=PALM_MM, **kw):
    """The Hand message the sender would publish for one rendered pose (None = absent)."""
    li = LeapInterface(recognizer_factory=lambda: GestureRecognizer(stateless=True))
    hands = [render_hand(side, pose, list(palm), **kw)] if pose else []
    return hand_conversions.to_hand(li.on_frame(Frame(id=7, timestamp=50.0, hands=hands))[side])


def by_id(array):
    return {m.id: m for m in array.markers}


@pytest.mark.parametrize('side', ['right', 'left'])
def test_present_hand_draws_palm_tips_lines_in_the_hand_frame(side):
    msg = hand_msg(side, 'open')
    out = viz.hand_markers(msg)
    ms = by_id(out)
    assert set(ms) == set(viz.HAND_MARKER_IDS)
    for m in ms.values():
        assert m.ns == 'hand_' + side and m.action == Marker.ADD
        assert m.header.frame_id == 'leap_hands'
        assert m.header.stamp == msg.header.stamp
        assert m.lifetime.to_sec() == pytest.approx(0.5)
    palm = ms[viz.PALM]
    assert palm.type == Marker.SPHERE
    assert (palm.pose.position.x, palm.pose.position.y, palm.pose.position.z) == \
        pytest.approx(tuple(v * 0.001 for v in PALM_MM))
    tips = ms[viz.TIPS]
    assert tips.type == Marker.SPHERE_LIST and len(tips.points) == 5
    assert [(p.x, p.y, p.z) for p in tips.points] == \
        [(p.x, p.y, p.z) for p in msg.finger_tips]
    # Fingertips are a hand's length from the palm, not at the origin or in mm.
    for p in tips.points:
        d = math.dist((p.x, p.y, p.z), (palm.pose.position.x, palm.pose.position.y,
                                        palm.pose.position.z))
        assert 0.03 < d < 0.2
    bones = ms[viz.BONES]
    assert bones.type == Marker.LINE_LIST and len(bones.points) == 10
    assert all(bones.points[i] == palm.pose.position for i in range(0, 10, 2))
    assert bones.points[1::2] == tips.points
    arrow = ms[viz.NORMAL]
    n = msg.palm_normal
    tip = arrow.points[1]
    d = (tip.x - palm.pose.position.x, tip.y - palm.pose.position.y,
         tip.z - palm.pose.position.z)
    assert sum(a * b for a, b in zip(d, (n.x, n.y, n.z))) == pytest.approx(0.06, rel=1e-3)
    assert ms[viz.LABEL].text == '%s: open' % side


@pytest.mark.parametrize('pose, state', [('open', 'open'), ('fist', 'fist'),
                                         ('thumbs_up', 'thumb_up'), ('pinch', 'pinch'),
                                         ('rock', 'rock')])
def test_colour_follows_the_recognised_state(pose, state):
    msg = hand_msg('right', pose, pinch_value=0.5)
    assert viz.hand_state(msg) == state
    rgb = viz.STATE_COLOURS.get(state, viz.IDLE_COLOUR)
    palm = by_id(viz.hand_markers(msg))[viz.PALM]
    assert (palm.color.r, palm.color.g, palm.color.b) == pytest.approx(rgb)


def test_every_state_has_its_own_colour():
    colours = list(viz.STATE_COLOURS.values()) + [viz.IDLE_COLOUR]
    assert len(set(colours)) == len(colours)


def test_folded_fingertips_are_faint():
    msg = hand_msg('right', 'point')         # index extended only
    assert list(msg.finger_extended) == [False, True, False, False, False]
    alphas = [c.a for c in by_id(viz.hand_markers(msg))[viz.TIPS].colors]
    assert alphas[1] == 1.0
    assert all(a == viz.FOLDED_ALPHA for i, a in enumerate(alphas) if i != 1)


@pytest.mark.parametrize('side', ['right', 'left'])
def test_absent_hand_deletes_its_own_markers_only(side):
    out = viz.hand_markers(hand_msg(side, None))
    assert sorted(m.id for m in out.markers) == sorted(viz.HAND_MARKER_IDS)
    assert all(m.action == Marker.DELETE and m.ns == 'hand_' + side for m in out.markers)


def test_frame_and_scale_overrides():
    out = by_id(viz.hand_markers(hand_msg('left', 'open'), frame_id='other', lifetime=0,
                                 scale=2.0))
    assert all(m.header.frame_id == 'other' for m in out.values())
    assert out[viz.PALM].scale.x == pytest.approx(0.08)
    assert out[viz.PALM].lifetime == rospy.Duration(0)


def test_bad_input_is_a_clear_value_error():
    msg = hand_msg('right', 'open')
    msg.palm_position.x = float('nan')
    with pytest.raises(ValueError, match='palm_position'):
        viz.hand_markers(msg)
    # Found: finite but huge coordinates (1e308 m) went to RViz, whose renderer fails
    # its bounding-box checks on them.
    for field, axis in (('palm_position', 'y'), ('palm_normal', 'z')):
        msg = hand_msg('right', 'open')
        setattr(getattr(msg, field), axis, 1e308)
        with pytest.raises(ValueError, match='%s is not finite or beyond 1000 m' % field):
            viz.hand_markers(msg)
    msg = hand_msg('right', 'open')
    msg.finger_tips[3].x = -2e3
    with pytest.raises(ValueError, match=r'finger_tips\[3\]'):
        viz.hand_markers(msg)
    msg = hand_msg('right', 'open')
    msg.side = 5
    with pytest.raises(ValueError, match='side'):
        viz.hand_markers(msg)
    msg = hand_msg('right', 'open')
    msg.header.frame_id = ''
    with pytest.raises(ValueError, match='frame_id'):
        viz.hand_markers(msg)
    assert by_id(viz.hand_markers(msg, frame_id='leap_hands'))[viz.PALM].header.frame_id \
        == 'leap_hands'


def test_throttle_rate_state_changes_and_single_delete():
    th = viz.HandMarkerThrottle(max_rate=10.0)
    open_r, fist_r, gone_r = hand_msg('right', 'open'), hand_msg('right', 'fist'), \
        hand_msg('right', None)
    open_l = hand_msg('left', 'open')
    assert th.update(open_r, 0.00) is not None
    assert th.update(open_r, 0.05) is None            # within 1/10 s, same state
    assert th.update(open_l, 0.05) is not None        # the other hand has its own clock
    assert th.update(fist_r, 0.06) is not None        # state change: at once
    assert th.update(fist_r, 0.10) is None
    assert th.update(fist_r, 0.17) is not None        # period elapsed
    out = th.update(gone_r, 0.18)
    assert out is not None and all(m.action == Marker.DELETE for m in out.markers)
    assert th.update(gone_r, 0.50) is None            # one delete, not one per frame
    assert th.update(open_r, 0.51) is not None        # back again
    assert th.update(open_r, 0.40) is not None        # clock went backwards (bag loop)
    every = viz.HandMarkerThrottle(max_rate=0)
    assert all(every.update(open_r, 1.0) is not None for _ in range(3))
    with pytest.raises(ValueError):
        viz.HandMarkerThrottle(max_rate=-1)


def test_drone_markers_are_frame_locked_primitives_with_unique_ids():
    out = viz.drone_markers('base')
    ids = [m.id for m in out.markers]
    assert len(ids) == len(set(ids)) >= 5
    assert all(m.header.frame_id == 'base' and m.frame_locked and m.action == Marker.ADD
               for m in out.markers)
    assert all(m.type in (Marker.CUBE, Marker.CYLINDER, Marker.SPHERE) for m in out.markers)
    # Everything within the AR.Drone's ~0.52 m hull.
    assert all(abs(m.pose.position.x) + m.scale.x / 2 <= 0.3 and
               abs(m.pose.position.y) + m.scale.y / 2 <= 0.3 for m in out.markers)


def test_latency_marker_is_text_above_the_hands_and_deletes_when_empty():
    m = viz.latency_marker(['capture -> stage, p50 / p99:', 'ur10_1/ur10_arm command: 9.0 / 12.0 ms'],
                           'leap_hands', (0.0, 0.6, 0.0), 12.5, scale=2.0)
    assert (m.ns, m.type, m.action) == ('latency', Marker.TEXT_VIEW_FACING, Marker.ADD)
    assert m.header.frame_id == 'leap_hands' and m.header.stamp.to_sec() == 12.5
    assert m.text.splitlines()[1] == 'ur10_1/ur10_arm command: 9.0 / 12.0 ms'
    assert (m.pose.position.y, m.scale.z) == (0.6, pytest.approx(0.1))
    assert m.lifetime.to_sec() > 1.0          # outlives the 1 s refresh, clears when it stops
    gone = viz.latency_marker([], 'leap_hands', (0.0, 0.45, 0.0), 13.0)
    assert (gone.ns, gone.id, gone.action) == ('latency', 0, Marker.DELETE)


def test_path_trail_is_bounded_and_spaced():
    trail = viz.PathTrail(max_points=5, min_step=0.1)
    q = (0.0, 0.0, 0.0, 1.0)
    assert trail.add(rospy.Time(1), (0, 0, 0), q)
    assert not trail.add(rospy.Time(2), (0.05, 0, 0), q)      # closer than min_step
    assert not trail.add(rospy.Time(2), (float('nan'), 0, 0), q)
    for i in range(1, 10):
        assert trail.add(rospy.Time(2 + i), (0.2 * i, 0, 0), q)
    assert trail.changed
    path = trail.to_msg('odom')
    assert not trail.changed
    assert len(path.poses) == 5
    assert path.header.frame_id == 'odom' and path.header.stamp == rospy.Time(11)
    xs = [p.pose.position.x for p in path.poses]
    assert xs == pytest.approx([1.0, 1.2, 1.4, 1.6, 1.8])     # the newest five, in order
    assert all(p.header.frame_id == 'odom' and p.pose.orientation.w == 1 for p in path.poses)
    trail.clear()
    assert trail.to_msg('odom', rospy.Time(3)).poses == []
    with pytest.raises(ValueError):
        viz.PathTrail(max_points=1)


NODE_CLIENT = r'''
import json, sys, time
sys.path.insert(0, sys.argv[1])
import rospy
from visualization_msgs.msg import MarkerArray
from leap_teleop.msg import Hand
from test_hand_markers import hand_msg
rospy.init_node('hand_markers_client')
got = []
rospy.Subscriber('leapmotion/hand_markers', MarkerArray,
                 lambda m: got.append([(k.ns, k.id, k.action, k.color.r, k.color.g)
                                       for k in m.markers]))
pub = rospy.Publisher('leapmotion/hand_left', Hand, queue_size=10)
deadline = time.time() + 10
while (pub.get_num_connections() == 0 or not got) and time.time() < deadline:
    if pub.get_num_connections():
        pub.publish(hand_msg('left', 'open'))    # until the node's first markers arrive
    time.sleep(0.1)
bad = hand_msg('left', 'fist')
bad.palm_position.y = float('inf')
for msg in (bad, hand_msg('left', 'fist'), hand_msg('left', None), hand_msg('left', None)):
    pub.publish(msg)
    time.sleep(0.3)
print(json.dumps(got))
'''


def test_node_publishes_markers_and_deletes_on_a_private_master():
    import json
    import os
    import subprocess
    import sys

    from tools.bench.ros_processes import ros_master, spawn_node, stop_spawned
    here = os.path.dirname(os.path.abspath(__file__))
    script = os.path.join(here, '..', 'scripts', 'hand_markers.py')
    with ros_master() as env:
        node = spawn_node(env, [sys.executable, script, '_max_rate:=0'])
        try:
            out = subprocess.run([sys.executable, '-c', NODE_CLIENT, here], env=env,
                                 capture_output=True, text=True, timeout=60)
        finally:
            stop_spawned(node)
            err = node.stderr.read().decode(errors='replace')
    assert out.returncode == 0, out.stderr
    arrays = json.loads(out.stdout.strip().splitlines()[-1])
    assert arrays, 'no MarkerArray from the node'
    assert all(ns == 'hand_left' for a in arrays for ns, *_ in a)
    fists = [a for a in arrays if a and a[0][2] == Marker.ADD and a[0][3] > 0.8]
    assert fists, arrays                     # the red fist after the bad message
    deletes = [a for a in arrays if a and all(k[2] == Marker.DELETE for k in a)]
    assert len(deletes) == 1                 # once, not per absent frame
    assert arrays[-1] == deletes[0]
    assert 'palm_position is not finite' in err


LATENCY_CLIENT = r'''
import json, time
import rospy
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from visualization_msgs.msg import MarkerArray
rospy.init_node('latency_client')
got = []
rospy.Subscriber('leapmotion/hand_markers', MarkerArray,
                 lambda m: got.extend([k.ns, k.action, k.text, k.header.frame_id] for k in m.markers))
pub = rospy.Publisher('/diagnostics', DiagnosticArray, queue_size=10)
status = DiagnosticStatus(name='ur10_1/ur10_arm: teleop', values=[
    KeyValue('input age p50 (ms, last 10 s)', '9.0'), KeyValue('input age p99 (ms, last 10 s)', '12.5'),
    KeyValue('input age samples', '300')])
deadline = time.time() + 20
while not got and time.time() < deadline:
    pub.publish(DiagnosticArray(status=[status]))
    time.sleep(0.5)
time.sleep(7.0)                          # no more reports: the text goes after 5 s
print(json.dumps(got))
'''


def test_node_shows_the_reported_input_ages_as_a_text_marker_then_clears_it():
    import json
    import os
    import subprocess
    import sys

    from tools.bench.ros_processes import ros_master, spawn_node, stop_spawned
    here = os.path.dirname(os.path.abspath(__file__))
    script = os.path.join(here, '..', 'scripts', 'hand_markers.py')
    with ros_master() as env:
        node = spawn_node(env, [sys.executable, script])
        try:
            out = subprocess.run([sys.executable, '-c', LATENCY_CLIENT], env=env,
                                 capture_output=True, text=True, timeout=60)
        finally:
            stop_spawned(node)
    assert out.returncode == 0, out.stderr
    markers = json.loads(out.stdout.strip().splitlines()[-1])
    assert markers and all(ns == 'latency' and frame == 'leap_hands' for ns, _, _, frame in markers)
    assert markers[0][1] == Marker.ADD
    assert markers[0][2].splitlines() == ['capture -> stage, p50 / p99:',
                                          'ur10_1/ur10_arm command: 9.0 / 12.5 ms']
    assert markers[-1][1] == Marker.DELETE and [m[1] for m in markers].count(Marker.DELETE) == 1


class LatencyMarkersSeen:
    """Stands in for the node's MarkerArray publisher: (wall time, action) of each marker."""

    def __init__(self):
        self.markers = []

    def publish(self, array):
        import time
        self.markers += [(time.monotonic(), m.action) for m in array.markers]


@pytest.mark.filterwarnings('ignore:notifyAll:DeprecationWarning')     # rospy's sim-time calls
def test_the_latency_text_goes_when_the_clock_stopped_with_the_reports(monkeypatch):
    # Its timer ran on ROS time: with /clock stopped (a paused simulator, a bag at its end)
    # it never fired again, and RViz expires the marker on ROS time too, so the last
    # figures stayed above the hands for ever instead of going within STOPPED_CLOCK_S.
    import time

    from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue

    from leap_teleop.control import input_age
    from leap_teleop.params import check_params
    from leap_teleop.ros.graph import TopicTypeWatch
    from leap_teleop.ros.nodes.hand_markers import PARAMS, HandMarkersNode
    monkeypatch.setattr(TopicTypeWatch, 'check', lambda self, _event=None: None)
    monkeypatch.setattr(input_age, 'STOPPED_CLOCK_S', 3.0)    # a minute in the node
    was = rospy.rostime.is_rostime_initialized()
    rospy.rostime.set_rostime_initialized(True)
    rospy.rostime._set_rostime(rospy.Time.from_sec(100.0))   # sim time, standing still
    node = HandMarkersNode(check_params(PARAMS, {}))
    try:
        node.pub = published = LatencyMarkersSeen()
        node.latency.board.stale_after_s = 1.0
        start = time.monotonic()
        node.latency.on_diagnostics(DiagnosticArray(status=[DiagnosticStatus(
            name='ur10_1/ur10_arm: teleop', values=[
                KeyValue('input age p50 (ms, last 10 s)', '3.1'),
                KeyValue('input age p99 (ms, last 10 s)', '12.0'),
                KeyValue('input age samples', '500')])]))
        while time.monotonic() - start < 8.0 and Marker.DELETE not in [a for _, a in published.markers]:
            time.sleep(0.1)
    finally:
        if hasattr(node, 'closing'):
            node.closing.set()
        for timer in (node.timer, node.type_watch.timer):
            timer.shutdown()
        for sub in node.subs + [node.latency.sub]:
            sub.unregister()
        rospy.rostime.switch_to_wallclock()                 # wakes the timers' threads
        for timer in (node.timer, node.type_watch.timer):
            timer.join(5.0)
        rospy.rostime.set_rostime_initialized(was)
    actions = [a for _, a in published.markers]
    assert actions and actions[0] == Marker.ADD, actions
    assert actions[-1] == Marker.DELETE and actions.count(Marker.DELETE) == 1, actions
    assert published.markers[-1][0] - start < 3.0 + 1.5     # within the stopped clock's time


def test_a_marker_topic_that_is_a_hand_topic_is_refused_at_start_up():
    # Taken before: MarkerArray went out on a Hand topic, and the only sign was rospy's
    # 3,856-character type-mismatch dump.
    from leap_teleop.params import check_params
    from leap_teleop.ros.nodes.hand_markers import PARAMS, HandMarkersNode
    p = check_params(PARAMS, {'marker_topic': '/leapmotion/hand_right', 'latency_text': False})
    with pytest.raises(ValueError, match="~marker_topic '/leapmotion/hand_right' is one of "
                                         '~hand_topics'):
        HandMarkersNode(p)
