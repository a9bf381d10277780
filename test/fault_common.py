"""Shared by the fault rostest nodes (test/fault_*.py): recording what the robots do,
finding and killing a node's process."""
import os
import signal
import threading
import time
import xmlrpc.client

import numpy as np
import rosgraph
import rospy
from geometry_msgs.msg import Twist
from sensor_msgs.msg import JointState
from trajectory_msgs.msg import JointTrajectory

from leap_teleop.msg import ArmStatus, GestureEvent, Navdata
from leap_teleop.ur10 import kinematics as kin


class _TimedTransport(xmlrpc.client.Transport):
    """XML-RPC over HTTP with a time limit on each call."""

    def __init__(self, timeout):
        super().__init__()
        self.timeout = timeout

    def make_connection(self, host):
        conn = super().make_connection(host)
        conn.timeout = self.timeout
        return conn


def node_pid(name, timeout=30.0, call_timeout=2.0):
    """The pid of a running node (asks the node itself through the master). Each call to
    the node is bounded by call_timeout, so one that hangs (a node gone or stalled under
    load) is retried instead of using up the whole timeout."""
    master = rosgraph.Master('/fault_check')
    deadline = time.monotonic() + timeout
    last = None
    while time.monotonic() < deadline:
        try:
            uri = master.lookupNode(name)
            proxy = xmlrpc.client.ServerProxy(uri, transport=_TimedTransport(call_timeout))
            return proxy.getPid('/fault_check')[2]
        except (rosgraph.MasterError, OSError, xmlrpc.client.Error) as e:
            last = e
            time.sleep(0.2)
    raise AssertionError('node %s did not come up (last: %r)' % (name, last))


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
            from std_msgs.msg import Empty
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
