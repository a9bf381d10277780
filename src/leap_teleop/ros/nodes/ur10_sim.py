"""ur10_sim: the simulated UR10 work cell (every arm of ~config in one PyBullet process).

Per arm, in the namespace named in the config (ur10_1, ur10_2): subscribes arm_controller/command
and gripper/command (trajectory_msgs/JointTrajectory, joint names with or without the '<arm>_'
prefix; header.stamp 0 = start now) and publishes joint_states (six arm joints +
'<arm>_finger_joint', prefixed) at ~joint_state_rate. Sets <arm>/robot_description if it is not set
yet (launch files set it first, for robot_state_publisher). Private: ~object_poses
(leap_teleop/ObjectPoses), services ~reset and ~snapshot (std_srvs/Trigger; snapshot answers with
the PNG's path). A malformed command is rejected with a rate-limited warning and the arm keeps its
current trajectory (as ros_control's JointTrajectoryController). /diagnostics: per arm, how long
commands wait for the physics step that applies them; commands rejected or dropped (WARN for
10 wall s after one). With /use_sim_time true it publishes /clock and can run faster than real
time (~realtime_factor, 0 = as fast as possible). Extra mode: `ur10_sim.py --urdf ARM
[--config FILE]` prints ARM's description and exits.
"""
import sys
import threading

import rospy
from std_srvs.srv import Trigger, TriggerResponse
from trajectory_msgs.msg import JointTrajectory

from leap_teleop.ros.cell_state_topics import CellStateTopics, command_type_watch
from leap_teleop.ros.diagnostics import diagnostics_updater, update_every
from leap_teleop.ros.node import RateLimitedLog, start_node
from leap_teleop.ros.signals import closed_at_shutdown
from leap_teleop.ros.ur10_conversions import CommandError, trajectory_points
from leap_teleop.ur10.cell_runner import KINDS, RUNNER_PARAMS, CellRunner
from leap_teleop.ur10.model import arm_urdf, print_urdf

PARAMS = RUNNER_PARAMS      # declared beside the cell; --help and docs/nodes.md read it


class UR10SimNode:
    def __init__(self, p):
        self.log = RateLimitedLog(2.0)
        self.rejected = 0                  # counted on the subscribers' threads
        self._rejected_lock = threading.Lock()
        self.use_sim_time = bool(rospy.get_param('/use_sim_time', False))
        self.runner = CellRunner(p, self.use_sim_time, rospy.get_time, self._reject, self._warn)
        self.cell = self.runner.cell
        self.topics = CellStateTopics(self.cell.config, p['joint_states_queue_size'],
                                      self.use_sim_time)
        self.type_watch = command_type_watch(self.cell.config, self.log)
        for arm, ns in ((a, a.name) for a in self.cell.config.arms):
            if not rospy.has_param(ns + '/robot_description'):
                rospy.set_param(ns + '/robot_description', arm_urdf(arm))
            for kind, (topic, _) in KINDS.items():
                rospy.Subscriber(ns + '/' + topic, JointTrajectory, self.on_command,
                                 callback_args=(ns, kind), queue_size=20, tcp_nodelay=True)
        rospy.Service('~reset', Trigger, self.on_reset)
        rospy.Service('~snapshot', Trigger, self.on_snapshot)
        self.diagnostics = diagnostics_updater('ur10_sim', 'cell', lambda: self.runner.report(
            self.rejected), self.runner.command_waits)
        self.diagnostics_timer = update_every(self.diagnostics)

    # -- inputs: validate here, apply in the loop ---------------------------------------
    def on_command(self, msg, args):
        arm, kind = args
        try:
            points, stamp = trajectory_points(msg, KINDS[kind][1], self.cell.config.arm(arm).prefix)
        except CommandError as e:
            self._reject(arm, kind, e)
            return
        if self.runner.queue(arm, kind, points, stamp):
            self.log.warn('pending', 'ur10_sim: %d command(s) dropped, the physics loop is '
                          'behind', self.runner.dropped_commands)

    def _reject(self, arm, kind, why):
        with self._rejected_lock:
            self.rejected += 1
        self.log.warn((arm, kind), 'ur10_sim: %s/%s rejected: %s; the arm keeps its '
                      'current trajectory', arm, KINDS[kind][0], why)

    def _warn(self, arm, kind, what):
        self.log.warn(('far', arm, kind), 'ur10_sim: %s/%s: a command %s', arm, KINDS[kind][0], what)

    def on_reset(self, _req):
        self.runner.reset()
        rospy.loginfo('ur10_sim: reset (arms home, grippers open, cubes at their start)')
        return TriggerResponse(success=True, message='reset')

    def on_snapshot(self, _req):
        try:
            return TriggerResponse(success=True, message=self.runner.snapshot())
        except (OSError, ValueError, TypeError, RuntimeError, TimeoutError) as e:
            return TriggerResponse(success=False, message='snapshot failed: %s' % e)


def main(argv=None):
    argv = sys.argv[1:] if argv is None else list(argv)
    if '--urdf' in argv:        # a bad config: one line on stderr, status 1
        print_urdf(argv)
        return
    p, node = start_node('ur10_sim.py', 'ur10_sim', __doc__, PARAMS, UR10SimNode,
                         [sys.argv[0]] + argv, errors=(ValueError, TypeError, KeyError, OSError))
    rospy.loginfo('ur10_sim: ready, arms %s (%s, %s)', ', '.join(node.cell.arm_names),
                  'GUI' if node.cell.gui else 'headless',
                  'sim time x%g' % float(p['realtime_factor']) if node.use_sim_time
                  else 'wall time')
    for warning in node.runner.start_warnings:
        rospy.logwarn('ur10_sim: %s', warning)
    try:
        with closed_at_shutdown():
            node.runner.run(node.topics.publish, rospy.is_shutdown, lambda lag: node.log.warn(
                'behind', 'ur10_sim: the physics loop fell %.2f s behind the wall clock', lag))
    except rospy.ROSInterruptException:
        pass
    finally:
        node.runner.close()
