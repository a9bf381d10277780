"""A consumer of the ros-drivers leap_motion driver, built only against that driver's message
definitions, receives filled messages from leap_teleop's stand-in (launch/leap_motion.launch)
from a recording, a scripted hand and the video source.

The scratch workspace's `leap_motion` package is written here from the driver's field lists
(below, not copied files) and built with catkin_make; its consumer subscribes with those
types (a wrong MD5 would get it nothing) and writes what it received as JSON lines, which the
test checks against the source's own frames in the driver's units (metres, radians).
"""
import csv
import json
import math
import os
import signal
import subprocess
import sys
import textwrap

import numpy as np
import pytest

from leap_teleop.hands.gestures.datasets import HANDS_DATA
from leap_teleop.hands.sources import leapjs
from leap_teleop.hands.sources.scripted import GestureScript
from tools.bench import ros_processes

# needs a ROS master, a simulator, a subprocess or a build: not in make check
pytestmark = pytest.mark.integration

HERE = os.path.dirname(os.path.abspath(__file__))
PYTHON = sys.executable

# The driver's message definitions: (name, fields), fields in wire order.
DRIVER_MESSAGES = {
    'Human': ['std_msgs/Header header', 'int32 lmc_frame_id', 'int32 nr_of_hands',
              'int32 nr_of_fingers', 'int32 nr_of_gestures', 'float32 current_frames_per_second',
              'string to_string', 'Hand right_hand', 'Hand left_hand'],
    'Hand': ['std_msgs/Header header', 'int32 lmc_hand_id', 'bool is_present',
             'bool valid_gestures', 'float32 time_visible', 'float32 confidence', 'float32 roll',
             'float32 pitch', 'float32 yaw', 'geometry_msgs/Vector3 direction',
             'geometry_msgs/Vector3 normal', 'float32 grab_strength', 'float32 pinch_strength',
             'float32[] palm_velocity', 'geometry_msgs/Point palm_center', 'float32 palm_width',
             'float32 sphere_radius', 'float32[] sphere_center', 'string to_string',
             'Finger[] finger_list', 'Gesture[] gesture_list', 'Arm arm'],
    'Finger': ['std_msgs/Header header', 'int32 lmc_finger_id', 'uint8 type', 'float32 length',
               'float32 width', 'string to_string', 'Bone[] bone_list'],
    'Bone': ['std_msgs/Header header', 'uint8 type', 'float32 length', 'float32 width',
             'string to_string', 'geometry_msgs/Pose bone_start', 'geometry_msgs/Pose bone_end',
             'float32[] center'],
    'Gesture': ['int32 lmc_gesture_id', 'bool is_valid', 'int64 duration_us', 'float32 duration_s',
                'int32 gesture_state', 'int32 gesture_type', 'string to_string',
                'int32[] pointable_ids'],
    'Arm': ['std_msgs/Header header', 'geometry_msgs/Pose elbow', 'geometry_msgs/Pose wrist',
            'float32[] center', 'geometry_msgs/Vector3 direction'],
    'leap': ['Header header', 'float64[3] hand_direction', 'float64[3] hand_normal',
             'float64[3] hand_palm_pos', 'float64 hand_pitch', 'float64 hand_roll',
             'float64 hand_yaw'],
}
# The sums the driver's generated code carries.
DRIVER_MD5 = {'Human': '2817a017ab58b244566892058c4f6e6d',
              'Hand': '9054fd3f5821eae3259c31fe94fd08a4',
              'Finger': 'c62c3b47717473d8242b45f476fc55c7',
              'Bone': 'ce39afad61bdb16ab802b0100be50795',
              'Gesture': 'a3bf4fe2d0e707244a5a679250ea8eba',
              'Arm': 'b93012a87e6395b9975695d8d7a942db',
              'leap': '3e9a0dc7fd1a98f1d7489e9011c78807'}

