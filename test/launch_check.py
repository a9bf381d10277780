#!/usr/bin/env python3
"""Watches a running launch for its purpose; exit status 0 once reached, 1 on timeout.

  --cube ARM:CUBE     (repeatable) the cube rests in the arm's tray (--cell YAML)
  --armed ARM         the arm node reports armed or tracking (its hand input arrives)
  --moved ARM         the arm's robot moves a joint by more than MOVED_RAD (its commands
                      reach the robot)
  --drone             every --navdata drone took off, flew and is landed again
  --topic T:PKG/MSG  (repeatable) at least --count messages arrive on T
  --rosout TEXT       (repeatable) a node logs a line containing TEXT
  --advertised T      (repeatable) some node advertises topic T (the master's graph)
  --subscribed T      (repeatable) some node subscribes to topic T
  --driver            stand in for the AR.Drone driver: navdata at 50 Hz, landed until a
                      takeoff, hovering until a land
Several conditions: all must hold. Prints what it saw either way.
"""
import argparse
import sys
import threading
import time

import numpy as np
import rosgraph
import roslib.message
import rospy
from rosgraph_msgs.msg import Log
from sensor_msgs.msg import JointState
from std_msgs.msg import Empty

from leap_teleop.msg import ArmStatus, Navdata
from leap_teleop.ros.ur10_conversions import OBJECT_POSES_TOPIC, OBJECT_POSES_TYPE, object_positions
from leap_teleop.ur10.config import load_config

LANDED, HOVERING, TAKING_OFF = 2, 4, 6
MOVED_RAD = 0.05


