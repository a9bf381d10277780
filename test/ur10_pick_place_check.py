#!/usr/bin/env python3
"""rostest node: a scripted pick & place through ur10_sim's topics alone (no hand input).

For each task "arm:cube" in ~tasks (all arms at once, one thread each) it plans joint
targets with the analytic IK from the cell config (leap_teleop.ur10.pick_place), sends
them as JointTrajectory commands on <arm>/arm_controller/command and
<arm>/gripper/command, waits on <arm>/joint_states for each move to finish, and checks
via ~object_poses that the cube was held while lifted, ends in the arm's tray, and that
no other cube moved. TF (robot_state_publisher) must agree with the kinematics.
"""
import sys
import threading
import unittest

import numpy as np
import rospy
import rostest
import tf2_ros
from sensor_msgs.msg import JointState
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

from leap_teleop.ros.ur10_conversions import OBJECT_POSES_TOPIC, OBJECT_POSES_TYPE, object_positions
from leap_teleop.ur10 import kinematics as kin
from leap_teleop.ur10.config import load_config
from leap_teleop.ur10.pick_place import pick_place_plan

from check_helpers import limit, read_limits

LIMITS = {
    'ready_timeout_s': limit('wait this long for joint states, subscribers and cube poses', 's',
                             gt=0),
    'step_timeout_s': limit('each move is done within this', 's', gt=0),
    'position_tolerance_rad': limit('a move is done when every joint is this close ...',
                                    'rad', gt=0),
    'speed_tolerance': limit('... and this slow', 'rad/s', gt=0),
    'tf_tolerance_m': limit('TF and the kinematics agree on the TCP this closely', 'm', gt=0),
    'cube_height_tolerance_m': limit('the placed cube rests on the tray floor this closely',
                                     'm', gt=0),
    'max_speed_ratio': limit('no joint faster than this share of its speed limit', gt=0),
    'max_other_cube_move_m': limit('a cube no arm was tasked with moves less than this', 'm',
                                   gt=0),
}


class ArmDriver:
    """Sends one arm's plan and follows its joint_states."""

    def __init__(self, cfg, arm):
        self.cfg, self.arm = cfg, cfg.arm(arm)
        self.lock = threading.Lock()
        self.q = self.qd = None
        self.g = None
        self.max_speed_ratio = 0.0
        ns = self.arm.name
        self.arm_pub = rospy.Publisher(ns + '/arm_controller/command', JointTrajectory,
                                       queue_size=5)
        self.grip_pub = rospy.Publisher(ns + '/gripper/command', JointTrajectory, queue_size=5)
        rospy.Subscriber(ns + '/joint_states', JointState, self.on_joints, queue_size=20)

    def on_joints(self, msg):
        names = [self.arm.prefix + n for n in kin.JOINT_NAMES]
        idx = [msg.name.index(n) for n in names]
        with self.lock:
            self.q = np.array([msg.position[i] for i in idx])
            self.qd = np.array([msg.velocity[i] for i in idx])
            self.g = msg.position[msg.name.index(self.arm.prefix + 'finger_joint')]
            self.max_speed_ratio = max(self.max_speed_ratio,
                                       float(np.max(np.abs(self.qd) / kin.MAX_JOINT_SPEED)))

    def state(self):
        with self.lock:
            return self.q, self.qd, self.g

    def wait_ready(self, timeout):
        deadline = rospy.get_time() + timeout
        while not rospy.is_shutdown() and rospy.get_time() < deadline:
            if (self.state()[0] is not None and self.arm_pub.get_num_connections()
                    and self.grip_pub.get_num_connections()):
                return True
            rospy.sleep(0.05)
        return False

    def send(self, pub, names, positions, duration):
        msg = JointTrajectory()
        msg.joint_names = [self.arm.prefix + n for n in names]     # stamp 0: start now
        msg.points = [JointTrajectoryPoint(positions=[float(v) for v in positions],
                                           time_from_start=rospy.Duration.from_sec(duration))]
        pub.publish(msg)

    def move(self, q, timeout, position_tol, speed_tol):
        # Duration 0: the sim stretches it to the joint speed limits.
        self.send(self.arm_pub, kin.JOINT_NAMES, q, 0.0)
        deadline = rospy.get_time() + timeout
        while not rospy.is_shutdown() and rospy.get_time() < deadline:
            rospy.sleep(0.02)
            qm, qdm, _ = self.state()
            if np.max(np.abs(qm - q)) < position_tol and np.max(np.abs(qdm)) < speed_tol:
                return True
        return False

    def grip(self, knuckle, seconds=0.8, start_timeout=5.0):
        g0 = self.state()[2]
        self.send(self.grip_pub, ['finger_joint'], [knuckle], 0.3)
        # The command may reach the simulator late on a loaded machine: the fingers' time
        # counts from when they start to move (or are there already), not from sending.
        deadline = rospy.get_time() + start_timeout
        while not rospy.is_shutdown() and rospy.get_time() < deadline:
            g = self.state()[2]
            if abs(g - knuckle) < 0.01 or abs(g - g0) > 0.02:
                break
            rospy.sleep(0.01)
        rospy.sleep(seconds)


