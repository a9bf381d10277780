"""The simulated UR10 cell's state, each tick it is due: every arm's joint_states (in the
arm's namespace), the cubes on ~object_poses and /clock in sim time; the watches on its
command topics' types; and the watch for a second /clock (both simulators use it)."""
import threading

import rosgraph
import rospy
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import JointState
from trajectory_msgs.msg import JointTrajectory

from leap_teleop.msg import ObjectPoses
from leap_teleop.ros.graph import TopicTypeWatch
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


class ClockRivalWatch:
    """Logs one error per other node that publishes /clock beside a simulator that is the
    clock under /use_sim_time (a bag played with --clock, another simulator): ROS time then
    jumps between the two and nothing that waits on it moves, with no other word of the
    cause. Asks the master every `period` wall s on a thread of its own: the lookup blocks,
    and it must never hold the physics loop."""

    def __init__(self, who, period=2.0, start=True):
        self.who, self.period = who, period
        self.reported = set()
        self._stop = threading.Event()
        self.thread = None
        if start:
            self.thread = threading.Thread(target=self._run, name='clock_rival_watch', daemon=True)
            self.thread.start()

    def check(self):
        """The other /clock publishers not reported before (each is logged once)."""
        me = rospy.get_name()
        clock = rospy.resolve_name('/clock')    # where this node's clock goes (remapped or not)
        try:
            published = rosgraph.Master(me).getSystemState()[0]
        except Exception:       # the master gone or busy: ask again next period
            return []
        new = sorted({n for topic, nodes in published if topic == clock
                      for n in nodes if n != me} - self.reported)
        if new:
            self.reported.update(new)
            rospy.logerr('%s: %s also publish%s %s: under /use_sim_time this simulator is the '
                         'clock, so ROS time jumps between the two and the robots do not move; run '
                         'the other without a clock (replay.launch: leave use_sim_time false)',
                         self.who, ', '.join(new), 'es' if len(new) == 1 else '', clock)
        return new

    def _run(self):
        while not self._stop.wait(self.period) and not rospy.is_shutdown():
            self.check()

    def stop(self):
        self._stop.set()


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