class LaunchProgress:
    """What the running launch has done so far, against the purposes asked for."""

    def __init__(self, args):
        self.args = args
        self.lock = threading.Lock()
        self.cubes, self.arm_states = {}, {}
        self.joint_ranges = {}         # arm -> (lowest, highest) position of each joint
        self.states = {topic: [] for topic in args.navdata}
        self.counts = {spec.rsplit(':', 1)[0]: 0 for spec in args.topic}
        self.logged = {}     # TEXT: the first line that held it
        self.graph = ({}, {})          # topic -> nodes: published, subscribed
        self.master = rosgraph.Master('/launch_check')
        if args.rosout:
            rospy.Subscriber('/rosout', Log, self._log, queue_size=100)     # no rosout node here
        if args.cube:
            self.cell = load_config(args.cell)
            rospy.Subscriber(OBJECT_POSES_TOPIC, OBJECT_POSES_TYPE, self._objects, queue_size=2)
        for arm in args.armed:
            rospy.Subscriber('/%s/ur10_arm/status' % arm, ArmStatus, self._status, arm,
                             queue_size=20)
        for arm in args.moved:
            rospy.Subscriber('/%s/joint_states' % arm, JointState, self._joints, arm,
                             queue_size=20)
        if args.drone:
            for topic in args.navdata:
                rospy.Subscriber(topic, Navdata, self._nav, topic, queue_size=100)
        if args.driver:
            self.driver_state = LANDED
            self.nav_pub = rospy.Publisher(args.navdata[0], Navdata, queue_size=10)
            rospy.Subscriber('/ardrone/takeoff', Empty, self._drive, HOVERING)
            rospy.Subscriber('/ardrone/land', Empty, self._drive, LANDED)
            rospy.Timer(rospy.Duration(0.02), lambda _e: self.nav_pub.publish(
                Navdata(state=self.driver_state, altd=1000 if self.driver_state != LANDED else 0)))
        for spec in args.topic:
            topic, msg_type = spec.rsplit(':', 1)
            msg_class = roslib.message.get_message_class(msg_type)
            if msg_class is None:
                raise SystemExit('unknown message type %s' % msg_type)
            rospy.Subscriber(topic, msg_class, self._msg, topic, queue_size=500)

    def _objects(self, msg):
        with self.lock:
            self.cubes = object_positions(msg)

    def _status(self, msg, arm):
        with self.lock:
            self.arm_states.setdefault(arm, set()).add(msg.state)

    def _joints(self, msg, arm):
        q = np.asarray(msg.position, dtype=float)
        with self.lock:
            lo, hi = self.joint_ranges.get(arm, (q, q))
            if lo.shape == q.shape:
                self.joint_ranges[arm] = (np.minimum(lo, q), np.maximum(hi, q))

    def moved(self, arm):
        lo, hi = self.joint_ranges.get(arm, (np.zeros(1), np.zeros(1)))
        return float(np.max(hi - lo)) > MOVED_RAD

    def _nav(self, msg, topic):
        with self.lock:
            states = self.states[topic]
            if not states or states[-1] != msg.state:
                states.append(msg.state)

    def _drive(self, _msg, state):
        self.driver_state = state

    def _log(self, msg):
        for text in self.args.rosout:
            if text in msg.msg:
                with self.lock:
                    self.logged.setdefault(text, '%s: %s' % (msg.name, msg.msg))

    def _msg(self, _msg, topic):
        with self.lock:
            self.counts[topic] += 1

    def cube_errors(self):
        out = {}
        for spec in self.args.cube:
            arm, cube = spec.split(':')
            pos = self.cubes.get(cube)
            if pos is None:
                out[cube] = None
                continue
            tray = self.cell.arm(arm).tray
            xy = float(np.linalg.norm(np.asarray(pos[:2]) - np.asarray(tray.xyz[:2])))
            out[cube] = (xy, pos[2] - tray.floor_z)
        return out

    def _poll_graph(self):
        if not (self.args.advertised or self.args.subscribed):
            return
        try:
            pubs, subs, _ = self.master.getSystemState()
        except (OSError, rosgraph.MasterException):
            return
        self.graph = ({t: nodes for t, nodes in pubs}, {t: nodes for t, nodes in subs})

    def graph_missing(self):
        pubs, subs = self.graph
        return ([t for t in self.args.advertised if not pubs.get(t)]
                + [t for t in self.args.subscribed if not subs.get(t)])

    def done(self):
        self._poll_graph()
        with self.lock:
            if self.graph_missing():
                return False
            for err in self.cube_errors().values():
                if err is None or err[0] > 0.03 or err[1] > self.cell.cube_size:
                    return False
            for arm in self.args.armed:
                if not self.arm_states.get(arm, set()) & {'armed', 'tracking'}:
                    return False
            if not all(self.moved(arm) for arm in self.args.moved):
                return False
            for s in (self.states.values() if self.args.drone else ()):
                if TAKING_OFF not in s or s[-1] != LANDED or s.index(TAKING_OFF) == len(s) - 1:
                    return False
            if len(self.logged) < len(self.args.rosout):
                return False
            return all(n >= self.args.count for n in self.counts.values())

    def report(self):
        with self.lock:
            return ('cubes (xy error m, height over tray floor m): %s; arm states: %s; '
                    'arms moved: %s; navdata states: %s; messages: %s; logged: %s; '
                    'not in the graph: %s'
                    % (self.cube_errors() if self.args.cube else '-', self.arm_states,
                       {arm: self.moved(arm) for arm in self.args.moved}, self.states,
                       self.counts, self.logged, self.graph_missing()))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    ap.add_argument('--timeout', type=float, required=True, help='wall seconds')
    ap.add_argument('--cube', action='append', default=[])
    ap.add_argument('--cell', default='ur10_cell.yaml')
    ap.add_argument('--armed', action='append', default=[])
    ap.add_argument('--moved', action='append', default=[])
    ap.add_argument('--drone', action='store_true')
    ap.add_argument('--navdata', action='append', default=[],
                    help='navdata topic (repeatable; default ardrone/navdata)')
    ap.add_argument('--topic', action='append', default=[])
    ap.add_argument('--count', type=int, default=1)
    ap.add_argument('--rosout', action='append', default=[])
    ap.add_argument('--driver', action='store_true')
    ap.add_argument('--advertised', action='append', default=[])
    ap.add_argument('--subscribed', action='append', default=[])
    args = ap.parse_args(rospy.myargv()[1:])
    args.navdata = args.navdata or ['ardrone/navdata']
    rospy.init_node('launch_check', anonymous=True, disable_signals=True)
    watch = LaunchProgress(args)
    t0 = time.monotonic()
    while time.monotonic() - t0 < args.timeout:
        if watch.done():
            print('reached after %.1f s: %s' % (time.monotonic() - t0, watch.report()))
            return 0
        time.sleep(0.2)
    print('NOT reached in %.0f s: %s' % (args.timeout, watch.report()))
    return 1


if __name__ == '__main__':
    sys.exit(main())
