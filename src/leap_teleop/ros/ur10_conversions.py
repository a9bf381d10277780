"""UR10 cell messages <-> the library's data, without a ROS master.

Object poses: leap_teleop/ObjectPoses on OBJECT_POSES_TOPIC (the sim node's private
~object_poses): header (frame "world", sim time), names[], poses[] (world, m) and
grasped_by[] (arm holding each object, "" when none).

Commands: trajectory_msgs/JointTrajectory as ros_control's JointTrajectoryController takes
them. Joint names may carry the arm's prefix ("ur10_1_shoulder_pan_joint") or not, in any
order, but every joint of the controller exactly once. Anything malformed raises
CommandError with a reason the node logs; the arm then keeps its current trajectory. The
arm node's commands and status go the other way (joint_trajectory_msg, arm_status_msg)."""
import math

import numpy as np
import rospy
from geometry_msgs.msg import Point, Pose
from sensor_msgs.msg import JointState
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

from leap_teleop.msg import ArmStatus, ObjectPoses
from leap_teleop.ur10.kinematics import JOINT_NAMES
from leap_teleop.ur10.model import GRIPPER_JOINT

OBJECT_POSES_TOPIC = '/ur10_sim/object_poses'
OBJECT_POSES_TYPE = ObjectPoses
WORLD_FRAME = 'world'
ARM_JOINTS = tuple(JOINT_NAMES)
GRIPPER_JOINTS = (GRIPPER_JOINT,)


class CommandError(ValueError):
    """A trajectory command the sim refuses; str() says why."""


def object_positions(msg):
    """{name: (x, y, z)} in world metres from an ObjectPoses message."""
    return {name: (pose.position.x, pose.position.y, pose.position.z)
            for name, pose in zip(msg.names, msg.poses)}


def object_poses_msg(poses, grasped_by=None, stamp=None):
    """ObjectPoses from UR10Cell.object_poses() ({name: (xyz, quat xyzw)}) and
    {object: arm} of the grasped ones."""
    grasped_by = grasped_by or {}
    msg = ObjectPoses()
    msg.header.frame_id = WORLD_FRAME
    if stamp is not None:
        msg.header.stamp = stamp
    for name, (xyz, quat) in poses.items():
        pose = Pose()
        pose.position.x, pose.position.y, pose.position.z = (float(v) for v in xyz)
        o = pose.orientation
        o.x, o.y, o.z, o.w = (float(v) for v in quat)
        msg.names.append(name)
        msg.poses.append(pose)
        msg.grasped_by.append(grasped_by.get(name, ''))
    return msg


def joint_state_msg(prefix, q, qd, gripper, gripper_velocity, stamp=None):
    """sensor_msgs/JointState of one arm: the six arm joints then the gripper knuckle,
    names prefixed (ur10_1_shoulder_pan_joint, ..., ur10_1_finger_joint)."""
    msg = JointState()
    if stamp is not None:
        msg.header.stamp = stamp
    msg.name = [prefix + n for n in ARM_JOINTS + GRIPPER_JOINTS]
    msg.position = [float(v) for v in q] + [float(gripper)]
    msg.velocity = [float(v) for v in qd] + [float(gripper_velocity)]
    msg.effort = []
    return msg


def _finite(values, what):
    try:
        a = np.asarray(values, dtype=float)
    except (TypeError, ValueError):
        raise CommandError('%s are not numbers' % what) from None
    if not np.all(np.isfinite(a)):
        raise CommandError('%s contain NaN or inf' % what)
    return a


def joint_order(names, expected, prefix):
    """Index into `names` for each expected joint; CommandError on unknown, duplicate or
    missing names. A name matches with or without the arm's prefix."""
    if not names:
        raise CommandError('no joint_names')
    index = {}
    for i, name in enumerate(names):
        # A bare name first: an arm called 'wrist' has the prefix 'wrist_', which the bare
        # 'wrist_1_joint' starts with ('<prefix>x' names a joint only where 'x' does not).
        bare = name if name in expected or not (prefix and name.startswith(prefix)) else name[len(prefix):]
        if bare not in expected:
            raise CommandError('unknown joint %r (expected %s, optionally prefixed %r)'
                               % (name, ', '.join(expected), prefix))
        if bare in index:
            raise CommandError('joint %r given twice' % name)
        index[bare] = i
    missing = [n for n in expected if n not in index]
    if missing:
        raise CommandError('missing joints %s (partial trajectories are not supported)'
                           % ', '.join(missing))
    return [index[n] for n in expected]


