#!/usr/bin/env python3
"""rostest node: ur10_sim rejects malformed trajectories with a warning and the arm holds.

Each bad command goes out on its own (further apart than the sim's 2 s warning rate
limit); the check wants a /rosout warning from the sim naming the reason, an arm that
has not moved, and a sim that still follows a valid command afterwards, also when a bad
command arrives in the middle of it.
"""
import math
import sys
import threading
import unittest

import numpy as np
import rospy
import rostest
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from rosgraph_msgs.msg import Log
from sensor_msgs.msg import JointState
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

from leap_teleop.ur10.kinematics import JOINT_NAMES

from check_helpers import limit, read_limits

ARM = 'ur10_1'
LIMITS = {
    'ready_timeout_s': limit('wait this long for joint states and a first warning', 's', gt=0),
    'warning_timeout_s': limit('each bad command\'s warning comes within this', 's', gt=0),
    'rate_limit_wait_s': limit('wait this long after a warning (the sim warns at most every '
                               '2 s)', 's', gt=0),
    'hold_tolerance': limit('a rejected command moves no joint (rad) or the gripper more than '
                            'this', gt=0),
    'reach_tolerance_rad': limit('the valid command is reached this closely ...', 'rad', gt=0),
    'reach_timeout_s': limit('... within this', 's', gt=0),
    'diagnostics_timeout_s': limit('the sim\'s /diagnostics warns and counts the rejected '
                                   'commands within this', 's', gt=0),
}
PREFIX = ARM + '_'
NAMES = [PREFIX + n for n in JOINT_NAMES]


def traj(names, points):
    msg = JointTrajectory()
    msg.joint_names = list(names)
    msg.points = [JointTrajectoryPoint(positions=list(pos), velocities=list(vel),
                                       time_from_start=rospy.Duration.from_sec(t))
                  for t, pos, vel in points]
    return msg


