"""ur10_arm: one hand drives one UR10 (the original's UR10_lm_arm).

Subscribes the hand's leapcobot topic and joint_states; publishes
arm_controller/command and gripper/command (trajectory_msgs/JointTrajectory) and
~status (ArmStatus) plus diagnostics. Callbacks only store input and wake the control
loop, which runs at ~rate and right after each new hand message. Every key of
config/ur10_teleop.yaml (mode, scale, workspace, max_joint_speed, gripper_mode, ...) is
also a private parameter; the launch files load that file into the node's namespace.
RECONFIGURABLE of them (gains, dead zone, filter constants, speed limits, the arming hold)
can be changed while running with dynamic_reconfigure; the others are start-up only.
"""
import threading
import time

import diagnostic_updater
import rospy
from diagnostic_msgs.msg import DiagnosticStatus
from sensor_msgs.msg import JointState
from trajectory_msgs.msg import JointTrajectory

from leap_teleop.control.input_age import InputAgeWindow
from leap_teleop.msg import ArmStatus
from leap_teleop.ros import conversions
from leap_teleop.ros.node import RateLimitedLog, package_path, start_node
from leap_teleop.ros.reconfigure import Reconfigure
from leap_teleop.ros.signals import closed_at_shutdown
from leap_teleop.ur10.joint_states import JointStateIndex
from leap_teleop.ur10.kinematics import JOINT_NAMES
from leap_teleop.ur10.model import GRIPPER_JOINT
from leap_teleop.ur10.teleop import HOLDING, ArmInput, ArmTeleop
from leap_teleop.ur10.teleop_params import ARM_NODE_PARAMS, ARM_RECONFIGURABLE, TELEOP_PARAMS, ArmTeleopParams

# The declarations live beside the teleop they configure; re-exported for --help and the docs.
PARAMS = ARM_NODE_PARAMS
RECONFIGURABLE = ARM_RECONFIGURABLE


def teleop_params(p):
    """ArmTeleopParams from the node's checked ~params."""
    return ArmTeleopParams.from_dict({k: p[k] for k in TELEOP_PARAMS})