# Reading, checking and planning a trajectory's points holds its subscriber thread (15-40 us
# a point; 100,000 held the physics loop for over a second when it planned them there).
# 10,000 is 100 s of points at 100 Hz.
MAX_TRAJECTORY_POINTS = 10000


def trajectory_points(msg, expected, prefix):
    """(points, stamp_s) from a JointTrajectory for joints `expected`: points are
    [(time_from_start s, positions in expected order, velocities or None[,
    accelerations])] (accelerations only where velocities are given, as the JTC reads them);
    stamp_s is
    header.stamp in seconds (0 = start now). CommandError when malformed: bad names,
    no points, NaN / inf, wrong lengths, times not strictly increasing or negative."""
    order = joint_order(list(msg.joint_names), expected, prefix)
    if not msg.points:
        raise CommandError('empty trajectory (no points)')
    if len(msg.points) > MAX_TRAJECTORY_POINTS:
        raise CommandError('%d points: at most %d' % (len(msg.points), MAX_TRAJECTORY_POINTS))
    n = len(msg.joint_names)
    points, last = [], -math.inf
    for k, pt in enumerate(msg.points):
        t = pt.time_from_start.to_sec()
        if not math.isfinite(t) or t < 0:
            raise CommandError('point %d: negative time_from_start %.6g' % (k, t))
        if t <= last:
            raise CommandError('point %d: time_from_start %.6g not after the previous %.6g'
                               % (k, t, last))
        last = t
        if len(pt.positions) != n:
            raise CommandError('point %d: %d positions for %d joints' % (k, len(pt.positions), n))
        pos = _finite(pt.positions, 'point %d positions' % k)[order]
        vel = None
        if len(pt.velocities):
            if len(pt.velocities) != n:
                raise CommandError('point %d: %d velocities for %d joints'
                                   % (k, len(pt.velocities), n))
            vel = _finite(pt.velocities, 'point %d velocities' % k)[order]
        if vel is not None and len(pt.accelerations):
            if len(pt.accelerations) != n:
                raise CommandError('point %d: %d accelerations for %d joints'
                                   % (k, len(pt.accelerations), n))
            points.append((t, pos, vel, _finite(pt.accelerations,
                                                'point %d accelerations' % k)[order]))
            continue
        points.append((t, pos, vel))
    return points, msg.header.stamp.to_sec()


def joint_trajectory_msg(names, points, stamp=0.0):
    """A JointTrajectory for joints `names` from points [(time_from_start s, positions,
    velocities or None)], starting at `stamp` (s; 0 = on receipt, the ros_control
    convention)."""
    msg = JointTrajectory()
    msg.header.stamp = rospy.Time.from_sec(stamp) if stamp > 0 else rospy.Time(0)
    msg.joint_names = list(names)
    msg.points = [JointTrajectoryPoint(
        positions=[float(x) for x in q],
        velocities=[] if v is None else [float(x) for x in v],
        time_from_start=rospy.Duration.from_sec(t)) for t, q, v in points]
    return msg


def arm_status_msg(status):
    """An ArmStatus from the arm teleop's ArmTeleopStatus, stamped now."""
    msg = ArmStatus(state=status.state, reason=status.reason, origin_set=status.origin_set,
                    rejected_inputs=status.rejected_inputs, ik_failures=status.ik_failures)
    msg.header.stamp = rospy.Time.now()
    if len(status.target) == 3:
        msg.target = Point(*status.target)
    if status.input_stamp > 0:
        msg.input_stamp = rospy.Time.from_sec(status.input_stamp)
    return msg