class BadCommands(unittest.TestCase):
    def setUp(self):
        self.lim = read_limits(LIMITS)
        self.lock = threading.Lock()
        self.q = None
        self.g = None
        self.warnings = []
        self.cell_status = None
        rospy.Subscriber(ARM + '/joint_states', JointState, self.on_joints, queue_size=20)
        rospy.Subscriber('/diagnostics', DiagnosticArray, self.on_diagnostics, queue_size=20)
        rospy.Subscriber('/rosout', Log, self.on_log, queue_size=100)
        self.arm_pub = rospy.Publisher(ARM + '/arm_controller/command', JointTrajectory,
                                       queue_size=5)
        self.grip_pub = rospy.Publisher(ARM + '/gripper/command', JointTrajectory, queue_size=5)
        deadline = rospy.get_time() + self.lim.ready_timeout_s
        while rospy.get_time() < deadline and not (
                self.q is not None and self.arm_pub.get_num_connections()
                and self.grip_pub.get_num_connections()):
            rospy.sleep(0.05)
        self.assertIsNotNone(self.q, 'no joint_states')
        # Until the log subscription is up, warnings are lost: warm up with a bad command.
        deadline = rospy.get_time() + self.lim.ready_timeout_s
        while rospy.get_time() < deadline and not self.warnings:
            self.arm_pub.publish(traj(['warm_up'], [(1.0, [0.0], [])]))
            rospy.sleep(0.5)
        self.assertTrue(self.warnings, 'no warnings from ur10_sim on /rosout')
        rospy.sleep(self.lim.rate_limit_wait_s)

    def on_joints(self, msg):
        with self.lock:
            self.q = np.array(msg.position[:6])
            self.g = msg.position[6]

    def on_log(self, msg):
        if msg.level == Log.WARN and msg.name.endswith('ur10_sim'):
            with self.lock:
                self.warnings.append(msg.msg)

    def on_diagnostics(self, msg):
        for status in msg.status:
            if status.name == 'ur10_sim: cell':
                with self.lock:
                    self.cell_status = (status.level, {kv.key: kv.value for kv in status.values})

    def joints(self):
        with self.lock:
            return self.q.copy(), self.g

    def expect_rejected(self, pub, msg, reason):
        with self.lock:
            n = len(self.warnings)
        q0, g0 = self.joints()
        pub.publish(msg)

        def warned():
            with self.lock:
                return any('rejected' in w and reason in w for w in self.warnings[n:])
        deadline = rospy.get_time() + self.lim.warning_timeout_s
        while not warned() and rospy.get_time() < deadline and not rospy.is_shutdown():
            rospy.sleep(0.05)
        # Past the warning rate limit counted from the warning, not from the publish (on a
        # loaded machine the command can reach the simulator late, and simulated time runs
        # 8x), and time to move if it would.
        rospy.sleep(self.lim.rate_limit_wait_s)
        q1, g1 = self.joints()
        with self.lock:
            new = self.warnings[n:]
        self.assertTrue(any('rejected' in w and reason in w for w in new),
                        'no warning with %r after the command; got %s' % (reason, new))
        self.assertLess(np.max(np.abs(q1 - q0)), self.lim.hold_tolerance,
                        'arm moved on a rejected command')
        self.assertLess(abs(g1 - g0), self.lim.hold_tolerance,
                        'gripper moved on a rejected command')

    def test_bad_commands_rejected_arm_holds(self):
        home, _ = self.joints()
        target = home + np.array([0.3, -0.2, 0.2, 0.1, 0.1, 0.3])
        arm, grip = self.arm_pub, self.grip_pub
        wrong = ['shoulder_pan', 'shoulder_lift_joint', 'elbow_joint', 'wrist_1_joint',
                 'wrist_2_joint', 'wrist_3_joint']
        cases = [
            (arm, traj(wrong, [(1.0, target, [])]), 'unknown joint'),
            (arm, traj(['ur10_2_' + n for n in JOINT_NAMES], [(1.0, target, [])]),
             'unknown joint'),
            (arm, traj(NAMES[:5], [(1.0, target[:5], [])]), 'missing joints'),
            (arm, traj(NAMES, []), 'empty trajectory'),
            (arm, traj([], [(1.0, target, [])]), 'no joint_names'),
            (arm, traj(NAMES, [(1.0, list(target[:5]) + [math.nan], [])]), 'NaN or inf'),
            (arm, traj(NAMES, [(1.0, target, [math.inf] * 6)]), 'NaN or inf'),
            (arm, traj(NAMES, [(1.0, target[:5], [])]), 'positions for'),
            (arm, traj(NAMES, [(1.0, target, []), (1.0, home, [])]), 'not after'),
            (arm, traj(NAMES, [(1.0, home + [0, 0, 4.0, 0, 0, 0], [])]), 'joint limits'),
            (grip, traj([PREFIX + 'finger_joint'], [(0.5, [math.nan], [])]), 'NaN or inf'),
            (grip, traj(NAMES, [(0.5, target, [])]), 'unknown joint'),
            (grip, traj([PREFIX + 'finger_joint'], [(0.5, [1.5], [])]), 'joint limits'),
        ]
        for pub, msg, reason in cases:
            self.expect_rejected(pub, msg, reason)

        # The sim still follows a valid command (unprefixed names, any order) ...
        order = [5, 3, 1, 0, 2, 4]
        arm.publish(traj([JOINT_NAMES[i] for i in order], [(1.0, target[order], [])]))
        # ... and a bad command in the middle of it does not stop or divert it.
        rospy.sleep(0.3)
        arm.publish(traj(NAMES, [(1.0, [math.nan] * 6, [])]))
        tol = self.lim.reach_tolerance_rad
        deadline = rospy.get_time() + self.lim.reach_timeout_s
        while rospy.get_time() < deadline and np.max(np.abs(self.joints()[0] - target)) > tol:
            rospy.sleep(0.05)
        self.assertLess(np.max(np.abs(self.joints()[0] - target)), tol)

        # The sim's /diagnostics says so: WARN, and every refused command counted.
        def cell_warns():
            with self.lock:
                status = self.cell_status
            return status is not None and status[0] == DiagnosticStatus.WARN and int(
                status[1].get('commands rejected', 0)) >= len(cases) + 1
        deadline = rospy.get_time() + self.lim.diagnostics_timeout_s
        while rospy.get_time() < deadline and not cell_warns():
            rospy.sleep(0.05)
        self.assertTrue(cell_warns(), 'ur10_sim: cell status %r' % (self.cell_status,))


if __name__ == '__main__':
    rospy.init_node('ur10_bad_commands_check')
    rostest.rosrun('leap_teleop', 'ur10_bad_commands_check', BadCommands, sys.argv)
