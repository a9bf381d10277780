"""A session recorded with record.launch replays into the consumers with the same outcome:
the dual-arm pick & place and the drone flight, through replay-driven rostests."""
import os
import signal
import subprocess
import sys
import time

import pytest
from test_rostests import check_every_test_passed

from leap_teleop.package_files import package_path
from tools.bench import ros_processes

# needs a ROS master, a simulator, a subprocess or a build: not in make check
pytestmark = pytest.mark.integration

HERE = os.path.dirname(os.path.abspath(__file__))


def record_session(tmp_path, script, topics, sides):
    """Run the real sender on `script` and record `topics` with record.launch."""
    bag = str(tmp_path / ('%s.bag' % os.path.basename(script).split('.')[0]))
    with ros_processes.ros_master() as env:
        recorder = subprocess.Popen(
            ['roslaunch', 'leap_teleop', 'record.launch', 'output:=' + bag,
             'topics:=' + ' '.join(topics)],
            env=env, stdout=subprocess.DEVNULL, stderr=subprocess.STDOUT, start_new_session=True)
        try:
            # The script starts once the recorder subscribes to every topic (a fixed wait
            # for roslaunch and rosbag to start can be outlasted on a loaded machine).
            sender = subprocess.run(
                [sys.executable, package_path('scripts', 'sender.py'), '_script:=' + script,
                 '_sides:=%s' % sides, '_shutdown_on_end:=true', '_wait_for_subscribers:=true',
                 '_wait_topics:=[%s]' % ', '.join(topics)],
                env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, timeout=120)
            assert sender.returncode == 0, sender.stderr.decode()[-2000:]
            time.sleep(1.0)
        finally:
            os.killpg(recorder.pid, signal.SIGINT)
            recorder.wait(30)
    assert os.path.getsize(bag) > 10000
    return bag


def rostest(test_file, tmp_path, **args):
    proc = subprocess.run(['rostest', test_file] + ['%s:=%s' % kv for kv in args.items()],
                          stdout=subprocess.PIPE, stderr=subprocess.STDOUT, timeout=300,
                          env=dict(os.environ, ROS_LOG_DIR=str(tmp_path / 'log')))
    out = proc.stdout.decode(errors='replace')
    assert proc.returncode == 0, out[-6000:]
    check_every_test_passed(test_file, out)


@pytest.mark.rostest
def test_recorded_dual_arm_session_replays_into_ur10_dual(tmp_path):
    bag = record_session(tmp_path, package_path('config', 'gestures', 'ur10_pick_place_dual.yaml'),
                         ['/leapmotion/data_right', '/leapmotion/data_left'], '[right, left]')
    rostest(os.path.join(HERE, 'ur10_teleop_dual.test'), tmp_path, bag=bag)


@pytest.mark.rostest
def test_recorded_drone_session_replays_into_the_pilot(tmp_path):
    bag = record_session(tmp_path, package_path('config', 'gestures', 'drone_flight.yaml'),
                         ['/leapmotion/hand_right', '/leapmotion/gestures'], '[right]')
    rostest(os.path.join(HERE, 'replay', 'drone_replay.test'), tmp_path, bag=bag)
