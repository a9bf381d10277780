"""A drone_pilot that ends (Ctrl-C) while steering leaves the drone hovering: the driver
holds the last cmd_vel, so the pilot's last word is a zero twist."""
import json
import os
import subprocess
import sys

import pytest
from pilot_client import PILOT_FEED, PILOT_FLYING

from tools.bench.ros_processes import ros_master, spawn_node, stop_spawned

# needs a ROS master and subprocesses: not in make check
pytestmark = pytest.mark.integration

HERE = os.path.dirname(os.path.abspath(__file__))

CLIENT = r'''
import json, sys, time
import rospy
from geometry_msgs.msg import Twist
rospy.init_node('pilot_client')
twists = []
twist_sub = rospy.Subscriber('cmd_vel', Twist, lambda m: twists.append(
    (m.linear.x, m.linear.y, m.linear.z, m.angular.z)), queue_size=1000)
''' + PILOT_FEED + PILOT_FLYING + r'''
state['palm'] = (0.0, 0.2, -0.08)          # forward of the reference
wait_until(lambda: twists and twists[-1][0] > 0.3, 'the pilot steering forward')
print('steering', flush=True)
wait_until(lambda: twist_sub.get_num_connections() == 0, 'the pilot gone', timeout=60.0)
time.sleep(0.2)
print(json.dumps({'last': twists[-1], 'forward': sum(t[0] > 0.3 for t in twists)}), flush=True)
'''


def test_a_pilot_stopped_while_steering_sends_a_hover_last():
    with ros_master() as env:
        pilot = spawn_node(env, [sys.executable, os.path.join(HERE, '..', 'scripts', 'drone_pilot.py'),
                                 '_hand_timeout:=2.0', '_navdata_timeout:=2.0'])
        client = subprocess.Popen([sys.executable, '-c', CLIENT], env=env, stdout=subprocess.PIPE,
                                  stderr=subprocess.PIPE, text=True, cwd=HERE)
        try:
            line = client.stdout.readline()
            assert line.strip() == 'steering', line + client.stderr.read()[-3000:]
            stop_spawned(pilot)
            assert pilot.returncode == 0
            out, err = client.communicate(timeout=90)
        finally:
            stop_spawned(pilot)
            if client.poll() is None:
                client.kill()
                client.communicate()
    assert client.returncode == 0, err[-3000:]
    got = json.loads(out.strip().splitlines()[-1])
    assert got['forward'] > 0 and got['last'] == [0.0, 0.0, 0.0, 0.0], got
