"""Shared by the rostest checker nodes (test/*_check.py): their pass / fail limits, read
from the YAML their .test file gives them; recording what the robots do; hand messages for
the arm node and the pilot; finding and killing a node's process."""
import os
import signal
import threading
import time
import types
import xmlrpc.client

import numpy as np
import rosgraph
import rospy
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import Twist
from sensor_msgs.msg import JointState
from std_msgs.msg import Empty
from trajectory_msgs.msg import JointTrajectory

from leap_teleop.drone.sim import STATE_NAMES
from leap_teleop.msg import ArmStatus, GestureEvent, Hand, Navdata, leapcobotright
from leap_teleop.params import Param, ParamError
from leap_teleop.ur10 import kinematics as kin

NAVDATA_STATES = {name: code for code, name in STATE_NAMES.items()}


class LimitsError(ValueError):
    """A .test file's limits for its checker: missing, unknown or out of range."""


def read_limits(table, param='~limits'):
    """The checker's pass / fail limits and expectations, from the mapping its .test file
    gives the test node (<rosparam param="limits">): every key of `table` (name -> Param)
    that has no default must be there, no other key may be (a misspelt limit would be
    ignored), and each value must be what its Param allows."""
    where = rospy.resolve_name(param)
    return check_limits(table, rospy.get_param(where, None), where)


def check_limits(table, raw, where):
    """The values of `raw` checked against `table`, as attributes; LimitsError naming the
    key otherwise."""
    if not isinstance(raw, dict):
        raise LimitsError('%s: %s; the .test file gives its checker a <rosparam param="limits"> '
                          'mapping of %s' % (where, 'missing' if raw is None else
                                             'not a mapping', ', '.join(sorted(table))))
    unknown = sorted(set(raw) - set(table))
    if unknown:
        raise LimitsError('%s: unknown key %s; known: %s'
                          % (where, ', '.join(unknown), ', '.join(sorted(table))))
    values = {}
    for key, p in table.items():
        if key not in raw and p.default is None:
            raise LimitsError('%s/%s: missing (%s: %s)' % (where, key, p.doc, p.allowed()))
        try:
            values[key] = p.check(key, raw.get(key, p.default))
        except ParamError as e:
            raise LimitsError('%s/%s: %s' % (where, key, e)) from None
    return types.SimpleNamespace(**values)


def limit(doc, unit='', kind='float', default=None, **bounds):
    """A required limit (unless given a default) for read_limits' table."""
    return Param(default, doc, unit, kind=kind, **bounds)


def state_limit(doc):
    """A navdata state by name (leap_teleop.drone.sim.STATE_NAMES); navdata_code turns it
    into its code."""
    return Param(None, doc, kind='str', choices=sorted(NAVDATA_STATES))


def states_limit(doc):
    """A list of navdata state names; navdata_codes turns it into the codes."""
    return Param(None, doc, kind='list', item='str', choices=sorted(NAVDATA_STATES))


def navdata_code(name):
    return NAVDATA_STATES[name]


def navdata_codes(names):
    return [NAVDATA_STATES[n] for n in names]


class _TimedTransport(xmlrpc.client.Transport):
    """XML-RPC over HTTP with a time limit on each call."""

    def __init__(self, timeout):
        super().__init__()
        self.timeout = timeout

    def make_connection(self, host):
        conn = super().make_connection(host)
        conn.timeout = self.timeout
        return conn


def node_proxy(name, call_timeout=2.0):
    """An XML-RPC proxy to a running node, looked up through the master; each call to it is
    bounded by call_timeout. Raises rosgraph.MasterError, OSError or xmlrpc.client.Error."""
    uri = rosgraph.Master('/check').lookupNode(name)
    return xmlrpc.client.ServerProxy(uri, transport=_TimedTransport(call_timeout))


def node_pid(name, timeout=30.0, call_timeout=2.0):
    """The pid of a running node (asks the node itself). A call that hangs (a node gone or
    stalled under load) is retried instead of using up the whole timeout."""
    deadline = time.monotonic() + timeout
    last = None
    while time.monotonic() < deadline:
        try:
            return node_proxy(name, call_timeout).getPid('/check')[2]
        except (rosgraph.MasterError, OSError, xmlrpc.client.Error) as e:
            last = e
            time.sleep(0.2)
    raise AssertionError('node %s did not come up (last: %r)' % (name, last))


