"""ur10_sim: the simulated UR10 work cell (every arm of ~config in one PyBullet process).

Per arm, in the namespace named in the config (ur10_1, ur10_2): subscribes
arm_controller/command and gripper/command (trajectory_msgs/JointTrajectory, joint names
with or without the '<arm>_' prefix; header.stamp 0 = start now) and publishes
joint_states (six arm joints + '<arm>_finger_joint', prefixed) at ~joint_state_rate.
Sets <arm>/robot_description if it is not set yet (launch files set it first, for
robot_state_publisher). Private: ~object_poses (leap_teleop/ObjectPoses), services ~reset
and ~snapshot (std_srvs/Trigger; snapshot answers with the PNG's path). A malformed
command is rejected with a rate-limited warning and the arm keeps its current trajectory
(as ros_control's JointTrajectoryController). With /use_sim_time true it publishes
/clock and can run faster than real time (~realtime_factor, 0 = as fast as possible).
Extra mode: `ur10_sim.py --urdf ARM [--config FILE]` prints ARM's description and exits.
"""
import collections
import os
import sys
import threading
import time

import rospy
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import JointState
from std_srvs.srv import Trigger, TriggerResponse
from trajectory_msgs.msg import JointTrajectory

from leap_teleop.msg import ObjectPoses
from leap_teleop.ros.conversions import (
    ARM_JOINTS,
    GRIPPER_JOINTS,
    CommandError,
    joint_state_msg,
    object_poses_msg,
    trajectory_points,
)
from leap_teleop.ros.node import Param, RateLimitedLog, start_node
from leap_teleop.ros.signals import closed_at_shutdown
from leap_teleop.ur10.model import build_urdf
from leap_teleop.ur10.snapshot import SnapshotRenderer
from leap_teleop.ur10.trajectory import TrajectoryError

PARAMS = {
    'config': Param('ur10_cell.yaml', 'cell YAML: a path or a file name in config/',
                    empty_ok=False),
    'gui': Param(False, 'open the PyBullet GUI window (needs a display)'),
    'realtime_factor': Param(1.0, 'sim speed vs wall time; 0 = as fast as possible '
                                  '(only with /use_sim_time)', ge=0.0, le=100.0),
    # joint_states feed the arm nodes' joint watchdog: at least 10 Hz.
    'joint_state_rate': Param(125.0, 'joint_states rate per arm (UR CB3 controller)',
                              unit='Hz', ge=10.0, le=1000.0),
    'object_pose_rate': Param(30.0, '~object_poses rate', unit='Hz', gt=0.0, le=1000.0),
    'clock_rate': Param(240.0, '/clock rate with /use_sim_time (at most the physics rate)',
                        unit='Hz', ge=10.0, le=10000.0),
    'snapshot_dir': Param('', 'where ~snapshot writes PNGs (default ROS_HOME or /tmp)'),
    'snapshot_size': Param([640, 480], 'snapshot width, height', unit='px', length=2,
                           ge=16, le=4096),
}

MAX_PENDING = 100               # commands queued for the physics loop (bounded)
SNAPSHOT_TIMEOUT = 30.0         # s for one picture (the first one starts the renderer)
KINDS = {'arm': ('arm_controller/command', ARM_JOINTS),
         'gripper': ('gripper/command', GRIPPER_JOINTS)}


