"""The bag tools docs/usage.md shows, as commands: `rosrun leap_teleop recording_to_bag` on a
shared recording and `python -m leap_teleop.ros.recording_to_bag --script` on a session write the
sender's topics, one message per frame and side."""
import os
import subprocess
import sys

import pytest
import rosbag

# needs a ROS master, a simulator, a subprocess or a build: not in make check
pytestmark = pytest.mark.integration

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def topics(path):
    with rosbag.Bag(path) as b:
        return {t: (i.msg_type, i.message_count) for t, i in b.get_type_and_topic_info().topics.items()}


def run(cmd):
    proc = subprocess.run(cmd, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                          text=True, timeout=300)
    assert proc.returncode == 0, proc.stdout
    return proc.stdout


def test_recording_to_bag_writes_the_take(tmp_path, leapjs_data):
    out = str(tmp_path / 'grab.bag')
    said = run(['rosrun', 'leap_teleop', 'recording_to_bag',
                os.path.join(leapjs_data, 'grab.json.lz'), out])
    frames = int(said.split(':')[-1].split()[0])
    assert frames == 374, said                      # grab.json.lz: 374 frames
    got = topics(out)
    assert got['leapmotion/data_right'] == ('leap_teleop/leapcobotright', frames)
    assert got['leapmotion/hand_right'] == ('leap_teleop/Hand', frames)
    # The gesture events are the ones the sender's logic finds in the take, in order.
    from leap_teleop.hands.leap_interface import LeapInterface
    from leap_teleop.hands.sources import make_source
    from leap_teleop.ros import conversions
    li, want = LeapInterface(sides=['right', 'left']), []
    li.add_hand_listener(lambda frame, state: want.extend(
        (m.side, m.gesture, m.active) for m in conversions.to_gesture_events(state)))
    for frame in make_source('recording', path=os.path.join(leapjs_data, 'grab.json.lz'),
                             realtime=False).frames():
        li.on_frame(frame)
    with rosbag.Bag(out) as b:
        events = [(m.side, m.gesture, m.active)
                  for _, m, _ in b.read_messages(topics=['leapmotion/gestures'])]
    assert events == want and ('fist' in [g for _, g, _ in events]), events


def test_to_bag_writes_a_scripted_session(tmp_path):
    out = str(tmp_path / 'dual.bag')
    said = run([sys.executable, '-m', 'leap_teleop.ros.recording_to_bag', '--script',
                'config/gestures/ur10_pick_place_dual.yaml', out])
    frames = int(said.split(':')[-1].split()[0])
    assert frames == 2424, said                     # 20.2 s at 120 Hz
    got = topics(out)
    for side in ('right', 'left'):
        assert got['leapmotion/data_' + side] == ('leap_teleop/leapcobot' + side, frames)
        assert got['leapmotion/hand_' + side] == ('leap_teleop/Hand', frames)