def publishes_to_a_subscriber(node, topic, call_timeout=2.0):
    """True once `node` has a live outbound connection on `topic` (the node's own bus
    info): a message it publishes then reaches a subscriber. A subscriber the master lists
    is not yet connected; a check that waits for this does not lean on how long the pilot
    holds a one-shot command for its driver."""
    try:
        connections = node_proxy(node, call_timeout).getBusInfo('/check')[2]
    except (rosgraph.MasterError, OSError, xmlrpc.client.Error):
        return False
    return any(c[4] == topic and c[2] == 'o' and c[5] for c in connections)


def kill(pid):
    os.kill(pid, signal.SIGKILL)
    t = time.monotonic()
    # A killed child stays a zombie until roslaunch reaps it; gone from the graph is enough.
    return t


def alive(pid):
    try:
        with open('/proc/%d/stat' % pid) as f:
            return f.read().rsplit(')', 1)[1].split()[0] not in ('Z', 'X')
    except OSError:
        return False


class Watch:
    """Receipt-timed (time.monotonic) records of an arm and / or the drone."""

    def __init__(self, arm=None, drone=False):
        self.lock = threading.Lock()
        self.joints, self.status, self.arm_cmds = [], [], []
        self.twists, self.nav, self.gestures, self.takeoffs = [], [], [], []
        if arm:
            rospy.Subscriber('/%s/joint_states' % arm, JointState, self._joints, queue_size=50)
            rospy.Subscriber('/%s/ur10_arm/status' % arm, ArmStatus, self._status, queue_size=50)
            rospy.Subscriber('/%s/arm_controller/command' % arm, JointTrajectory, self._cmd,
                             queue_size=100)
        if drone:
            rospy.Subscriber('cmd_vel', Twist, self._add, self.twists, queue_size=200)
            rospy.Subscriber('ardrone/navdata', Navdata, self._nav, queue_size=50)
            rospy.Subscriber('leapmotion/gestures', GestureEvent, self._add, self.gestures,
                             queue_size=100)
            rospy.Subscriber('ardrone/takeoff', Empty, self._add, self.takeoffs, queue_size=10)

    def _add(self, msg, store):
        with self.lock:
            store.append((time.monotonic(), msg))

    def _joints(self, msg):
        idx = [next(i for i, n in enumerate(msg.name) if n.endswith(j)) for j in kin.JOINT_NAMES]
        with self.lock:
            self.joints.append((time.monotonic(), np.array([msg.position[i] for i in idx]),
                                np.array([msg.velocity[i] for i in idx])))

    def _status(self, msg):
        with self.lock:
            self.status.append((time.monotonic(), msg))

    def _cmd(self, msg):
        with self.lock:
            self.arm_cmds.append((time.monotonic(), np.array(msg.points[0].positions)))

    def _nav(self, msg):
        with self.lock:
            if not self.nav or self.nav[-1][1] != msg.state:
                self.nav.append((time.monotonic(), msg.state))

    # -- queries ----------------------------------------------------------------------
    def arm_speed(self, t0, t1):
        with self.lock:
            qd = [float(np.max(np.abs(v))) for t, _, v in self.joints if t0 <= t <= t1]
        return max(qd) if qd else None

    def q_at(self, t):
        with self.lock:
            before = [q for tt, q, _ in self.joints if tt <= t]
        return before[-1] if before else None

    def first_status(self, state, after, reason_part=''):
        with self.lock:
            for t, s in self.status:
                if t >= after and s.state == state and reason_part in s.reason:
                    return t, s
        return None, None

    def drone_state(self):
        with self.lock:
            return self.nav[-1][1] if self.nav else None

    def first_nav(self, states, after):
        with self.lock:
            return next((t for t, s in self.nav if t >= after and s in states), None)


def wait_for(cond, timeout, step=0.02):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline and not rospy.is_shutdown():
        if cond():
            return True
        time.sleep(step)
    return bool(cond())


class NavdataStates:
    """The navdata states of one drone, in order, each once per change (list-like)."""

    def __init__(self, topic='ardrone/navdata'):
        self.lock = threading.Lock()
        self.states = []
        rospy.Subscriber(topic, Navdata, self._nav, queue_size=100)

    def _nav(self, msg):
        with self.lock:
            if not self.states or self.states[-1] != msg.state:
                self.states.append(msg.state)

    def get(self):
        with self.lock:
            return list(self.states)


