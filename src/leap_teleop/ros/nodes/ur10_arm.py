"""ur10_arm: one hand drives one UR10 (the original's UR10_lm_arm).

Subscribes the hand's leapcobot topic and joint_states; publishes arm_controller/command and
gripper/command (trajectory_msgs/JointTrajectory) and ~status (ArmStatus) plus diagnostics.
Callbacks only store input and wake the control loop, which runs at ~rate and right after
each new hand message. Every key of config/ur10_teleop.yaml (mode, scale, workspace,
max_joint_speed, gripper_mode, ...) is also a private parameter; the launch files load that
file into the node's namespace. Those --help marks live (gains, dead zone, filters, speed
limits, the arming hold) change while running (dynamic_reconfigure); the rest at start-up.
"""
import threading

import rospy
from sensor_msgs.msg import JointState

from leap_teleop.hands.gestures.bindings import load_bindings
from leap_teleop.package_files import package_path
from leap_teleop.ros import hand_conversions
from leap_teleop.ros.arm_topics import ArmCommandTopics
from leap_teleop.ros.diagnostics import diagnostics_updater
from leap_teleop.ros.graph import TopicTypeWatch, wait_for_first_message
from leap_teleop.ros.hand_subscription import HandSubscription
from leap_teleop.ros.node import RateLimitedLog, start_node
from leap_teleop.ros.reconfigure import Reconfigure
from leap_teleop.ros.signals import closed_at_shutdown
from leap_teleop.ur10.joint_states import JointStateIndex
from leap_teleop.ur10.teleop import ArmInput
from leap_teleop.ur10.teleop_params import ARM_NODE_PARAMS, ARM_RECONFIGURABLE, TELEOP_PARAMS, ArmTeleopParams
from leap_teleop.ur10.teleop_runner import ArmTeleopRunner, StatusReporter

# The declarations live beside the teleop they configure; re-exported for --help and the docs.
PARAMS = ARM_NODE_PARAMS
RECONFIGURABLE = ARM_RECONFIGURABLE


class ArmNode:
    def __init__(self, p):
        self.p, self.name = p, rospy.get_name().lstrip('/')     # with the arm's namespace
        params = ArmTeleopParams.from_dict({k: p[k] for k in TELEOP_PARAMS})
        self.runner = ArmTeleopRunner(params, p['rate'], load_bindings(p['gesture_bindings']).arm_words())
        self.log = RateLimitedLog(2.0)
        self.joint_index = JointStateIndex(p['joint_prefix'])
        self.hand_topic = p['hand_topic'] or hand_conversions.default_topics(p['hand'])['leapcobot']
        self.hand_type = hand_conversions.LEAPCOBOT_TYPES[p['hand']]
        self.topics = ArmCommandTopics(p['joint_prefix'], p['command_queue_size'])
        self.joints_seen = threading.Event()
        self.type_watch = TopicTypeWatch(self.name, self.log)
        self.type_watch.subscribe('joint_states', JointState, self.on_joints, 'this arm',
                                  'the arm waits for its joints; publish sensor_msgs/JointState '
                                  'there', queue_size=10)
        self.type_watch.add(self.hand_topic, self.hand_type, 'this arm (hand %s)' % p['hand'],
                            "no hand input arrives; publish the %s hand there or set ~hand_topic / "
                            "the launch file's topic" % p['hand'])
        self.reporter = StatusReporter(p['status_rate'], lambda text: rospy.loginfo('%s: %s', self.name, text),
                                       lambda text: rospy.logwarn('%s: %s', self.name, text))
        self.hand_sub = None            # from wait_for_robot on
        self.diagnostics = diagnostics_updater('ur10_arm_%s' % p['hand'], 'teleop', self.report,
                                               self.topics.input_age)
        rospy.loginfo('%s: %s hand on %s drives %s (%s)', self.name, p['hand'],
                      rospy.resolve_name(self.hand_topic), self.topics.arm.resolved_name,
                      params.summary())

    # Callbacks: store and wake, nothing else.
    def on_hand(self, msg):
        hand = ArmInput.from_leapcobot_dict(hand_conversions.from_leapcobot(msg))
        why = self.runner.on_hand(hand, rospy.get_time())
        if why:
            self.log.warn('reject', '%s: ignored a hand message: %s', self.name, why)
        return why

    def on_joints(self, msg):
        try:
            q, qd = self.joint_index.state(msg.name, msg.position, msg.velocity)
            if not self.runner.on_joints(q, rospy.get_time(), qd):
                raise ValueError('non-finite or impossible positions %s' % q)
        except ValueError as e:
            self.log.warn('joints', '%s: ignored a joint_states message: %s', self.name, e)
            return
        self.joints_seen.set()

    def wait_for_robot(self):
        """Listen to the hand only once the robot reports its joints, so no gesture
        (a thumbs-up) is spent while nothing could act on it; a sender started with
        ~wait_for_subscribers then starts its session exactly when the arm is ready."""
        if not wait_for_first_message(self.joints_seen, 'joint_states', self.name):
            return False
        self.hand_sub = HandSubscription(self.hand_topic, self.hand_type, self.on_hand, self.name,
                                         self.p, self.runner.new_input_connection)
        return True

    def report(self):
        level, summary, values = self.runner.teleop.diagnostics()
        return level, summary, values + (self.hand_sub.diagnostic_values() if self.hand_sub else [])

    def tick(self, cmd, snapshot, now):
        """After each step, on the control loop's thread."""
        self.topics.send(cmd, self.runner.teleop.p.command_lead > 0)
        if self.reporter.due(snapshot, now):
            self.topics.send_status(self.runner.teleop.status)
        self.diagnostics.update()


def main(argv=None):
    p, node = start_node('ur10_arm.py', 'ur10_arm', __doc__, PARAMS, ArmNode, argv,
                         hint=' (see %s)' % package_path('config', 'ur10_teleop.yaml'))
    node.reconfigure = Reconfigure(node.name, PARAMS, RECONFIGURABLE, vars(node.runner.teleop.p),
                                   node.runner.retune)
    if node.wait_for_robot():
        with closed_at_shutdown():
            node.runner.run(rospy.get_time, rospy.is_shutdown, node.tick)