class ArmNode:
    def __init__(self, p, params):
        self.p = p
        self.teleop = ArmTeleop(params)
        self.lock = threading.Lock()
        self.wake = threading.Event()
        self.log = RateLimitedLog(2.0)
        prefix = p['joint_prefix']
        self.arm_joints = [prefix + n for n in JOINT_NAMES]
        self.gripper_joint = prefix + GRIPPER_JOINT
        self.joint_index = JointStateIndex()
        side = p['hand']
        topic = p['hand_topic'] or 'leapmotion/data_%s' % side
        self.arm_pub = rospy.Publisher('arm_controller/command', JointTrajectory, queue_size=10)
        self.gripper_pub = rospy.Publisher('gripper/command', JointTrajectory, queue_size=10)
        self.status_pub = rospy.Publisher('~status', ArmStatus, queue_size=10, latch=True)
        self.hand_topic, self.hand_type = topic, conversions.LEAPCOBOT_TYPES[side]
        self.joints_seen = threading.Event()
        rospy.Subscriber('joint_states', JointState, self.on_joints, queue_size=10)
        self._last_status = None
        self._last_status_pub = 0.0
        self.input_age = InputAgeWindow()      # control loop thread only
        self.diagnostics = diagnostic_updater.Updater()
        self.diagnostics.setHardwareID('ur10_arm_%s' % side)
        self.diagnostics.add('teleop', self.diagnose)
        rospy.loginfo('ur10_arm: %s hand on %s drives %s (mode %s, orientation %s, gripper %s, '
                      'max joint speed %.3g rad/s, acceleration %.3g rad/s^2)', side,
                      rospy.resolve_name(topic), self.arm_pub.resolved_name, params.mode,
                      params.orientation, params.gripper_mode, params.max_joint_speed,
                      params.max_joint_accel)

    # Callbacks: store and wake, nothing else.
    def on_hand(self, msg):
        hand = ArmInput.from_leapcobot_dict(conversions.from_leapcobot(msg))
        with self.lock:
            why = self.teleop.on_hand(hand, rospy.get_time())
        if why:
            self.log.warn('reject', 'ur10_arm: ignored a hand message: %s', why)
        self.wake.set()

    def on_joints(self, msg):
        try:
            q = self.joint_index.positions(msg.name, msg.position)
        except KeyError as e:
            self.log.warn('joints', 'ur10_arm: joint_states lacks %s', e.args[0])
            return
        with self.lock:
            self.teleop.on_joints(q, rospy.get_time())
        self.joints_seen.set()

    def start_reconfigure(self):
        """dynamic_reconfigure on ~: RECONFIGURABLE, applied under the control loop's lock."""
        def apply(changes):
            with self.lock:
                self.teleop.retune(changes)
        self.reconfigure = Reconfigure('ur10_arm', PARAMS, RECONFIGURABLE,
                                       {k: getattr(self.teleop.p, k) for k in RECONFIGURABLE},
                                       apply)

    def wait_for_robot(self):
        """Listen to the hand only once the robot reports its joints, so no gesture
        (a thumbs-up) is spent while nothing could act on it; a sender started with
        ~wait_for_subscribers then starts its session exactly when the arm is ready."""
        last_log = time.monotonic()
        while not self.joints_seen.wait(0.2):
            if rospy.is_shutdown():
                return False
            if time.monotonic() - last_log >= 5.0:
                last_log = time.monotonic()
                rospy.loginfo('ur10_arm: waiting for %s', rospy.resolve_name('joint_states'))
        rospy.Subscriber(self.hand_topic, self.hand_type, self.on_hand, queue_size=50,
                         tcp_nodelay=True)
        # Its own timer thread: the master lookup blocks, the control loop must not.
        self._type_check = rospy.Timer(rospy.Duration(5.0), self.check_hand_type)
        return True

    def check_hand_type(self, _event=None):
        """Say so when the hand topic carries another type (e.g. the other hand's
        leapcobot, or leapros): rospy drops such a connection with no word to this node,
        and the arm would wait for a thumbs-up that never arrives."""
        topic, want = rospy.resolve_name(self.hand_topic), self.hand_type._type
        try:
            published = dict(rospy.get_published_topics())
        except Exception as e:      # the master gone or busy: try again next period
            self.log.warn('type_check', 'ur10_arm: cannot ask the master for %s: %s', topic, e)
            return None
        got = published.get(topic)
        if got is not None and got != want:
            self.log.warn('type_check', 'ur10_arm: %s carries %s, but this arm (hand %s) reads '
                          '%s: no hand input arrives; publish the %s hand there or set '
                          '~hand_topic / the launch file\'s topic', topic, got, self.p['hand'],
                          want, self.p['hand'])
        return got

    def loop(self):
        period = 1.0 / float(self.p['rate'])
        while not rospy.is_shutdown():
            self.wake.wait(period)
            self.wake.clear()
            now = rospy.get_time()
            with self.lock:
                cmd = self.teleop.step(now)
                status = self.teleop.status
                snapshot = (status.state, status.reason, status.origin_set)
            if cmd.points:
                # Stamp 0 (start on receipt): a command delayed in transport still starts
                # from the controller's current state instead of partly in the past.
                self.arm_pub.publish(conversions.joint_trajectory(self.arm_joints, cmd.points))
            if cmd.gripper is not None:
                self.gripper_pub.publish(conversions.joint_trajectory(
                    [self.gripper_joint], [(0.1, [cmd.gripper], None)]))
            if cmd.points or cmd.gripper is not None:
                self.input_age.add(rospy.get_time(), cmd.input_stamp)
            self._publish_status(snapshot, now)
            self.diagnostics.update()

    def _publish_status(self, snapshot, now):
        changed = snapshot != self._last_status
        if changed:
            state, reason, _ = snapshot
            log = rospy.logwarn if state == HOLDING else rospy.loginfo
            log('ur10_arm: %s (%s)', state, reason)
        if not changed and now - self._last_status_pub < 1.0 / float(self.p['status_rate']):
            return
        self._last_status, self._last_status_pub = snapshot, now
        self.status_pub.publish(conversions.arm_status_message(self.teleop.status))

    def diagnose(self, stat):
        warn, summary, values = self.teleop.diagnostics()
        stat.summary(DiagnosticStatus.WARN if warn else DiagnosticStatus.OK, summary)
        for key, value in values + self.input_age.diagnostic_values(rospy.get_time()):
            stat.add(key, value)
        return stat


def main(argv=None):
    p, node = start_node('ur10_arm.py', 'ur10_arm', __doc__, PARAMS,
                         lambda p: ArmNode(p, teleop_params(p)), argv,
                         hint=' (see %s)' % package_path('config', 'ur10_teleop.yaml'))
    node.start_reconfigure()
    if node.wait_for_robot():
        with closed_at_shutdown():
            node.loop()
