"""dynamic_reconfigure on ur10_arm, the drone pilot and the sender: the servers are built
from the nodes' Param declarations (same bounds), only the runtime subset is offered, and
`dynparam set` changes behaviour live; an out-of-range or NaN value is refused, the previous
value kept (a limit cannot be disabled that way)."""
import json
import os
import subprocess
import sys

import pytest
from pilot_client import PILOT_FEED, PILOT_FLYING

from leap_teleop.ros.nodes import drone_pilot, sender, ur10_arm
from leap_teleop.ros.reconfigure import bounds, config_type
from tools.bench.ros_processes import ros_master, spawn_node, stop_spawned

# needs a ROS master, a simulator, a subprocess or a build: not in make check
pytestmark = pytest.mark.integration

HERE = os.path.dirname(os.path.abspath(__file__))
SCRIPTS = os.path.join(HERE, '..', 'scripts')
NODES = [(ur10_arm, 'ur10_arm'), (drone_pilot, 'drone_pilot'), (sender, 'sender')]
# Start-up only: watchdog times, modes, rates, topics, sources.
STARTUP_ONLY = {
    'ur10_arm': {'mode', 'orientation', 'gripper_mode', 'input_timeout', 'joint_timeout',
                 'max_input_age', 'hand', 'hand_topic', 'rate', 'axis_map', 'workspace_min',
                 'workspace_max'},
    'drone_pilot': {'mode', 'hand_timeout', 'land_after', 'navdata_timeout', 'max_input_age',
                    'rate', 'queue_size', 'side', 'hand_topic', 'gesture_topic'},
    'sender': {'source', 'sides', 'human_topic', 'filtered_human_topic', 'rotation_dead_bands',
               'frame_id', 'freq', 'rate'},
}


@pytest.mark.parametrize('module, name', NODES, ids=[n for _, n in NODES])
def test_the_servers_offer_the_runtime_subset_with_the_declared_bounds(module, name):
    names = module.RECONFIGURABLE
    assert len(set(names)) == len(names) and set(names) <= set(module.PARAMS)
    assert not set(names) & STARTUP_ONLY[name]
    defaults = {n: module.PARAMS[n].default for n in names}
    t = config_type(module.PARAMS, names, defaults)
    for n in names:
        p = module.PARAMS[n]
        assert p.kind in ('int', 'float', 'bool')
        lo = p.ge if p.ge is not None else p.gt
        hi = p.le if p.le is not None else p.lt
        assert (t.min[n], t.max[n]) == (lo, hi) == bounds(p), n      # every one is bounded
        assert t.defaults[n] == p.default
        assert t.type[n] == {'int': 'int', 'float': 'double', 'bool': 'bool'}[p.kind]
    descr = {q['name']: q['description'] for q in t.config_description['parameters']}
    assert all(module.PARAMS[n].allowed() in descr[n] for n in names)


def test_a_string_parameter_is_not_offered():
    with pytest.raises(ValueError):
        config_type(sender.PARAMS, ['source'], {'source': 'scripted'})


def test_a_request_with_one_refused_value_changes_nothing(monkeypatch):
    # One request (a tuning file loaded at once) whose max_cmd was NaN still applied its
    # 5x steeper full_scale, with the cap meant to go with it left as it was.
    from leap_teleop.drone.pilot_params import PILOT_RECONFIGURABLE, PilotParams
    from leap_teleop.ros import reconfigure

    class Server:
        def __init__(self, _type, callback):
            self.callback = callback
    monkeypatch.setattr(reconfigure, '_RefusingServer', Server)
    cfg = PilotParams()
    applied = []
    r = reconfigure.Reconfigure('drone_pilot', drone_pilot.PARAMS, PILOT_RECONFIGURABLE, vars(cfg),
                                applied.append)
    before = dict(r.values)
    out = r._on_request(dict(before, dead_zone=0.10, full_scale=0.02, max_cmd=float('nan')), 1)
    assert applied == [] and r.values == before
    assert {k: out[k] for k in before} == before            # what clients are shown
    assert r.refused == 3
    out = r._on_request(dict(before, dead_zone=0.10, full_scale=0.02), 1)
    assert applied == [{'dead_zone': 0.10, 'full_scale': 0.02}]