class UR10SimNode:
    def __init__(self, p):
        from leap_teleop.ur10.cell import UR10Cell  # pybullet: after --help / --urdf
        self.p = p
        self.cell = UR10Cell(p['config'], gui=bool(p['gui']))
        self.lock = threading.Lock()               # guards self.cell (physics)
        self.render_lock = threading.Lock()        # one snapshot at a time
        self.renderer = SnapshotRenderer(self.cell.config)
        self.pending = collections.deque()         # validated commands for the loop
        self.dropped_commands = 0
        self.log = RateLimitedLog(2.0)
        self.use_sim_time = bool(rospy.get_param('/use_sim_time', False))
        self.clock_pub = (rospy.Publisher('/clock', Clock, queue_size=10)
                          if self.use_sim_time else None)
        self.js_pubs = {}
        for arm in self.cell.config.arms:
            ns = arm.name
            if not rospy.has_param(ns + '/robot_description'):
                rospy.set_param(ns + '/robot_description',
                                build_urdf(arm.prefix, arm.base_xyz, arm.base_rpy))
            self.js_pubs[ns] = rospy.Publisher(ns + '/joint_states', JointState, queue_size=20)
            for kind, (topic, _) in KINDS.items():
                rospy.Subscriber(ns + '/' + topic, JointTrajectory, self.on_command,
                                 callback_args=(ns, kind), queue_size=20, tcp_nodelay=True)
        self.obj_pub = rospy.Publisher('~object_poses', ObjectPoses, queue_size=5)
        rospy.Service('~reset', Trigger, self.on_reset)
        rospy.Service('~snapshot', Trigger, self.on_snapshot)

    # -- inputs: validate here, apply in the loop ---------------------------------------
    def on_command(self, msg, args):
        arm, kind = args
        topic, joints = KINDS[kind]
        try:
            points, stamp = trajectory_points(msg, joints, self.cell.config.arm(arm).prefix)
        except CommandError as e:
            self._reject(arm, kind, e)
            return
        if len(self.pending) >= MAX_PENDING:       # the loop stalled: newer commands win
            self.pending.popleft()
            self.dropped_commands += 1
            self.log.warn('pending', 'ur10_sim: %d command(s) dropped, the physics loop is '
                          'behind', self.dropped_commands)
        self.pending.append((arm, kind, points, stamp))

    def _reject(self, arm, kind, why):
        self.log.warn((arm, kind), 'ur10_sim: %s/%s rejected: %s; the arm keeps its '
                      'current trajectory', arm, KINDS[kind][0], why)

    def _apply_pending(self):
        """Hand queued commands to the cell (lock held)."""
        cell = self.cell
        while self.pending:
            arm, kind, points, stamp = self.pending.popleft()
            # A stamped start in ROS time -> cell time; 0 = now.
            start = None if stamp <= 0 else cell.time + (stamp - rospy.get_time())
            command = cell.command_arm if kind == 'arm' else cell.command_gripper
            try:
                command(arm, points, start)
            except TrajectoryError as e:
                self._reject(arm, kind, e)

    def on_reset(self, _req):
        with self.lock:
            self.pending.clear()
            self.cell.reset()
        rospy.loginfo('ur10_sim: reset (arms home, grippers open, cubes at their start)')
        return TriggerResponse(success=True, message='reset')

    def on_snapshot(self, _req):
        """Copy the poses under the physics lock; a renderer process draws them, so a slow
        render never delays joint_states."""
        folder = self.p['snapshot_dir'] or os.environ.get('ROS_HOME') or '/tmp'
        try:
            w, h = self.p['snapshot_size']
            os.makedirs(folder, exist_ok=True)
            with self.lock:
                t, state = self.cell.time, self.cell.pose_state()
            path = os.path.join(folder, 'ur10_sim_%08.3f.png' % t)
            with self.render_lock:
                self.renderer.render(state, path, w, h, SNAPSHOT_TIMEOUT)
        except (OSError, ValueError, TypeError, RuntimeError, TimeoutError) as e:
            return TriggerResponse(success=False, message='snapshot failed: %s' % e)
        return TriggerResponse(success=True, message=path)

    # -- outputs --------------------------------------------------------------------------
    def run(self):
        cell = self.cell
        rtf = float(self.p['realtime_factor'])
        if rtf <= 0 and not self.use_sim_time:
            rospy.logwarn('ur10_sim: realtime_factor %g without /use_sim_time: running in real '
                          'time instead', rtf)
            rtf = 1.0
        js_period = 1.0 / float(self.p['joint_state_rate'])
        obj_period = 1.0 / float(self.p['object_pose_rate'])
        clock_period = 1.0 / float(self.p['clock_rate'])
        next_js = next_obj = next_clock = cell.time
        t0_wall, t0_sim = time.monotonic(), cell.time
        while not rospy.is_shutdown():
            states, objects = None, None
            with self.lock:
                self._apply_pending()
                cell.step()
                t = cell.time
                if t >= next_js - 1e-9:
                    next_js = max(next_js + js_period, t)
                    states = {a: cell.joint_state(a) for a in cell.arm_names}
                if t >= next_obj - 1e-9:
                    next_obj = max(next_obj + obj_period, t)
                    objects = (cell.object_poses(),
                               {c: a for a in cell.arm_names
                                for c in [cell.grasped(a)] if c is not None})
            stamp = rospy.Time.from_sec(t) if self.use_sim_time else rospy.Time.now()
            if self.clock_pub is not None and t >= next_clock - 1e-9:
                next_clock = max(next_clock + clock_period, t)
                self.clock_pub.publish(Clock(clock=stamp))
            if states:
                for arm, (q, qd, g, gd) in states.items():
                    self.js_pubs[arm].publish(joint_state_msg(cell.config.arm(arm).prefix,
                                                              q, qd, g, gd, stamp))
            if objects:
                self.obj_pub.publish(object_poses_msg(*objects, stamp=stamp))
            if rtf > 0:
                delay = t0_wall + (t - t0_sim) / rtf - time.monotonic()
                if delay > 0:
                    time.sleep(delay)
                elif delay < -0.5:        # fell behind (loaded machine): do not sprint
                    t0_wall, t0_sim = time.monotonic(), t
            else:
                time.sleep(0)             # let the callbacks in

    def close(self):
        with self.lock:
            self.cell.close()
        self.renderer.close()


def print_urdf(argv):
    """--urdf ARM [--config FILE]: the arm's description on stdout (for <param command=>)."""
    import argparse

    from leap_teleop.ur10.config import load_config
    ap = argparse.ArgumentParser(prog='ur10_sim.py --urdf')
    ap.add_argument('--urdf', required=True, metavar='ARM')
    ap.add_argument('--config', default=PARAMS['config'].default)
    args, _ = ap.parse_known_args(argv)
    arm = load_config(args.config).arm(args.urdf)
    sys.stdout.write(build_urdf(arm.prefix, arm.base_xyz, arm.base_rpy))


def main(argv=None):
    argv = sys.argv[1:] if argv is None else list(argv)
    if '--urdf' in argv:
        print_urdf(argv)
        return
    p, node = start_node('ur10_sim.py', 'ur10_sim', __doc__, PARAMS, UR10SimNode,
                         [sys.argv[0]] + argv, errors=(ValueError, TypeError, KeyError, OSError))
    rospy.loginfo('ur10_sim: ready, arms %s (%s, %s)', ', '.join(node.cell.arm_names),
                  'GUI' if node.cell.gui else 'headless',
                  'sim time x%g' % float(p['realtime_factor']) if node.use_sim_time
                  else 'wall time')
    try:
        with closed_at_shutdown():
            node.run()
    except rospy.ROSInterruptException:
        pass
    finally:
        node.close()