CONSUMER = r'''
#!/usr/bin/env python3
# A consumer of the leap_motion driver: its Human (raw and filtered), its visualizer's
# markers and the old leap message; each message as one JSON line in argv[1]. Exits once
# messages stopped for 3 s (or after argv[2] s).
import json, sys, threading
import rospy
from visualization_msgs.msg import MarkerArray
from leap_motion.msg import Human, leap

out = open(sys.argv[1], 'w')
lock = threading.Lock()
last = [None]

def xyz(p):
    return [p.x, p.y, p.z]

def hand(h):
    return {'present': h.is_present, 'id': h.lmc_hand_id, 'valid_gestures': h.valid_gestures,
            'time_visible': h.time_visible, 'confidence': h.confidence,
            'palm_width': h.palm_width, 'sphere_radius': h.sphere_radius,
            'sphere_center': list(h.sphere_center),
            'rpy': [h.roll, h.pitch, h.yaw], 'direction': xyz(h.direction),
            'normal': xyz(h.normal), 'grab': h.grab_strength, 'pinch': h.pinch_strength,
            'velocity': list(h.palm_velocity), 'palm': xyz(h.palm_center),
            'frame_id': h.header.frame_id,
            'fingers': [{'id': f.lmc_finger_id, 'type': f.type, 'length': f.length, 'width': f.width,
                         'bones': [{'type': b.type, 'length': b.length,
                                    'start': xyz(b.bone_start.position),
                                    'end': xyz(b.bone_end.position), 'center': list(b.center)}
                                   for b in f.bone_list]} for f in h.finger_list],
            'gestures': [{'id': g.lmc_gesture_id, 'type': g.gesture_type,
                          'state': g.gesture_state, 'valid': g.is_valid,
                          'duration_us': g.duration_us, 'pointables': list(g.pointable_ids)}
                         for g in h.gesture_list]}

def write(record):
    with lock:
        last[0] = rospy.get_time()
        out.write(json.dumps(record) + '\n')

def on_human(msg, topic):
    write({'topic': topic, 'md5': Human._md5sum, 'frame': msg.lmc_frame_id,
           'frame_id': msg.header.frame_id, 'stamp': msg.header.stamp.to_sec(),
           'hands': msg.nr_of_hands, 'fingers': msg.nr_of_fingers,
           'gestures': msg.nr_of_gestures, 'fps': msg.current_frames_per_second,
           'right': hand(msg.right_hand), 'left': hand(msg.left_hand)})

def on_leap(msg):
    write({'topic': 'leap', 'md5': leap._md5sum, 'stamp': msg.header.stamp.to_sec(),
           'direction': list(msg.hand_direction), 'normal': list(msg.hand_normal),
           'palm': list(msg.hand_palm_pos),
           'rpy': [msg.hand_roll, msg.hand_pitch, msg.hand_yaw]})

def on_markers(msg):
    write({'topic': 'markers', 'markers': [
        {'ns': m.ns, 'id': m.id, 'type': m.type, 'frame_id': m.header.frame_id,
         'position': xyz(m.pose.position), 'points': [xyz(p) for p in m.points]}
        for m in msg.markers]})

rospy.init_node('driver_consumer')
rospy.Subscriber('leap_motion/leap_device', Human, on_human, 'raw', queue_size=5000)
rospy.Subscriber('leap_motion/filtered_values', Human, on_human, 'filtered', queue_size=5000)
rospy.Subscriber('leap_motion/visualization_marker_array', MarkerArray, on_markers,
                 queue_size=5000)
rospy.Subscriber('leapmotion/raw', leap, on_leap, queue_size=5000)
deadline = rospy.get_time() + float(sys.argv[2])
while not rospy.is_shutdown() and rospy.get_time() < deadline:
    with lock:
        if last[0] is not None and rospy.get_time() - last[0] > 3.0:
            break
    rospy.sleep(0.1)
out.close()
'''


def write_driver_package(dst):
    files = {
        'package.xml': """
            <?xml version="1.0"?>
            <package format="2">
              <name>leap_motion</name><version>0.0.1</version>
              <description>the leap_motion driver's messages and a consumer</description>
              <maintainer email="user@example.com">user</maintainer><license>BSD</license>
              <buildtool_depend>catkin</buildtool_depend>
              <build_depend>message_generation</build_depend>
              <exec_depend>message_runtime</exec_depend>
              <depend>std_msgs</depend><depend>geometry_msgs</depend>
              <exec_depend>rospy</exec_depend><exec_depend>visualization_msgs</exec_depend>
            </package>""",
        'CMakeLists.txt': """
            cmake_minimum_required(VERSION 3.0.2)
            project(leap_motion)
            find_package(catkin REQUIRED COMPONENTS geometry_msgs message_generation std_msgs)
            add_message_files(FILES %s)
            generate_messages(DEPENDENCIES geometry_msgs std_msgs)
            catkin_package(CATKIN_DEPENDS geometry_msgs message_runtime std_msgs)""" % (
            ' '.join('%s.msg' % n for n in DRIVER_MESSAGES)),
        'scripts/consumer.py': CONSUMER,
    }
    for name, fields in DRIVER_MESSAGES.items():
        files['msg/%s.msg' % name] = '\n'.join(fields)
    for rel, text in files.items():
        path = os.path.join(dst, rel)
        os.makedirs(os.path.dirname(path), exist_ok=True)
        with open(path, 'w') as f:
            f.write(textwrap.dedent(text).lstrip() + '\n')


