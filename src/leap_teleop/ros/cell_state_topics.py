"""The simulated UR10 cell's state, each tick it is due: every arm's joint_states (in the
arm's namespace), the cubes on ~object_poses and /clock in sim time."""
import rospy
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import JointState

from leap_teleop.msg import ObjectPoses
from leap_teleop.ros.conversions import joint_state_msg, object_poses_msg


class CellStateTopics:
    """The publishers of a CellTick for `config`'s arms (joint_states queued
    `joint_states_queue_size` per subscriber)."""

    def __init__(self, config, joint_states_queue_size, use_sim_time):
        self.config, self.use_sim_time = config, use_sim_time
        self.clock = rospy.Publisher('/clock', Clock, queue_size=10) if use_sim_time else None
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
