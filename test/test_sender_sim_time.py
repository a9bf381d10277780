"""The sender under /use_sim_time (a ROS master and a /clock publisher as subprocesses)."""
import subprocess
import sys
import textwrap

import pytest

from leap_teleop.package_files import package_path
from tools.bench import ros_processes

# needs a ROS master, a simulator, a subprocess or a build: not in make check
pytestmark = pytest.mark.integration

# /clock as a simulator started again and again would send it: 0.3 s of sim time at wall
# speed, then back to where it began.
SAWTOOTH_CLOCK = textwrap.dedent('''
    import time
    import rospy
    from rosgraph_msgs.msg import Clock
    rospy.set_param('/use_sim_time', True)
    rospy.init_node('sawtooth_clock')
    pub = rospy.Publisher('/clock', Clock, queue_size=10)
    print('ready', flush=True)
    k = 0
    while not rospy.core.is_shutdown_requested():
        pub.publish(Clock(clock=rospy.Time.from_sec(100.0 + (k % 30) * 0.01)))
        k += 1
        time.sleep(0.01)
''')

SCRIPT = 'rate_hz: 60\nhands:\n  right:\n    - {pose: open, palm: [0, 200, 0], duration: 1.0}\n'


def test_a_sender_whose_source_ends_while_the_clock_jumps_back_shuts_down_cleanly(tmp_path):
    # Its wait for subscribers to drain the last frames was a rospy.sleep, which raised
    # ROSTimeMovedBackwardsException: a traceback and status 1 instead of 'source ended'.
    script = tmp_path / 'short.yaml'
    script.write_text(SCRIPT)
    with ros_processes.ros_master() as env:
        clock = subprocess.Popen([sys.executable, '-c', SAWTOOTH_CLOCK], env=env, stdout=subprocess.PIPE,
                                 stderr=subprocess.DEVNULL, text=True)
        try:
            assert clock.stdout.readline().strip() == 'ready'
            sender = subprocess.run([sys.executable, package_path('scripts', 'sender.py'), '_script:=%s' % script,
                                     '_sides:=[right]', '_shutdown_on_end:=true'],
                                    env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                                    timeout=60)
        finally:
            ros_processes.stop_spawned(clock)
    out = sender.stdout[-3000:]
    assert sender.returncode == 0, out
    assert 'source ended after' in out and 'Traceback' not in out, out
