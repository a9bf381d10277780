"""One UR10's teleop outputs: the JointTrajectory commands of its arm and gripper
controllers, and the arm node's latched ~status."""
import rospy
from trajectory_msgs.msg import JointTrajectory

from leap_teleop.control.input_age import InputAgeWindow
from leap_teleop.msg import ArmStatus
from leap_teleop.ros import ur10_conversions
from leap_teleop.ur10.kinematics import JOINT_NAMES
from leap_teleop.ur10.model import GRIPPER_JOINT


class ArmCommandTopics:
    """arm_controller/command and gripper/command for the joints named with `prefix`, and
    ~status. input_age keeps the age of the hand input behind each command sent (read and
    written on the sending thread only)."""

    def __init__(self, prefix, queue_size=50):
        self.arm_joints = [prefix + n for n in JOINT_NAMES]
        self.gripper_joint = prefix + GRIPPER_JOINT
        self.arm = rospy.Publisher('arm_controller/command', JointTrajectory,
                                   queue_size=queue_size)
        self.gripper = rospy.Publisher('gripper/command', JointTrajectory, queue_size=queue_size)
        self.status = rospy.Publisher('~status', ArmStatus, queue_size=10, latch=True)
        self.input_age = InputAgeWindow()

    def send(self, cmd, stamped=False):
        """Publish what an ArmCommand holds: its trajectory, its gripper goal, or neither.
        stamped (a command_lead): the trajectory starts at cmd.stamp."""
        if cmd.points:
            # Else stamp 0 (start on receipt): a command delayed in transport still starts
            # from the controller's current state instead of partly in the past.
            self.arm.publish(ur10_conversions.joint_trajectory_msg(
                self.arm_joints, cmd.points, cmd.stamp if stamped else 0.0))
        if cmd.gripper is not None:
            self.gripper.publish(ur10_conversions.joint_trajectory_msg(
                [self.gripper_joint], [(0.1, [cmd.gripper], None)]))
        if cmd.points or cmd.gripper is not None:
            self.input_age.add(rospy.get_time(), cmd.input_stamp)

    def send_status(self, status):
        """Publish the teleop's ArmTeleopStatus as an ArmStatus."""
        self.status.publish(ur10_conversions.arm_status_msg(status))