def test_retune_reaches_the_arms_filters_and_servo():
    from leap_teleop.ur10.teleop import ArmTeleop
    teleop = ArmTeleop()
    teleop.retune({'filter_beta': 0.5, 'rotation_d_cutoff_hz': 2.0,
                    'max_joint_speed': 0.02, 'max_joint_accel': 0.3,
                             'servo_gain': 5.0, 'scale': 1.5})
    assert teleop.p.scale == 1.5 and teleop._filter.beta == 0.5
    assert teleop._rotation_filter.d_cutoff_hz == 2.0
    assert float(max(teleop._servo.max_speed)) == 0.02
    assert float(max(teleop._servo.max_accel)) == 0.3 and teleop._servo.gain == 5.0


def run_client(env, code, timeout=180):
    out = subprocess.run([sys.executable, '-c', code], env=env, capture_output=True, text=True,
                         timeout=timeout)
    assert out.returncode == 0, out.stdout[-3000:] + out.stderr[-3000:]
    return json.loads(out.stdout.strip().splitlines()[-1])


def run_node_and_client(script, args, client):
    """scripts/`script` with `args` on a private master and the client code beside it:
    (what the client printed, as JSON; the node's stderr)."""
    with ros_master() as env:
        node = spawn_node(env, [sys.executable, os.path.join(SCRIPTS, script)] + args)
        try:
            out = run_client(env, client)
        finally:
            stop_spawned(node)
            err = node.stderr.read().decode(errors='replace')
    return out, err


CLIENT_HEAD = r'''
import json, subprocess, threading, time
import rospy

def dynparam(*args):
    # the command-line tool, as a user runs it
    out = subprocess.run(['rosrun', 'dynamic_reconfigure', 'dynparam'] + [str(a) for a in args],
                         capture_output=True, text=True, timeout=60)
    return out.stdout + out.stderr

_clients = {}

def client(node):
    # the server call `dynparam` makes, without a process (a second or so of CPU) per value
    import dynamic_reconfigure.client
    if node not in _clients:
        _clients[node] = dynamic_reconfigure.client.Client(node, timeout=30)
    return _clients[node]

def set_each(node, name, values):
    out = []
    for v in values:
        try:
            out.append(str(client(node).update_configuration({name: v})))
        except Exception as e:      # what dynparam would print
            out.append(repr(e))
    return out

def get(node):
    return client(node).get_configuration(timeout=30)
'''

PILOT_CLIENT = CLIENT_HEAD + r'''
from geometry_msgs.msg import Twist
rospy.init_node('pilot_client')
twists = []
twist_sub = rospy.Subscriber('cmd_vel', Twist, lambda m: twists.append((time.monotonic(), m.linear.y)),
                 queue_size=1000)
''' + PILOT_FEED + PILOT_FLYING + r'''
state['palm'] = (0.05, 0.2, 0.0)           # 50 mm right of the reference
wait_until(lambda: twists and twists[-1][1] != 0.0, 'the pilot steering')

def window(secs=1.2):
    t0 = time.monotonic()
    time.sleep(secs)
    return [y for t, y in twists if t > t0 + 0.3]

out = {}
out['default'] = window()
out['set'] = dynparam('set', '/drone_pilot', 'dead_zone', 0.06)
out['wide_dead_zone'] = window()
out['bad'] = set_each('/drone_pilot', 'dead_zone', (float('nan'), 0.9, -1.0))
out['after_bad_dead_zone'] = window()
out['dead_zone'] = get('/drone_pilot')['dead_zone']
state['palm'] = (0.3, 0.2, 0.0)            # far: the command cap decides
out['full'] = window()
dynparam('set', '/drone_pilot', 'max_cmd', 0.1)
out['capped'] = window()
set_each('/drone_pilot', 'max_cmd', (float('nan'), 5.0, 0.0, -0.5))
out['after_bad_cap'] = window()
out['max_cmd'] = get('/drone_pilot')['max_cmd']
print(json.dumps(out))
'''


@pytest.mark.rostest
def test_dynparam_retunes_the_pilot_and_cannot_disable_its_limits():
    # A stream stalled past hand_timeout (0.15 s, easily reached on a loaded machine)
    # re-captures the reference where the hand is: the windows below would read zeros.
    out, err = run_node_and_client('drone_pilot.py', ['_hand_timeout:=2.0', '_navdata_timeout:=2.0'],
                                   PILOT_CLIENT)
    assert 'no Hand message' not in err, err[-3000:]
    assert out['default'] and all(y == pytest.approx(-0.2) for y in out['default']), out
    assert out['wide_dead_zone'] and all(y == 0.0 for y in out['wide_dead_zone']), out
    assert out['after_bad_dead_zone'] and all(y == 0.0 for y in out['after_bad_dead_zone'])
    assert out['dead_zone'] == 0.06
    assert out['full'] and all(y == pytest.approx(-1.0) for y in out['full'])
    assert out['capped'] and all(y == pytest.approx(-0.1) for y in out['capped'])
    assert out['after_bad_cap'] and all(y == pytest.approx(-0.1) for y in out['after_bad_cap'])
    assert out['max_cmd'] == 0.1
    assert 'refused ~dead_zone = nan' in err and 'refused ~max_cmd = 5.0' in err, err[-3000:]


