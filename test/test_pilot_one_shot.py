"""Takeoff and land before the driver listens: the pilot holds them instead of publishing
into nothing (HeldOneShot without ROS; then the drone_pilot node on a private master with a
driver whose subscriptions come late)."""
import json
import os
import subprocess
import sys

import pytest
from pilot_client import PILOT_FEED

from leap_teleop.drone.one_shot import HeldOneShot
from leap_teleop.drone.pilot import Command, DronePilot, PilotInput, PilotParams, PilotWorker

HERE = os.path.dirname(os.path.abspath(__file__))
SCRIPTS = os.path.join(HERE, '..', 'scripts')


class Driver:
    """Which one-shot topics have a subscriber, what was published, a settable clock."""

    def __init__(self):
        self.listening = set()
        self.published = []
        self.waits = []                      # None: sent at once, else seconds held
        self.now = 100.0
        self.warnings = []
        self.wanted = True                   # what the pilot says of a held takeoff

    def hold(self, takeoff_hold=1.0):
        return HeldOneShot(self.publish, lambda kind: kind in self.listening,
                           takeoff_hold, lambda: self.wanted, clock=lambda: self.now,
                           warn=lambda key, text: self.warnings.append(key))

    def publish(self, cmd, waited):
        self.published.append(cmd)
        self.waits.append(waited)


def kinds(cmds):
    return [c.kind for c in cmds]


def test_a_listened_one_shot_goes_out_at_once():
    d = Driver()
    d.listening = {'takeoff', 'land'}
    h = d.hold()
    assert h.send(Command('takeoff')) and h.send(Command('land'))
    assert kinds(d.published) == ['takeoff', 'land'] and h.pending is None
    assert h.held == 0 and not d.warnings and d.waits == [None, None]


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
    assert d.waits == [pytest.approx(0.9)]                     # the log line says so
    assert kinds(d.published) == ['takeoff'] and h.send_held() is None      # once only


def test_a_takeoff_held_past_the_hold_is_dropped_not_sent_late():
    d = Driver()
    h = d.hold(1.0)
    h.send(Command('takeoff'))
    d.now += 1.01
    assert h.send_held() is None and h.dropped == 1 and 'takeoff_dropped' in d.warnings
    d.listening.add('takeoff')
    assert h.send_held() is None and not d.published


def test_a_zero_hold_never_holds_a_takeoff():
    d = Driver()
    h = d.hold(0.0)
    assert not h.send(Command('takeoff'))
    assert h.pending is None and h.dropped == 1 and h.held == 0
    d.listening.add('takeoff')
    assert h.send_held() is None and not d.published


def test_a_stalled_caller_never_sends_a_takeoff_late():
    d = Driver()
    h = d.hold(1.0)
    h.send(Command('takeoff'))
    d.now += 5.0                             # the worker was stopped; the driver came meanwhile
    d.listening.add('takeoff')
    assert h.send_held() is None and not d.published and h.dropped == 1


def test_a_takeoff_the_pilot_no_longer_wants_is_dropped():
    d = Driver()
    h = d.hold(1.0)
    h.send(Command('takeoff'))
    d.wanted = False                         # a fold, a lost hand or stale navdata since
    d.listening.add('takeoff')
    assert h.send_held() is None and not d.published and h.dropped == 1
    d.wanted = True
    h.send(Command('land'))                  # a land is never the pilot's to withdraw
    assert kinds(d.published) == []
    d.wanted = False
    d.listening.add('land')
    assert h.send_held().kind == 'land'


def test_a_land_waits_as_long_as_it_takes():
    d = Driver()
    h = d.hold(1.0)
    h.send(Command('land'))
    for _ in range(100):
        d.now += 1.0
        assert h.send_held() is None
    d.listening.add('land')
    assert h.send_held().kind == 'land' and h.dropped == 0


def test_the_pilot_wants_a_held_takeoff_only_until_a_fold_a_lost_hand_or_stale_navdata():
    def landed_after_unfold():
        pilot = DronePilot(PilotParams())
        pilot.on_navdata(2, 0, 10.0)
        pilot.on_hand(PilotInput(True, (0.0, 0.2, 0.0), (0.0, -1.0, 0.0), (0.0, 0.0, -1.0)),
                      10.0)
        assert not pilot.takeoff_still_wanted(10.0)          # nobody asked yet
        pilot.on_gesture('unfold', True, 10.01)
        assert pilot.takeoff_still_wanted(10.02)
        return pilot
    pilot = landed_after_unfold()
    pilot.on_gesture('fold', True, 10.05)
    assert not pilot.takeoff_still_wanted(10.06)
    pilot = landed_after_unfold()
    pilot.on_gesture('hand_lost', True, 10.05)
    assert not pilot.takeoff_still_wanted(10.06)
    pilot = landed_after_unfold()
    assert not pilot.takeoff_still_wanted(10.0 + pilot.cfg.navdata_timeout + 0.01)
    pilot = landed_after_unfold()
    pilot.on_navdata(3, 1000, 10.03)                       # already flying
    assert not pilot.takeoff_still_wanted(10.04)


def test_the_worker_sends_a_held_land_even_when_its_watchdog_fails():
    class WatchdogFails(DronePilot):
        def watchdog(self, now):
            raise RuntimeError('broken watchdog')
    calls = []
    worker = PilotWorker(WatchdogFails(PilotParams()), lambda cmd: None, flip_call=None,
                         clock=lambda: 1.0, send_held=lambda: calls.append('held'))
    worker.step()
    worker.step()
    assert calls == ['held', 'held'] and worker.errors == 2


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
import json, time
import rospy
from diagnostic_msgs.msg import DiagnosticArray
from std_msgs.msg import Empty
rospy.init_node('driver_late')
got = {'takeoff': [], 'land': []}
held = []

def on_diagnostics(msg):
    held.extend(int(kv.value) for st in msg.status for kv in st.values
                if kv.key == 'takeoff / land held for the driver')

rospy.Subscriber('/diagnostics', DiagnosticArray, on_diagnostics, queue_size=10)
''' + PILOT_FEED + r'''

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
time.sleep(3.5)                            # past the takeoff hold: a land still waits
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
                                '_takeoff_hold:=3.0'])
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
