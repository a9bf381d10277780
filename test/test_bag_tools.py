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
    assert got['/leapmotion/data_right'] == ('leap_teleop/leapcobotright', frames)
    assert got['/leapmotion/hand_right'] == ('leap_teleop/Hand', frames)
    # The gesture events are the ones the sender's logic finds in the take, in order.
    from leap_teleop.hands.leap_interface import LeapInterface
    from leap_teleop.hands.sources import make_source
    from leap_teleop.ros import hand_conversions
    li, want = LeapInterface(sides=['right', 'left']), []
    li.add_hand_listener(lambda frame, state: want.extend(
        (m.side, m.gesture, m.active) for m in hand_conversions.to_gesture_events(state)))
    for frame in make_source('recording', path=os.path.join(leapjs_data, 'grab.json.lz'),
                             realtime=False).frames():
        li.on_frame(frame)
    with rosbag.Bag(out) as b:
        events = [(m.side, m.gesture, m.active)
                  for _, m, _ in b.read_messages(topics=['/leapmotion/gestures'])]
    assert events == want and ('fist' in [g for _, g, _ in events]), events


def test_to_bag_writes_a_scripted_session(tmp_path):
    out = str(tmp_path / 'dual.bag')
    said = run([sys.executable, '-m', 'leap_teleop.ros.recording_to_bag', '--script',
                'config/gestures/ur10_pick_place_dual.yaml', out])
    frames = int(said.split(':')[-1].split()[0])
    assert frames == 2424, said                     # 20.2 s at 120 Hz
    got = topics(out)
    for side in ('right', 'left'):
        assert got['/leapmotion/data_' + side] == ('leap_teleop/leapcobot' + side, frames)
        assert got['/leapmotion/hand_' + side] == ('leap_teleop/Hand', frames)


# -- bad input ------------------------------------------------------------------------

@pytest.mark.parametrize('args, message', [
    (['--sides', 'middle'], "argument --sides: 'middle': one or more of right, left"),
    (['--kinds', 'foo'], "argument --kinds: 'foo': one or more of leapcobot, hand, gesture"),
    (['--start', 'nan'], "argument --start: 'nan': seconds since 1970, 0 or more"),
    (['--start', '-5'], "argument --start: '-5': seconds since 1970, 0 or more"),
    (['--start', 'inf'], "argument --start: 'inf': seconds since 1970, 0 or more"),
    (['--right-topic='], "--right-topic '': not a legal ROS topic name"),
    (['--left-topic=a b'], "--left-topic 'a b': not a legal ROS topic name"),
    (['--left-topic=~data'], "--left-topic '~data': a bag has no node to be private to"),
    # two outputs on one topic: on replay a subscriber of the other type got none of them
    (['--right-topic=/x', '--left-topic=x'],
     'the right leapcobot and the left leapcobot are both on /x: one topic per output'),
    (['--right-topic=/leapmotion/hand_right'],
     'the right leapcobot and the right hand are both on /leapmotion/hand_right'),
    (['--left-topic=leapmotion/gestures'],
     'the right gesture and the left leapcobot are both on /leapmotion/gestures'),
])
def test_recording_to_bag_refuses_bad_arguments(tmp_path, leapjs_data, capsys, args, message):
    from leap_teleop.ros import recording_to_bag
    with pytest.raises(SystemExit) as stop:
        recording_to_bag.main([os.path.join(leapjs_data, 'grab.json.lz'), str(tmp_path / 'b.bag')]
                              + args)
    assert stop.value.code == 2
    assert message in capsys.readouterr().err.splitlines()[-1]
    assert os.listdir(tmp_path) == []


def test_recording_to_bag_takes_a_shared_topic_only_one_output_writes(tmp_path, leapjs_data):
    from leap_teleop.ros import recording_to_bag
    take = os.path.join(leapjs_data, 'grab.json.lz')
    out = tmp_path / 'right.bag'
    assert recording_to_bag.main([take, str(out), '--sides', 'right', '--left-topic',
                                  '/leapmotion/data_right']) == 0
    out = tmp_path / 'leapcobot.bag'
    assert recording_to_bag.main([take, str(out), '--kinds', 'leapcobot', '--right-topic',
                                  '/leapmotion/hand_right']) == 0
    assert topics(str(out)) == {'/leapmotion/hand_right': ('leap_teleop/leapcobotright', 374),
                                '/leapmotion/data_left': ('leap_teleop/leapcobotleft', 374)}


def test_recording_to_bag_refuses_an_output_without_a_folder(tmp_path, leapjs_data, capsys):
    from leap_teleop.ros import recording_to_bag
    out = tmp_path / 'no_dir' / 'b.bag'
    with pytest.raises(SystemExit) as stop:
        recording_to_bag.main([os.path.join(leapjs_data, 'grab.json.lz'), str(out)])
    assert stop.value.code == 2
    assert capsys.readouterr().err.splitlines()[-1].endswith(
        ': error: %s: no folder %s' % (out, out.parent))


def test_recording_to_bag_reports_the_frames_it_wrote(tmp_path, leapjs_data, capsys):
    """A frame counts when it put a message into the bag; nothing to write is an error."""
    from leap_teleop.ros import recording_to_bag
    take = os.path.join(leapjs_data, 'grab.json.lz')
    out = tmp_path / 'gestures.bag'
    assert recording_to_bag.main([take, str(out), '--kinds', 'gesture']) == 0
    said = capsys.readouterr().out
    with rosbag.Bag(str(out)) as b:
        stamps = {t for _, _, t in b.read_messages()}
    assert 0 < len(stamps) < 374 and said == 'wrote %s: %d frames\n' % (out, len(stamps))
    empty = tmp_path / 'empty.bag'
    assert recording_to_bag.main([take, str(empty), '--sides', 'left', '--kinds', 'gesture']) == 1
    assert capsys.readouterr().err.endswith(
        'recording_to_bag: no gesture message for the left hand: nothing written to %s\n' % empty)
    assert not empty.exists()
    late = tmp_path / 'late.bag'    # the take's 3.4 s pass the end of ROS time
    assert recording_to_bag.main([take, str(late), '--start', str(2 ** 32 - 2)]) == 1
    assert 'past the end of ROS time' in capsys.readouterr().err
    assert not late.exists()


def test_recording_to_bag_help_gives_the_whole_first_paragraph(capsys):
    from leap_teleop.ros import recording_to_bag
    with pytest.raises(SystemExit) as stop:
        recording_to_bag.main(['--help'])
    assert stop.value.code == 0
    out = ' '.join(capsys.readouterr().out.split())
    assert "into a bag of the sender's topics." in out
    for option, help_text in (('--sides SIDES', 'which hands'),
                              ('--right-topic RIGHT_TOPIC', "the right hand's"),
                              ('--left-topic LEFT_TOPIC', "the left hand's")):
        assert '%s %s' % (option, help_text) in out, out


def test_recording_to_bag_letterboxes_camera_footage_as_the_sender_does(tmp_path, detector_sizes):
    # Before: --video gave the detector the images as they came, while the sender
    # letterboxes them to 640x480: the bag held other hands than the sender publishes.
    import cv2
    import numpy as np

    from leap_teleop.ros import recording_to_bag
    image = str(tmp_path / 'wide.png')
    cv2.imwrite(image, np.zeros((720, 1280, 3), np.uint8))
    out = tmp_path / 'x.bag'
    assert recording_to_bag.main(['--video', image, str(out)]) == 0
    assert detector_sizes == [(480, 640, 3)]