class DiagnosticCounts:
    """One integer value (`key`, e.g. 'rejected inputs') each node reports on /diagnostics,
    by status name: the latest report of each."""

    def __init__(self, key):
        self.key = key
        self.values = {}
        rospy.Subscriber('/diagnostics', DiagnosticArray, self._diag, queue_size=20)

    def _diag(self, msg):
        for st in msg.status:
            for kv in st.values:
                if kv.key == self.key:
                    self.values[st.name] = int(kv.value)

    def get(self, part):
        """The count of the first node whose status name contains `part`, or None."""
        return next((v for k, v in self.values.items() if part in k), None)


def pilot_hand(stamp, palm=(0.0, 0.2, 0.0), side=Hand.SIDE_RIGHT, present=True):
    """A Hand for the drone pilot (palm in m, Leap axes), level and pointing forward."""
    h = Hand(side=side, present=present)
    h.header.stamp = rospy.Time.from_sec(stamp)
    if present:
        h.palm_position.x, h.palm_position.y, h.palm_position.z = palm
        h.palm_normal.y, h.direction.z = -1.0, -1.0
    return h


class RightHands:
    """The right hand on the arm's leapcobot topic and the pilot's Hand topic, one pose;
    the pilot's gesture events."""

    def __init__(self):
        self.arm_pub = rospy.Publisher('/leapmotion/data_right', leapcobotright, queue_size=500)
        self.hand_pub = rospy.Publisher('/leapmotion/hand_right', Hand, queue_size=500)
        self.gesture_pub = rospy.Publisher('leapmotion/gestures', GestureEvent, queue_size=10)

    def listened(self):
        """The arm node and the pilot subscribe to the hands and the pilot to the gestures."""
        return (self.arm_pub.get_num_connections() > 0 and self.hand_pub.get_num_connections() > 0
                and self.gesture_pub.get_num_connections() > 0)

    def unfold(self):
        ev = GestureEvent(side=GestureEvent.SIDE_RIGHT, gesture='unfold', active=True)
        ev.header.stamp = rospy.Time.now()
        self.gesture_pub.publish(ev)

    def publish(self, stamp, palm, thumb_up=False, rock=False):
        """palm in mm."""
        m = leapcobotright()
        m.header.stamp = rospy.Time.from_sec(stamp)
        m.is_right_hand = True
        m.right_hand_palmpos.x, m.right_hand_palmpos.y, m.right_hand_palmpos.z = palm
        m.right_hand_thumb_up = thumb_up
        m.right_hand_set_origin_frame_detected = rock
        self.arm_pub.publish(m)
        self.hand_pub.publish(pilot_hand(stamp, tuple(v / 1000.0 for v in palm)))


def hover_navdata(stop):
    """Until `stop` is set, a thread publishes the navdata of a drone hovering at 1 m, 50 Hz
    (the pilot flies only with navdata)."""
    pub = rospy.Publisher('ardrone/navdata', Navdata, queue_size=10)

    def loop():
        while not stop.is_set() and not rospy.is_shutdown():
            pub.publish(Navdata(state=4, altd=1000))
            time.sleep(0.02)
    threading.Thread(target=loop, daemon=True).start()


def start_streaming(arm, hands, stream, stop, timeout):
    """Before a check drives both robots: hovering navdata until `stop` is set, the arm's
    joint states, the arm node and the pilot listening within `timeout` (AssertionError
    otherwise); then the caller's `stream` of hands runs on a thread."""
    hover_navdata(stop)
    rospy.wait_for_message('/%s/joint_states' % arm, JointState, timeout=60)
    if not wait_for(hands.listened, timeout):
        raise AssertionError('the arm node and the pilot did not listen within %.1f s' % timeout)
    threading.Thread(target=stream, daemon=True).start()


def arm_track_and_unfold(watch, hands, pose, neutral, timeout):
    """Through pose['now'] (the hand the caller's stream sends): a thumbs-up arms the arm and
    a rock starts it tracking, each within `timeout` (AssertionError otherwise); then the
    neutral hand and an unfold engage the pilot. Returns the (monotonic) time it began."""
    t0 = time.monotonic()
    for gesture, state in (('thumb_up', 'armed'), ('rock', 'tracking')):
        pose['now'] = dict(neutral, **{gesture: True})
        if not wait_for(lambda state=state: watch.first_status(state, t0)[0] is not None,
                        timeout):
            raise AssertionError('not %s within %.1f s of the %s' % (state, timeout, gesture))
    pose['now'] = dict(neutral)
    hands.unfold()
    return t0
