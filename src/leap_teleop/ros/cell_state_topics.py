"""The simulated UR10 cell's state, each tick it is due: every arm's joint_states (in the
arm's namespace), the cubes on ~object_poses and /clock in sim time; the watches on its
command topics' types; and the watch for a second /clock (ros/graph.py's)."""
import rospy
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import JointState
from trajectory_msgs.msg import JointTrajectory

from leap_teleop.msg import ObjectPoses
from leap_teleop.ros.graph import ClockRivalWatch, TopicTypeWatch
from leap_teleop.ros.ur10_conversions import joint_state_msg, object_poses_msg
from leap_teleop.ur10.cell_runner import KINDS


def command_type_watch(config, log):
    """A TopicTypeWatch (warning through `log`) on each command topic of `config`'s arms:
    rospy drops a publisher of another type with no word to the sim."""
    watch = TopicTypeWatch('ur10_sim', log)
    for arm in config.arms:
        for kind, (topic, joints) in KINDS.items():
            watch.add('%s/%s' % (arm.name, topic), JointTrajectory, 'the simulated %s' % arm.name,
                      'nothing published there moves the %s; publish trajectory_msgs/JointTrajectory '
                      'for %s' % (kind, ', '.join(joints)))
    return watch


class CellStateTopics:
    """The publishers of a CellTick for `config`'s arms (joint_states queued
    `joint_states_queue_size` per subscriber)."""

    def __init__(self, config, joint_states_queue_size, use_sim_time):
        self.config, self.use_sim_time = config, use_sim_time
        self.clock = rospy.Publisher('/clock', Clock, queue_size=10) if use_sim_time else None
        self.clock_watch = ClockRivalWatch('ur10_sim') if use_sim_time else None
        self.joint_states = {a.name: rospy.Publisher(a.name + '/joint_states', JointState,
                                                     queue_size=joint_states_queue_size)
                             for a in config.arms}
        self.object_poses = rospy.Publisher('~object_poses', ObjectPoses, queue_size=5)

    def publish(self, tick):
        stamp = rospy.Time.from_sec(tick.time) if self.use_sim_time else rospy.Time.now()
        if tick.clock:
            self.clock.publish(Clock(clock=stamp))
        for arm, (q, qd, g, gd) in (tick.joint_states or {}).items():
            self.joint_states[arm].publish(joint_state_msg(self.config.arm(arm).prefix,
                                                           q, qd, g, gd, stamp))
        if tick.object_poses:
            self.object_poses.publish(object_poses_msg(*tick.object_poses, stamp=stamp))