ARM_CLIENT = CLIENT_HEAD + r'''
import math
from sensor_msgs.msg import JointState
from trajectory_msgs.msg import JointTrajectory
from leap_teleop.msg import ArmStatus, leapcobotright
from leap_teleop.ur10.kinematics import HOME_Q, JOINT_NAMES
rospy.init_node('arm_client')
hand = {'thumb_up': False, 'rock': False, 'palm': (0.0, 200.0, 0.0)}
states, speeds = [], []
rospy.Subscriber('ur10_arm/status', ArmStatus,
                 lambda m: states.append((time.monotonic(), m.state)), queue_size=100)
robot = list(HOME_Q)        # the robot follows each command (to its first point)

def on_command(m):
    speeds.append((time.monotonic(), max((abs(v) for p in m.points for v in p.velocities),
                                         default=0.0)))
    robot[:] = m.points[0].positions
rospy.Subscriber('arm_controller/command', JointTrajectory, on_command, queue_size=1000)
joints = rospy.Publisher('joint_states', JointState, queue_size=10)
hands = rospy.Publisher('leapmotion/data_right', leapcobotright, queue_size=10)

def feed():
    while not rospy.is_shutdown():
        joints.publish(JointState(name=list(JOINT_NAMES), position=list(robot)))
        m = leapcobotright(is_right_hand=True, right_hand_thumb_up=hand['thumb_up'],
                           right_hand_set_origin_frame_detected=hand['rock'])
        m.header.stamp = rospy.Time.now()
        m.right_hand_palmpos.x, m.right_hand_palmpos.y, m.right_hand_palmpos.z = hand['palm']
        hands.publish(m)
        time.sleep(0.01)

threading.Thread(target=feed, daemon=True).start()
time.sleep(2.0)

def state_after(**pose):
    hand.update(pose)
    time.sleep(1.0)
    return states[-1][1] if states else None

def top_speed(secs=1.5):
    t0 = time.monotonic()
    for i in range(int(secs / 0.1)):       # the palm swings +-40 mm: the target keeps moving
        hand['palm'] = (40.0 if i % 10 < 5 else -40.0, 200.0, 0.0)
        time.sleep(0.1)
    return max((s for t, s in speeds if t > t0 + 0.3), default=None)

out = {}
out['set_hold'] = dynparam('set', '/ur10_arm', 'arm_hold_s', 2.0)
out['long_hold'] = state_after(thumb_up=True)       # held 1 s < 2 s: not armed
state_after(thumb_up=False)
dynparam('set', '/ur10_arm', 'arm_hold_s', 0.3)
out['short_hold'] = state_after(thumb_up=True)      # held 1 s > 0.3 s: armed
out['tracking'] = state_after(thumb_up=False, rock=True)
hand['rock'] = False
out['speed_default'] = top_speed()
dynparam('set', '/ur10_arm', 'max_joint_speed', 0.02)
out['speed_slow'] = top_speed()
set_each('/ur10_arm', 'max_joint_speed', (float('nan'), 10.0, 0.0, -1.0))
out['speed_after_bad'] = top_speed()
out['max_joint_speed'] = get('/ur10_arm')['max_joint_speed']
print(json.dumps(out))
'''


@pytest.mark.rostest
def test_dynparam_retunes_the_arm_and_cannot_disable_its_speed_limit():
    # ~deadzone_mm: the arm's old name of ~dead_zone, left in a user's YAML.
    out, err = run_node_and_client('ur10_arm.py', ['_deadzone_mm:=20.0'], ARM_CLIENT)
    assert out['long_hold'] == 'disarmed' and out['short_hold'] == 'armed', out
    assert out['tracking'] == 'tracking', out
    assert out['speed_default'] == pytest.approx(0.05, abs=1e-6), out
    assert out['speed_slow'] == pytest.approx(0.02, abs=1e-6), out
    assert out['speed_after_bad'] == pytest.approx(0.02, abs=1e-6), out
    assert out['max_joint_speed'] == 0.02
    assert 'refused ~max_joint_speed = nan' in err and 'refused ~max_joint_speed = 10' in err, \
        err[-3000:]
    assert err.count('~deadzone_mm is not a parameter of ur10_arm (did you mean ~dead_zone?); '
                     'ignored') == 1, err[-3000:]