@pytest.fixture(scope='module')
def driver_ws(tmp_path_factory):
    """The scratch workspace, built; returns (its devel setup.bash, a clean environment)."""
    root = tmp_path_factory.mktemp('driver_ws')
    write_driver_package(str(root / 'src' / 'leap_motion'))
    env = {'PATH': '%s:/usr/local/bin:/usr/bin:/bin' % os.path.dirname(PYTHON),
           'HOME': os.environ.get('HOME', '/root'), 'LANG': 'C.UTF-8',
           'ROS_HOME': str(root / 'ros_home'), 'ROS_LOG_DIR': str(root / 'ros_log'),
           'PYTHONDONTWRITEBYTECODE': '1'}
    proc = subprocess.run(['catkin_make', '-DPYTHON_EXECUTABLE=%s' % PYTHON], cwd=str(root),
                          env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                          timeout=600)
    assert proc.returncode == 0, proc.stdout[-4000:]
    setup = root / 'devel' / 'setup.bash'
    out = subprocess.run(['bash', '-c', 'source %s && python -c "from leap_motion.msg import *; '
                          'print(%s)"' % (setup, ', '.join('%s._md5sum' % n for n in DRIVER_MD5))],
                         env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    assert out.stdout.split() == list(DRIVER_MD5.values()), out.stdout
    return str(setup), env


def run_stand_in(driver_ws, tmp_path, launch_args, max_time=90.0, echo=()):
    """Start the consumer, then `roslaunch leap_teleop leap_motion.launch ARGS` (its sender
    waits for the consumer), under a private master; the consumer's records. echo: topics
    of leap_teleop's own whose `rostopic echo -p` goes to tmp_path/<topic>.csv."""
    setup, clean = driver_ws
    records = tmp_path / 'received.jsonl'
    echoes = []
    with ros_processes.ros_master() as env:
        for topic in echo:
            echoes.append(subprocess.Popen(
                ['rostopic', 'echo', '-p', topic], env=env, stderr=subprocess.DEVNULL,
                stdout=open(tmp_path / (topic.strip('/').replace('/', '_') + '.csv'), 'w')))
        cenv = dict(clean, ROS_MASTER_URI=env['ROS_MASTER_URI'], ROS_HOSTNAME='127.0.0.1',
                    ROS_IP='127.0.0.1')
        script = os.path.join(os.path.dirname(setup), '..', 'src', 'leap_motion', 'scripts',
                              'consumer.py')
        consumer = subprocess.Popen(['bash', '-c', 'source %s && exec python %s %s %s'
                                     % (setup, script, records, max_time)], env=cenv,
                                    stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        log = open(tmp_path / 'roslaunch.log', 'wb')
        launch = subprocess.Popen(
            ['roslaunch', 'leap_teleop', 'leap_motion.launch', 'wait_for_subscribers:=true',
             'wait_topics:=[/leap_motion/leap_device, /leap_motion/filtered_values, '
             '/leap_motion/visualization_marker_array]'] + launch_args,
            env=dict(env, ROS_LOG_DIR=str(tmp_path / 'log')), stdout=log,
            stderr=subprocess.STDOUT, start_new_session=True)
        try:
            out, _ = consumer.communicate(timeout=max_time + 60)
        finally:
            for proc in echoes:
                proc.send_signal(signal.SIGINT)
                proc.wait(10)
            ros_processes.interrupt_group(launch, 30)
    tail = (tmp_path / 'roslaunch.log').read_text(errors='replace')[-3000:]
    assert consumer.returncode == 0, '%s\n%s' % (out, tail)
    assert records.exists(), tail
    got = [json.loads(line) for line in records.read_text().splitlines()]
    assert got, 'the consumer received nothing\n' + tail
    return got


def by_topic(records, topic):
    return [r for r in records if r['topic'] == topic]


def sdk_angles(normal, direction):
    """roll, pitch, yaw as the Leap SDK defines them (Vector.roll of the normal, pitch and
    yaw of the direction)."""
    return [math.atan2(normal[0], -normal[1]), math.atan2(direction[1], -direction[2]),
            math.atan2(direction[0], -direction[2])]


def check_hand(test_hand, src, tol_m=1e-6, tol_unit=1e-6):
    """A received driver Hand against a hands.frame.TrackedHand of the source (mm)."""
    assert test_hand['present']
    assert test_hand['id'] == src.id
    np.testing.assert_allclose(test_hand['palm'], np.asarray(src.palm_position) / 1000.0,
                               atol=tol_m)
    np.testing.assert_allclose(test_hand['velocity'], np.asarray(src.palm_velocity) / 1000.0,
                               atol=1e-5 + 1e-6 * np.abs(src.palm_velocity).max())
    np.testing.assert_allclose(test_hand['direction'], src.direction, atol=tol_unit)
    np.testing.assert_allclose(test_hand['normal'], src.palm_normal, atol=tol_unit)
    np.testing.assert_allclose(test_hand['rpy'], sdk_angles(src.palm_normal, src.direction),
                               atol=1e-5)
    # The source's own measures in metres where it has them (a recording's), else 0 / empty.
    assert test_hand['palm_width'] == pytest.approx((src.palm_width or 0.0) / 1000.0, rel=1e-6)
    assert test_hand['sphere_radius'] == pytest.approx((src.sphere_radius or 0.0) / 1000.0, rel=1e-6)
    np.testing.assert_allclose(test_hand['sphere_center'], [] if src.sphere_center is None
                               else np.asarray(src.sphere_center) / 1000.0, atol=tol_m)
    if src.time_visible is not None:
        assert test_hand['time_visible'] == pytest.approx(src.time_visible, rel=1e-6)
    assert len(test_hand['fingers']) == 5
    for i, (f, sf) in enumerate(zip(test_hand['fingers'], src.fingers)):
        assert f['type'] == i and f['id'] == src.id * 10 + i
        assert f['width'] == pytest.approx((sf.width or 0.0) / 1000.0, rel=1e-6)
        bones = f['bones']
        assert [b['type'] for b in bones] == [0, 1, 2, 3]
        joints = [sf.mcp, sf.pip, sf.dip, sf.tip]
        for b, (start, end) in zip(bones[1:], zip(joints, joints[1:])):
            np.testing.assert_allclose(b['start'], np.asarray(start) / 1000.0, atol=tol_m)
            np.testing.assert_allclose(b['end'], np.asarray(end) / 1000.0, atol=tol_m)
            length = np.linalg.norm(np.asarray(end) - np.asarray(start)) / 1000.0
            assert b['length'] == pytest.approx(length, abs=1e-5)
            np.testing.assert_allclose(b['center'], (np.asarray(start) + np.asarray(end)) / 2000.0,
                                       atol=1e-5)
        # The metacarpal ends at the knuckle; it starts at the carpal joint where the source
        # measures it (the Leap sources, protocol-6 takes), else at the knuckle (length 0).
        np.testing.assert_allclose(bones[0]['end'], np.asarray(sf.mcp) / 1000.0, atol=tol_m)
        base = sf.mcp if sf.carpal is None else sf.carpal
        np.testing.assert_allclose(bones[0]['start'], np.asarray(base) / 1000.0, atol=tol_m)
        assert bones[0]['length'] == pytest.approx(
            np.linalg.norm(np.asarray(sf.mcp) - np.asarray(base)) / 1000.0, abs=1e-5)
        assert f['length'] == pytest.approx(sum(b['length'] for b in bones), abs=1e-5)


def check_filtered(raw, filtered):
    """The filtered Human: the same frames; each hand's first filtered palm is its raw one,
    and the filtered palm path is shorter (smoother) than the raw one."""
    assert [r['frame'] for r in filtered] == [r['frame'] for r in raw][:len(filtered)]
    assert len(filtered) >= 0.9 * len(raw)
    for side in ('right', 'left'):
        pairs = [(r[side], f[side]) for r, f in zip(raw, filtered) if r[side]['present']]
        if len(pairs) < 20:
            continue
        np.testing.assert_allclose(pairs[0][1]['palm'], pairs[0][0]['palm'], atol=1e-6)
        raw_path = np.diff([r['palm'] for r, _ in pairs], axis=0)
        smooth_path = np.diff([f['palm'] for _, f in pairs], axis=0)
        assert np.linalg.norm(smooth_path, axis=1).sum() < np.linalg.norm(raw_path, axis=1).sum()
        for _, f in pairs:
            assert len(f['fingers']) == 5


def check_markers(markers, raw):
    """The visualizer's markers: in leap_hands, a palm sphere per present hand at a palm the
    Human had, bones and joints per finger."""
    assert markers
    palms = {tuple(np.round(r[side]['palm'], 3)) for r in raw for side in ('right', 'left')
             if r[side]['present']}
    seen = 0
    for rec in markers:
        for m in rec['markers']:
            assert m['frame_id'] == 'leap_hands'
            if m['ns'] in ('Right', 'Left') and m['id'] == 0:
                seen += 1
        names = {m['ns'] for m in rec['markers']}
        if 'Right' in names:
            assert {'Right_Thumb', 'Right_Index', 'Right_Middle', 'Right_Ring',
                    'Right_Pinky'} <= names
    assert seen >= 0.5 * len(markers)
    assert palms


@pytest.mark.rostest
def test_a_recording_reaches_a_driver_consumer(driver_ws, leapjs_data, tmp_path):
    path = os.path.join(leapjs_data, 'flapping.json.lz')
    _, frames, _ = leapjs.load_frames(path)
    source = {f.id: f for f in frames}
    got = run_stand_in(driver_ws, tmp_path, ['source:=recording', 'recording:=' + path,
                                             'leap:=true'])
    raw, filtered = by_topic(got, 'raw'), by_topic(got, 'filtered')
    assert {r['md5'] for r in raw} == {DRIVER_MD5['Human']}
    assert len(raw) >= 0.9 * len(frames), (len(raw), len(frames))
    both = 0
    gestures = {}
    for r in raw:
        f = source[r['frame']]
        assert r['frame_id'] == 'leap_hands'
        for side in ('right', 'left'):
            h = f.hand(side)
            assert r[side]['present'] == (h is not None)
            if h is not None:
                check_hand(r[side], h)
                for g in r[side]['gestures']:
                    gestures.setdefault(g['type'], set()).add(g['state'])
        assert r['hands'] == len(f.hands)
        assert r['fingers'] == 5 * len(f.hands)
        both += len(f.hands) == 2
        # Every SDK gesture of a known type comes out on its hand, typed and staged.
        want = sorted((g['id'], {'swipe': 1, 'circle': 4, 'screenTap': 5, 'keyTap': 6}[g['type']],
                       {'start': 1, 'update': 2, 'stop': 3}[g['state']]) for g in f.gestures)
        have = sorted((g['id'], g['type'], g['state']) for side in ('right', 'left')
                      for g in r[side]['gestures'])
        assert have == want, r['frame']
        assert r['gestures'] == len(want)
    assert both > 100
    # The recording has swipes, circles and key taps (flapping.json.lz).
    assert gestures[1] == {1, 2, 3} and gestures[4] == {1, 2, 3} and 3 in gestures[6]
    # The recording's sphere fit reaches the consumer (checked per hand in check_hand).
    assert all(r[side]['sphere_radius'] > 0.02 for r in raw for side in ('right', 'left')
               if r[side]['present'])
    # The frame rate is the recording's (~104 fps); time_visible is the SDK's as recorded
    # (checked in check_hand): it grows while one hand (id) stays.
    assert 80 < raw[-1]['fps'] < 130
    right = [(r['right']['id'], r['right']['time_visible']) for r in raw if r['right']['present']]
    assert all(b[1] >= a[1] - 1e-4 for a, b in zip(right, right[1:]) if a[0] == b[0])
    assert max(t for _, t in right) > 2.0
    check_filtered(raw, filtered)
    check_markers(by_topic(got, 'markers'), raw)
    # The old leap message: Leap mm and degrees, for the right hand.
    leaps = [m for m in by_topic(got, 'leap') if m['palm'] != [0.0, 0.0, 0.0]]
    assert {m['md5'] for m in leaps} == {DRIVER_MD5['leap']}
    right_palms = [tuple(np.round(np.asarray(f.hand('right').palm_position), 6)) for f in frames
                   if f.hand('right') is not None]
    assert len(leaps) >= 0.9 * len(right_palms)
    for m in leaps:
        assert tuple(np.round(m['palm'], 6)) in set(right_palms)
        # The classic sender's angles: roll and pitch of the direction, yaw of the normal.
        n, d = m['normal'], m['direction']
        np.testing.assert_allclose(m['rpy'], np.degrees([math.atan2(d[0], -d[1]),
                                                          math.atan2(d[1], -d[2]),
                                                          math.atan2(n[0], -n[2])]), atol=1e-9)


CIRCLE_SCRIPT = """\
rate_hz: 120
hands:
  right:
    - {pose: absent, duration: 0.3}
    - {pose: open, palm: [0, 200, 0], duration: 0.6}
    - {pose: open, palm: [35, 200, 0], duration: 0.3}
    - {pose: open, circle: {radius: 35, turns: 1, direction: cw}, duration: 1.2}
    - {pose: fist, palm: [0, 200, 0], duration: 0.6}
    - {pose: absent, duration: 0.3}
"""


@pytest.mark.rostest
def test_a_scripted_hand_reaches_a_driver_consumer(driver_ws, tmp_path):
    script_path = tmp_path / 'circle.yaml'
    script_path.write_text(CIRCLE_SCRIPT)
    script = GestureScript.load(str(script_path))
    got = run_stand_in(driver_ws, tmp_path, ['source:=scripted', 'script:=%s' % script_path])
    raw = by_topic(got, 'raw')
    n = int(round(script.duration * script.rate_hz))
    assert len(raw) >= 0.9 * n, (len(raw), n)
    present = 0
    circles = []
    for r in raw:
        expected = script.hand_at('right', (r['frame'] - 1) / script.rate_hz)
        assert r['right']['present'] == (expected is not None), r['frame']
        assert not r['left']['present']
        if expected is not None:
            present += 1
            # The hand's id is the source's; palm, joints within float32 of the script.
            check_hand(r['right'], expected, tol_m=1e-6, tol_unit=1e-6)
            assert r['right']['grab'] == pytest.approx(expected.grab_strength, abs=1e-6)
            circles += [g for g in r['right']['gestures'] if g['type'] == 4]
    assert present > 0.7 * len(raw)
    # The recognizer's circle comes out as the driver's circle gesture (completed).
    assert len(circles) == 1 and circles[0]['state'] == 3 and circles[0]['valid'], circles
    check_filtered(raw, by_topic(got, 'filtered'))
    check_markers(by_topic(got, 'markers'), raw)


@pytest.mark.rostest
def test_the_video_source_reaches_a_driver_consumer(driver_ws, tmp_path):
    video = os.path.join(HANDS_DATA, 'clip_palm_motion__mps__hl_test_video.mp4')
    assert os.path.isfile(video), 'the shared hand clip is missing: %s' % video
    # leap_teleop's own Hand topics: a second view of the same source frames.
    got = run_stand_in(driver_ws, tmp_path, ['source:=video', 'video:=' + video],
                       max_time=150.0, echo=['/leapmotion/hand_right', '/leapmotion/hand_left'])
    own = {}
    for side in ('right', 'left'):
        with open(tmp_path / ('leapmotion_hand_%s.csv' % side)) as f:
            rows = list(csv.DictReader(f))
        for row in rows:
            if row['field.present'] in ('1', 'True'):
                own[(side, int(row['field.leap_frame_id']))] = row
    raw = [r for r in by_topic(got, 'raw') if r['right']['present'] or r['left']['present']]
    assert len(raw) > 30, len(by_topic(got, 'raw'))
    matched = 0
    for r in raw:
        for side in ('right', 'left'):
            h = r[side]
            if not h['present']:
                continue
            assert abs(np.linalg.norm(h['direction']) - 1) < 1e-5
            assert abs(np.linalg.norm(h['normal']) - 1) < 1e-5
            np.testing.assert_allclose(h['rpy'], sdk_angles(h['normal'], h['direction']),
                                       atol=1e-5)
            assert 0.05 < h['palm'][1] < 0.6            # metres above the virtual device
            row = own.get((side, r['frame']))
            if row is not None:
                matched += 1
                np.testing.assert_allclose(
                    h['palm'], [float(row['field.palm_position.' + a]) for a in 'xyz'], atol=1e-6)
                for i, f in enumerate(h['fingers']):
                    np.testing.assert_allclose(
                        f['bones'][3]['end'],
                        [float(row['field.finger_tips%d.%s' % (i, a)]) for a in 'xyz'], atol=1e-6)
            assert len(h['fingers']) == 5
            for f in h['fingers']:
                for b in f['bones'][1:]:
                    assert 0.005 < b['length'] < 0.08   # a finger bone, in metres
    assert matched > 0.8 * len(raw), (matched, len(raw))
    check_filtered(by_topic(got, 'raw'), by_topic(got, 'filtered'))
    check_markers(by_topic(got, 'markers'), by_topic(got, 'raw'))