class PickPlace(unittest.TestCase):
    def test_pick_place_through_topics(self):
        lim = read_limits(LIMITS)
        cfg = load_config(rospy.get_param('~config'))
        tasks = dict(t.split(':') for t in rospy.get_param('~tasks').split())
        poses, held = {}, {}
        lock = threading.Lock()

        def on_objects(msg):
            with lock:
                poses.update(object_positions(msg))
                for name, arm in zip(msg.names, msg.grasped_by):
                    if arm:
                        held.setdefault(name, set()).add(arm)

        rospy.Subscriber(OBJECT_POSES_TOPIC, OBJECT_POSES_TYPE, on_objects, queue_size=20)
        drivers = {arm: ArmDriver(cfg, arm) for arm in tasks}
        for arm, d in drivers.items():
            self.assertTrue(d.wait_ready(lim.ready_timeout_s),
                            '%s: no joint_states / command subscribers' % arm)
        deadline = rospy.get_time() + lim.ready_timeout_s
        while not rospy.is_shutdown() and rospy.get_time() < deadline and len(poses) < len(cfg.cubes):
            rospy.sleep(0.05)
        with lock:
            start = dict(poses)
        self.assertEqual(sorted(start), sorted(c.name for c in cfg.cubes))

        # TF from robot_state_publisher agrees with the kinematics at the start pose.
        tf_buffer = tf2_ros.Buffer()
        tf2_ros.TransformListener(tf_buffer)
        for arm, d in drivers.items():
            t = tf_buffer.lookup_transform('world', cfg.arm(arm).prefix + 'tcp_link',
                                           rospy.Time(0), rospy.Duration(10.0)).transform
            fk = cfg.arm(arm).to_world(kin.fk(d.state()[0]))[:3, 3]
            tf_xyz = np.array([t.translation.x, t.translation.y, t.translation.z])
            self.assertLess(np.linalg.norm(tf_xyz - fk), lim.tf_tolerance_m, '%s TF %s vs FK %s'
                            % (arm, tf_xyz, fk))

        failures = []

        def run(arm, cube):
            d = drivers[arm]
            for step in pick_place_plan(cfg, arm, cube, q_start=d.state()[0]):
                if step.what == 'arm':
                    if not d.move(step.target, lim.step_timeout_s, lim.position_tolerance_rad,
                                  lim.speed_tolerance):
                        failures.append('%s: %s not reached (q %s)' % (arm, step.label,
                                                                        d.state()[0]))
                        return
                    rospy.sleep(0.2)
                else:
                    d.grip(float(step.target[0]))

        threads = [threading.Thread(target=run, args=item) for item in tasks.items()]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        self.assertEqual(failures, [])
        rospy.sleep(1.0)
        with lock:
            end = dict(poses)
        for arm, cube in tasks.items():
            tray = cfg.arm(arm).tray
            x, y, z = end[cube]
            rospy.loginfo('%s: %s at %.3f %.3f %.3f, tray at %s', arm, cube, x, y, z, tray.xyz)
            self.assertIn(arm, held.get(cube, set()), '%s was never reported grasped' % cube)
            self.assertLess(abs(x - tray.xyz[0]), tray.inner[0] / 2, (cube, end[cube]))
            self.assertLess(abs(y - tray.xyz[1]), tray.inner[1] / 2, (cube, end[cube]))
            self.assertAlmostEqual(z, tray.floor_z + cfg.cube_size / 2,
                                   delta=lim.cube_height_tolerance_m)
            self.assertLessEqual(drivers[arm].max_speed_ratio, lim.max_speed_ratio, arm)
        for name in start:
            others = set(held.get(name, set())) - {a for a, c in tasks.items() if c == name}
            self.assertEqual(others, set(), '%s held by an arm that was not tasked' % name)
            if name not in tasks.values():
                moved = np.linalg.norm(np.subtract(end[name], start[name]))
                self.assertLess(moved, lim.max_other_cube_move_m,
                                '%s moved by %.3f m' % (name, moved))


if __name__ == '__main__':
    rospy.init_node('ur10_pick_place_check')
    rostest.rosrun('leap_teleop', 'ur10_pick_place_check', PickPlace, sys.argv)