SENDER_SCRIPT = """\
rate_hz: 120
hands:
  right:
    - {pose: open, palm: [-50, 200, 0], duration: 0.5}
    - {pose: fist, palm: [50, 200, 0], duration: 0.5}
"""

SENDER_CLIENT = CLIENT_HEAD + r'''
from leap_teleop.msg import DriverHuman, GestureEvent
rospy.init_node('sender_client')
fists, raw, filtered = [], {}, {}
rospy.Subscriber('leapmotion/gestures', GestureEvent,
                 lambda m: m.gesture == 'fist' and m.active and fists.append(time.monotonic()),
                 queue_size=1000)

def keep(store):
    return lambda m: store.__setitem__(m.lmc_frame_id,
                                       (time.monotonic(), m.right_hand.palm_center.x))

rospy.Subscriber('leap_motion/leap_device', DriverHuman, keep(raw), queue_size=1000)
rospy.Subscriber('leap_motion/filtered_values', DriverHuman, keep(filtered), queue_size=1000)
time.sleep(2.0)

def window(secs=2.5):
    t0 = time.monotonic()
    time.sleep(secs)
    starts = len([t for t in fists if t > t0 + 0.3])
    got, seen = dict(filtered), dict(raw)     # copies: the subscribers keep adding
    lag = [abs(got[k][1] - seen[k][1]) for k in got if k in seen and got[k][0] > t0 + 0.3]
    return starts, sum(lag) / max(len(lag), 1)

out = {'default': window()}
dynparam('set', '/leap_sender', 'recognizer_on_frames', 100)   # fists last 60 frames
out['slow_recognizer'] = window()
set_each('/leap_sender', 'recognizer_on_frames', (0, 1000, -3))
out['after_bad_frames'] = window()
out['on_frames'] = get('/leap_sender')['recognizer_on_frames']
dynparam('set', '/leap_sender', 'recognizer_on_frames', 3)
dynparam('set', '/leap_sender', 'filter_cutoff', 1.0)
out['light_filter'] = window()
dynparam('set', '/leap_sender', 'filter_cutoff', 40.0)
out['heavy_filter'] = window()
set_each('/leap_sender', 'filter_cutoff', (float('nan'), 0.0, -1.0, 5000.0))
out['after_bad_cutoff'] = window()
out['cutoff'] = get('/leap_sender')['filter_cutoff']
print(json.dumps(out))
'''


@pytest.mark.rostest
def test_dynparam_retunes_the_senders_recognizer_and_filter(tmp_path):
    script = tmp_path / 'open_fist.yaml'
    script.write_text(SENDER_SCRIPT)
    out, err = run_node_and_client('sender.py', [
        '_script:=%s' % script, '_loop:=true', '_sides:=[right]',
        '_human_topic:=leap_motion/leap_device',
        '_filtered_human_topic:=leap_motion/filtered_values'], SENDER_CLIENT)
    assert out['default'][0] >= 2, out                    # a fist per second
    assert out['slow_recognizer'][0] == 0, out            # 60-frame fists never start
    assert out['after_bad_frames'][0] == 0, out
    assert out['on_frames'] == 100
    light, heavy = out['light_filter'][1], out['heavy_filter'][1]
    assert out['light_filter'][0] >= 2                    # fists are back
    assert heavy > 3 * light > 0, out                     # lag behind the raw palm, m
    assert out['after_bad_cutoff'][1] > 3 * light, out
    assert out['cutoff'] == 40.0
    assert 'refused ~recognizer_on_frames = 1000' in err, err[-3000:]
    assert 'refused ~filter_cutoff = nan' in err, err[-3000:]


def test_the_senders_recognizer_defaults_are_the_recognizers():
    import inspect

    from leap_teleop.hands.gestures import GestureRecognizer
    sig = inspect.signature(GestureRecognizer).parameters
    for name in ('on_frames', 'off_frames', 'min_confidence'):
        assert sender.PARAMS['recognizer_' + name].default == sig[name].default
