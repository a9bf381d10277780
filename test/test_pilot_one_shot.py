"""Takeoff and land before the driver listens: the pilot holds them instead of publishing
into nothing (HeldOneShot without ROS; then the drone_pilot node on a private master with a
driver whose subscriptions come late)."""
import json
import os
import subprocess
import sys

import pytest

from leap_teleop.drone.one_shot import HeldOneShot
from leap_teleop.drone.pilot import Command

HERE = os.path.dirname(os.path.abspath(__file__))
SCRIPTS = os.path.join(HERE, '..', 'scripts')


class Driver:
    """Which one-shot topics have a subscriber, what was published, a settable clock."""

    def __init__(self):
        self.listening = set()
        self.published = []
        self.now = 100.0
        self.warnings = []

    def hold(self, takeoff_hold=1.0):
        return HeldOneShot(self.published.append, lambda kind: kind in self.listening,
                           takeoff_hold, clock=lambda: self.now,
                           warn=lambda key, text: self.warnings.append(key))


def kinds(cmds):
    return [c.kind for c in cmds]


def test_a_listened_one_shot_goes_out_at_once():
    d = Driver()
    d.listening = {'takeoff', 'land'}
    h = d.hold()
    assert h.send(Command('takeoff')) and h.send(Command('land'))
    assert kinds(d.published) == ['takeoff', 'land'] and h.pending is None
    assert h.held == 0 and not d.warnings


def test_a_takeoff_waits_for_the_driver_within_the_hold():
    d = Driver()
    h = d.hold(1.0)
    assert not h.send(Command('takeoff', input_stamp=99.9))
    assert d.warnings == ['held_takeoff'] and h.held == 1
    d.now += 0.5
    assert h.send_held() is None and not d.published          # nobody yet: still held
    d.listening.add('takeoff')
    d.now += 0.4
    sent = h.send_held()
    assert sent.kind == 'takeoff' and sent.input_stamp == 99.9
    assert kinds(d.published) == ['takeoff'] and h.send_held() is None      # once only


def test_a_takeoff_held_past_the_hold_is_dropped_not_sent_late():
    d = Driver()
    h = d.hold(1.0)
    h.send(Command('takeoff'))
    d.now += 1.01
    assert h.send_held() is None and h.dropped == 1 and 'takeoff_dropped' in d.warnings
    d.listening.add('takeoff')
    assert h.send_held() is None and not d.published


def test_a_zero_hold_never_sends_a_takeoff_late():
    d = Driver()
    h = d.hold(0.0)
    h.send(Command('takeoff'))
    d.now += 0.001
    h.send_held()
    d.listening.add('takeoff')
    assert h.send_held() is None and not d.published and h.dropped == 1


def test_a_land_waits_as_long_as_it_takes():
    d = Driver()
    h = d.hold(1.0)
    h.send(Command('land'))
    for _ in range(100):
        d.now += 1.0
        assert h.send_held() is None
    d.listening.add('land')
    assert h.send_held().kind == 'land' and h.dropped == 0


def test_the_latest_one_shot_replaces_a_held_one():
    d = Driver()
    h = d.hold(5.0)
    h.send(Command('takeoff'))
    h.send(Command('land'))                  # the person folded before the driver came
    assert 'one_shot_replaced' in d.warnings
    d.listening = {'takeoff', 'land'}
    h.send_held()
    assert kinds(d.published) == ['land']
    h.send(Command('takeoff'))
    assert kinds(d.published) == ['land', 'takeoff']


def test_a_connected_send_clears_a_held_one():
    d = Driver()
    h = d.hold(5.0)
    h.send(Command('land'))                  # the land topic has no subscriber
    d.listening.add('takeoff')
    h.send(Command('takeoff'))               # newer, and its topic listens
    d.listening.add('land')
    assert h.send_held() is None and kinds(d.published) == ['takeoff']


CLIENT = r'''
import json, threading, time
import rospy
from diagnostic_msgs.msg import DiagnosticArray
from std_msgs.msg import Empty
from leap_teleop.msg import GestureEvent, Hand, Navdata
rospy.init_node('driver_late')
state = {'nav': 2}
got = {'takeoff': [], 'land': []}
held = []

def on_diagnostics(msg):
    held.extend(int(kv.value) for st in msg.status for kv in st.values
                if kv.key == 'takeoff / land held for the driver')

rospy.Subscriber('/diagnostics', DiagnosticArray, on_diagnostics, queue_size=10)
hand_pub = rospy.Publisher('leapmotion/hand_right', Hand, queue_size=10)
nav_pub = rospy.Publisher('ardrone/navdata', Navdata, queue_size=10)
gesture_pub = rospy.Publisher('leapmotion/gestures', GestureEvent, queue_size=10)

def feed():
    while not rospy.is_shutdown():
        h = Hand(side=0, present=True)
        h.header.stamp = rospy.Time.now()
        h.palm_position.y, h.palm_normal.y, h.direction.z = 0.2, -1.0, -1.0
        hand_pub.publish(h)
        nav_pub.publish(Navdata(state=state['nav'], altd=1000))
        time.sleep(0.02)

def wait(cond, timeout=20.0):
    t_end = time.monotonic() + timeout
    while not cond() and time.monotonic() < t_end:
        time.sleep(0.01)
    return cond()

def listen(kind):
    return rospy.Subscriber('ardrone/' + kind, Empty,
                            lambda _m: got[kind].append(time.monotonic()), queue_size=10)

def gesture(name):
    gesture_pub.publish(GestureEvent(side=0, gesture=name, active=True))

threading.Thread(target=feed, daemon=True).start()
out = {'wired': wait(lambda: gesture_pub.get_num_connections() > 0
                     and nav_pub.get_num_connections() > 0)}
time.sleep(1.0)                            # fresh navdata: landed
gesture('unfold')                          # nothing listens on ardrone/takeoff yet
time.sleep(0.3)
listen('takeoff')
out['late_takeoff'] = wait(lambda: got['takeoff'], 3.0) and len(got['takeoff'])
state['nav'] = 3
time.sleep(0.5)
gesture('fold')                            # nothing listens on ardrone/land yet
time.sleep(1.5)                            # past the takeoff hold: a land still waits
listen('land')
out['late_land'] = wait(lambda: got['land'], 3.0) and len(got['land'])
out['held'] = wait(lambda: held and held[-1] == 2, 5.0) and held[-1]
print(json.dumps(out))
'''


@pytest.mark.integration
@pytest.mark.rostest
def test_the_pilot_holds_takeoff_and_land_until_the_driver_listens():
    from tools.bench.ros_processes import ros_master, spawn_node, stop_spawned
    with ros_master() as env:
        node = spawn_node(env, [sys.executable, os.path.join(SCRIPTS, 'drone_pilot.py'),
                                '_takeoff_hold:=0.6'])
        try:
            run = subprocess.run([sys.executable, '-c', CLIENT], env=env, capture_output=True,
                                 text=True, timeout=120)
        finally:
            stop_spawned(node)
            err = node.stderr.read().decode(errors='replace')
    assert run.returncode == 0, run.stdout[-3000:] + run.stderr[-3000:]
    out = json.loads(run.stdout.strip().splitlines()[-1])
    assert out == {'wired': True, 'late_takeoff': 1, 'late_land': 1, 'held': 2}, (
        out, err[-3000:])
    assert 'nothing listens on ardrone/takeoff yet' in err, err[-3000:]
    assert 'nothing listens on ardrone/land yet' in err
