"""Messages <-> the library's data, without a ROS master (so it is unit-testable).

Hands: HandState -> ROS messages, one function per message type, both hands alike; the
leap_motion driver's Human from whole frames (DriverHumanBuilder).

UR10 cell: Object poses: leap_teleop/ObjectPoses on OBJECT_POSES_TOPIC (the sim node's private
~object_poses): header (frame "world", sim time), names[], poses[] (world, m) and
grasped_by[] (arm holding each object, "" when none).

Commands: trajectory_msgs/JointTrajectory as ros_control's JointTrajectoryController takes
them. Joint names may carry the arm's prefix ("ur10_1_shoulder_pan_joint") or not, in any
order, but every joint of the controller exactly once. Anything malformed raises
CommandError with a reason the node logs; the arm then keeps its current trajectory.

AR.Drone: the driver's navdata, imu, mag, odometry, TF and camera messages that ardrone_sim
publishes (DroneMessages, camera_info_msg, rgb_image_msg); the pilot's input from a Hand
(pilot_input) and its cmd_vel (twist_msg).
"""
import math

import numpy as np
import rospy
from geometry_msgs.msg import Point, Pose, TransformStamped, Twist, Vector3, Vector3Stamped
from nav_msgs.msg import Odometry
from sensor_msgs.msg import CameraInfo, Image, Imu, JointState
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

from leap_teleop.drone.pilot import PilotInput
from leap_teleop.hands import skeleton
from leap_teleop.hands.frame import FINGER_NAMES
from leap_teleop.hands.tracker import hand_angles
from leap_teleop.msg import (
    ArmStatus,
    DriverBone,
    DriverFinger,
    DriverGesture,
    DriverHuman,
    GestureEvent,
    Hand,
    Navdata,
    ObjectPoses,
    leap,
    leapcobotleft,
    leapcobotright,
    leapros,
    navdata_altitude,
)
from leap_teleop.ros.ardrone_interface import NAVDATA_ALTITUDE_SIZE, NAVDATA_ALTITUDE_TAG
from leap_teleop.ur10.kinematics import JOINT_NAMES
from leap_teleop.ur10.model import GRIPPER_JOINT

LEAP_FRAME = 'leap_hands'
LEAPCOBOT_TYPES = {'right': leapcobotright, 'left': leapcobotleft}
SIDE_CODES = {'right': Hand.SIDE_RIGHT, 'left': Hand.SIDE_LEFT}
MM = 0.001


def _header(msg, state, frame_id=LEAP_FRAME):
    msg.header.stamp = rospy.Time.from_sec(state.timestamp)
    msg.header.frame_id = frame_id
    return msg


# leapcobot field -> HandState attribute, per side (built once: this is the hot path).
_LEAPCOBOT_FIELDS = {
    side: [(pattern % side, attr) for pattern, attr in (
        ('is_%s_hand', 'present'), ('%s_hand_fist', 'fist'), ('%s_hand_thumb_up', 'thumb_up'),
        ('%s_hand_pinch', 'pinch'), ('%s_hand_pinch_value', 'pinch_value'),
        ('%s_hand_origin_frame', 'origin_set'), ('%s_hand_set_origin_frame_detected', 'rock'),
        ('%s_hand_rotate_value', 'rotate'), ('%s_hand_turn_value', 'turn'),
        ('%s_hand_swing_value', 'swing'))]
    for side in ('right', 'left')}
_PALMPOS = {side: '%s_hand_palmpos' % side for side in ('right', 'left')}


def to_leapcobot(state, frame_id=LEAP_FRAME, msg=None):
    """The original leapcobotright / leapcobotleft message; palmpos in Leap mm.

    msg: a message of the side's type to refill instead of building one. The sender
    reuses one per side: filling costs about half of building on its per-frame path, and
    rospy serializes during publish() (not for latched publishers, which keep it)."""
    side = state.side
    if msg is None:
        msg = LEAPCOBOT_TYPES[side]()
    _header(msg, state, frame_id)
    for field, attr in _LEAPCOBOT_FIELDS[side]:
        setattr(msg, field, getattr(state, attr))
    palm = getattr(msg, _PALMPOS[side])
    palm.x, palm.y, palm.z = state.palm_position
    return msg


def from_leapcobot(msg):
    """Field dict of a leapcobot message without the side prefix, for consumers
    that serve both hands with one code path."""
    side = 'right' if hasattr(msg, 'is_right_hand') else 'left'
    prefix = '%s_hand_' % side
    out = {'side': side, 'present': getattr(msg, 'is_%s_hand' % side),
           'stamp': msg.header.stamp.to_sec()}
    for slot in msg.__slots__:
        if slot.startswith(prefix):
            out[slot[len(prefix):]] = getattr(msg, slot)
    p = out['palmpos']
    out['palmpos'] = (p.x, p.y, p.z)
    return out


# leapros bone field -> frame.Finger joint: a Leap bone's position is its base (the joint
# nearer the wrist); the metacarpal's base (the carpal joint) is in no source's frames.
_LEAPROS_BONES = (('proximal', 'mcp'), ('intermediate', 'pip'), ('distal', 'dip'))


def to_leapros(state, hand=None, frame_id=LEAP_FRAME):
    """The classic leap_motion/leapros message for one side, in that driver's units: Leap
    axes, millimetres, ypr in degrees as (yaw, pitch, roll), yaw and pitch of the hand's
    direction, roll of its palm normal. Finger tips come from the state; bone bases
    (proximal = knuckle, intermediate, distal) from `hand` (a hands.frame.TrackedHand) where
    its source tracks joints; a metacarpal base and anything untracked stays 0. A frame
    without the hand gives a message with only the header set."""
    msg = _header(leapros(), state, frame_id)
    if not state.present:
        return msg
    d, n = state.direction, state.palm_normal
    msg.direction = Vector3(*d)
    msg.normal = Vector3(*n)
    msg.palmpos = Point(*state.palm_position)
    # The Leap SDK's Vector.yaw / pitch / roll.
    msg.ypr = Vector3(math.degrees(math.atan2(d[0], -d[2])), math.degrees(math.atan2(d[1], -d[2])),
                      math.degrees(math.atan2(n[0], -n[1])))
    fingers = hand.fingers if hand is not None else ()
    for i, name in enumerate(FINGER_NAMES):
        setattr(msg, name + '_tip', Point(*state.finger_tips[i]))
        if i < len(fingers):
            for bone, joint in _LEAPROS_BONES:
                xyz = getattr(fingers[i], joint)
                if xyz is not None and all(math.isfinite(float(v)) for v in xyz):
                    setattr(msg, '%s_%s' % (name, bone), Point(*(float(v) for v in xyz)))
    return msg


def to_hand(state, frame_id=LEAP_FRAME):
    """The rich Hand message; positions in metres in frame leap_hands."""
    msg = _header(Hand(), state, frame_id)
    msg.side = SIDE_CODES[state.side]
    msg.present = state.present
    msg.leap_frame_id = state.frame_id
    msg.palm_position = Point(*(x * MM for x in state.palm_position))
    msg.palm_velocity = Vector3(*(x * MM for x in state.palm_velocity))
    msg.palm_normal = Vector3(*state.palm_normal)
    msg.direction = Vector3(*state.direction)
    msg.grab_strength = state.grab_strength
    msg.pinch_strength = state.pinch_strength
    msg.confidence = state.confidence
    msg.finger_extended = list(state.finger_extended)
    msg.finger_tips = [Point(*(x * MM for x in tip)) for tip in state.finger_tips]
    for name in ('fist', 'thumb_up', 'thumb_down', 'pinch', 'pinch_value', 'rock', 'open', 'origin_set',
                 'rotate', 'turn', 'swing', 'pose_class', 'pose_probability'):
        setattr(msg, name, getattr(state, name))
    return msg


def to_gesture_events(state, frame_id=LEAP_FRAME):
    """One GestureEvent message per event this frame produced."""
    out = []
    for event in state.events:
        msg = _header(GestureEvent(), state, frame_id)
        msg.side = SIDE_CODES[state.side]
        msg.gesture = event.gesture
        msg.active = event.active
        msg.value = event.value
        out.append(msg)
    return out


def hand_messages(state, frame_id=LEAP_FRAME, leapcobot=None):
    """Everything the sender publishes for one side's state, as (kind, message) pairs,
    leapcobot first; kind is 'leapcobot', 'hand' or 'gesture'. A generator, so the
    first message can go out before the others are built. Shared with the bag tools.
    leapcobot: a message to refill (see to_leapcobot)."""
    yield 'leapcobot', to_leapcobot(state, frame_id, leapcobot)
    yield 'hand', to_hand(state, frame_id)
    for msg in to_gesture_events(state, frame_id):
        yield 'gesture', msg


def default_topics(side):
    """The sender's default topic per kind for one side."""
    return {'leapcobot': 'leapmotion/data_%s' % side, 'hand': 'leapmotion/hand_%s' % side,
            'gesture': 'leapmotion/gestures'}


# --- the leap_motion driver's interface (DriverHuman and friends, leap) ------------------
# Gesture codes of the driver's Gesture message (the Leap SDK's enums).
GESTURE_TYPES = {'swipe': 1, 'circle': 4, 'screenTap': 5, 'keyTap': 6}
GESTURE_STATES = {'start': 1, 'update': 2, 'stop': 3}
# Recognizer events with a driver counterpart: both circle directions are its circle.
# fold / unfold, hand_found / hand_lost and the held poses have none.
EVENT_GESTURE_TYPES = {'circle_cw': GESTURE_TYPES['circle'],
                       'circle_ccw': GESTURE_TYPES['circle']}


def _int32(x):
    return ((int(x) + 2 ** 31) % 2 ** 32) - 2 ** 31


def _sdk_gesture(g):
    """DriverGesture from a recorded SDK gesture dict (LeapJS: type, state, id, duration in
    us, pointableIds); None for a type the driver does not have."""
    gtype = GESTURE_TYPES.get(g.get('type'))
    if gtype is None:
        return None
    msg = DriverGesture()
    msg.lmc_gesture_id = _int32(g.get('id', 0)) if isinstance(g.get('id'), int) else 0
    msg.gesture_type = gtype
    msg.gesture_state = GESTURE_STATES.get(g.get('state'), -1)
    msg.is_valid = msg.gesture_state != -1
    duration = g.get('duration', 0)
    duration = int(duration) if isinstance(duration, (int, float)) and math.isfinite(duration) \
        and duration >= 0 else 0
    msg.duration_us = duration
    msg.duration_s = duration * 1e-6
    ids = g.get('pointableIds')
    msg.pointable_ids = [_int32(i) for i in ids if isinstance(i, int)] if isinstance(ids, list) \
        else []
    msg.to_string = 'Gesture id:%d type:%s state:%s' % (msg.lmc_gesture_id, g.get('type'),
                                                         g.get('state'))
    return msg


class DriverHumanBuilder:
    """Frames + HandStates -> the leap_motion driver's Human (DriverHuman), metres and
    radians, frame leap_hands. Stateful across frames: each hand's time_visible, the frame
    rate, and ids for the recognizer's gestures.

    Filled from every source: palm centre, velocity, normal, direction, roll / pitch / yaw,
    grab / pinch strength, confidence, time_visible, the fingers' bones (skeleton), the
    recognizer's circles as circle gestures. Filled only where the frames carry them: the
    SDK's swipe, key tap, screen tap and circle gestures (recordings). Left empty (no
    source's frames have them): palm_width, sphere_radius, sphere_center, finger and bone
    widths, the metacarpal's base (the bone has length 0), the arm, bone orientations
    (identity)."""

    def __init__(self, frame_id=LEAP_FRAME):
        self.frame_id = frame_id
        self._found_at = {}
        self._last_stamp = None
        self._fps = 0.0
        self._gesture_ids = 0

    def _rate(self, stamp):
        last, self._last_stamp = self._last_stamp, stamp
        if last is not None and stamp > last:
            fps = 1.0 / (stamp - last)
            self._fps = fps if self._fps == 0.0 else 0.9 * self._fps + 0.1 * fps

    @staticmethod
    def _fingers(header, hand_id, joints):
        """Five DriverFingers from (5, 4, 3) joints in mm (mcp, pip, dip, tip)."""
        starts, ends = skeleton.bone_ends(joints)
        lengths = (np.linalg.norm(ends - starts, axis=2) * MM).tolist()
        centers = ((starts + ends) * (MM / 2.0)).tolist()
        starts, ends = (starts * MM).tolist(), (ends * MM).tolist()
        out = []
        for i in range(5):
            f = DriverFinger(header=header, type=i)
            f.lmc_finger_id = _int32(hand_id * 10 + i)
            for b in range(4):
                bone = DriverBone(header=header, type=b, length=lengths[i][b],
                                  center=centers[i][b])
                for pose, xyz in ((bone.bone_start, starts[i][b]), (bone.bone_end, ends[i][b])):
                    pose.position.x, pose.position.y, pose.position.z = xyz
                    pose.orientation.w = 1.0
                bone.to_string = '%s bone length:%.1f mm' % (skeleton.BONE_NAMES[b],
                                                             lengths[i][b] / MM)
                f.bone_list.append(bone)
            f.length = sum(lengths[i])
            f.to_string = '%s finger id:%d length:%.1f mm' % (FINGER_NAMES[i], f.lmc_finger_id,
                                                              f.length / MM)
            out.append(f)
        return out

    def _gestures(self, frame, hand, state):
        out = []
        for g in frame.gestures:
            ids = g.get('handIds')
            if isinstance(ids, list) and hand.id in ids:
                msg = _sdk_gesture(g)
                if msg is not None:
                    out.append(msg)
        for event in state.events:
            gtype = EVENT_GESTURE_TYPES.get(event.gesture)
            if gtype is None:
                continue
            self._gesture_ids += 1
            # The recognizer reports a circle once, when it has been drawn: a stop.
            out.append(DriverGesture(lmc_gesture_id=_int32(self._gesture_ids), is_valid=True,
                                     gesture_state=GESTURE_STATES['stop'], gesture_type=gtype,
                                     pointable_ids=[_int32(hand.id * 10 + 1)],
                                     to_string='Gesture %s (leap_teleop recognizer)'
                                               % event.gesture))
        return out

    def _hand(self, msg, hand, state, points, gestures, time_visible):
        """Fill msg from the state; points: (21, 3) mm, the palm centre then each finger's
        mcp, pip, dip, tip (or (1, 3): the palm only, when the source tracks no joints)."""
        header = msg.header
        msg.lmc_hand_id = _int32(hand.id)
        msg.is_present = True
        msg.time_visible = time_visible
        msg.confidence = state.confidence
        n, d = state.palm_normal, state.direction
        roll, yaw, pitch = hand_angles(n, d)
        msg.roll, msg.pitch, msg.yaw = roll, pitch, yaw
        msg.direction = Vector3(*d)
        msg.normal = Vector3(*n)
        msg.grab_strength = state.grab_strength
        msg.pinch_strength = state.pinch_strength
        msg.palm_velocity = [x * MM for x in state.palm_velocity]
        msg.palm_center = Point(*(float(x) * MM for x in points[0]))
        if len(points) > 1:
            msg.finger_list = self._fingers(header, hand.id, points[1:].reshape(5, 4, 3))
        msg.gesture_list = gestures
        msg.valid_gestures = bool(gestures)
        msg.arm.header = header
        msg.arm.elbow.orientation.w = msg.arm.wrist.orientation.w = 1.0
        p = msg.palm_center
        msg.to_string = 'Hand id:%d %s palm:(%.3f, %.3f, %.3f) m' % (hand.id, state.side, p.x,
                                                                     p.y, p.z)

    def _message(self, frame):
        msg = DriverHuman()
        msg.header.stamp = rospy.Time.from_sec(frame.timestamp)
        msg.header.frame_id = self.frame_id
        msg.lmc_frame_id = _int32(frame.id)
        msg.current_frames_per_second = self._fps
        msg.right_hand.header = msg.left_hand.header = msg.header
        return msg

    def build(self, frame, states, raw=True, lowpass=None):
        """(raw, filtered) DriverHumans of one frame; states: side -> HandState (a
        LeapInterface listener's). raw=False leaves the raw one out (None); `lowpass`
        (lowpass.LowPass, one key per side) makes the filtered one, as the driver's filter
        node does: the palm centre and every joint low-passed (else None). A side missing
        from `states`, or not present in its state, is an absent hand."""
        self._rate(frame.timestamp)
        out = [self._message(frame) if raw else None,
               self._message(frame) if lowpass is not None else None]
        for side in ('right', 'left'):
            state = states.get(side)
            hand = frame.hand(side)
            if state is None or not state.present or hand is None:
                self._found_at.pop(side, None)
                if lowpass is not None:
                    lowpass.reset(side)
                continue
            found = self._found_at.setdefault(side, state.timestamp)
            time_visible = max(state.timestamp - found, 0.0)
            gestures = self._gestures(frame, hand, state)
            joints = skeleton.hand_joints(hand)
            points = np.asarray(state.palm_position, dtype=float).reshape(1, 3)
            if joints is not None:
                points = np.concatenate([points, joints.reshape(20, 3)])
            for msg, pts in ((out[0], points),
                             (out[1], lowpass(side, points) if lowpass is not None else None)):
                if msg is None:
                    continue
                h = getattr(msg, side + '_hand')
                self._hand(h, hand, state, pts, gestures, time_visible)
                msg.nr_of_hands += 1
                msg.nr_of_fingers += len(h.finger_list)
                msg.nr_of_gestures += len(h.gesture_list)
        for msg in out:
            if msg is not None:
                msg.to_string = 'Frame id:%d timestamp:%.3f hands:%d fingers:%d gestures:%d' % (
                    msg.lmc_frame_id, frame.timestamp, msg.nr_of_hands, msg.nr_of_fingers,
                    msg.nr_of_gestures)
        return tuple(out)


def to_leap(state, frame_id=LEAP_FRAME):
    """The old sender's leap message for one side, in that sender's units (the same getters
    fed its leapros): Leap axes, millimetres, degrees; the angles as to_leapros's (pitch and
    yaw of the direction, roll of the palm normal). A frame without the hand gives a message
    with only the header set."""
    msg = _header(leap(), state, frame_id)
    if not state.present:
        return msg
    msg.hand_direction = list(state.direction)
    msg.hand_normal = list(state.palm_normal)
    msg.hand_palm_pos = list(state.palm_position)
    roll, yaw, pitch = hand_angles(state.palm_normal, state.direction)
    msg.hand_roll, msg.hand_yaw, msg.hand_pitch = (math.degrees(roll), math.degrees(yaw),
                                                   math.degrees(pitch))
    return msg


# -- UR10 cell: object poses, joint states, trajectory commands -----------------------

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
        bare = name[len(prefix):] if prefix and name.startswith(prefix) else name
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


# Reading and checking a trajectory's points holds the simulator's physics loop: 100,000
# stopped its joint states for over a second. 10,000 is 100 s of points at 100 Hz.
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


# -- AR.Drone: the driver's messages from a DroneReading ---------------------------------

G_NAVDATA = 9.8                 # m/s^2 per g of navdata's ax / ay / az on ardrone/imu


class DroneMessages:
    """What ardrone_sim publishes each tick, from one drone.sim_runner.DroneReading:
    navdata (with the sensors), mag, imu, odometry, the TF odom -> body and the
    navdata_altitude option (built only when asked for)."""

    def __init__(self, reading, stamp, base_frame, odom_frame, with_altitude=False):
        r, nav = reading, reading.nav
        self.navdata = Navdata()
        self.navdata.header.stamp, self.navdata.header.frame_id = stamp, base_frame
        for key, value in nav.items():
            setattr(self.navdata, key, value)
        self.mag = Vector3Stamped(header=self.navdata.header,
                                  vector=Vector3(nav['magX'], nav['magY'], nav['magZ']))
        self.imu = Imu()
        self.imu.header.stamp, self.imu.header.frame_id = stamp, base_frame
        o = self.imu.orientation
        o.x, o.y, o.z, o.w = r.quat
        self.imu.angular_velocity = Vector3(*r.omega)
        self.imu.linear_acceleration = Vector3(nav['ax'] * G_NAVDATA, nav['ay'] * G_NAVDATA,
                                               nav['az'] * G_NAVDATA)
        self.odometry = Odometry()
        self.odometry.header.stamp, self.odometry.header.frame_id = stamp, odom_frame
        self.odometry.child_frame_id = base_frame
        pp = self.odometry.pose.pose
        pp.position = Point(r.pos[0], r.pos[1], r.altitude)
        pp.orientation = o
        self.odometry.twist.twist.linear = Vector3(nav['vx'] / 1000, nav['vy'] / 1000,
                                                   nav['vz'] / 1000)
        self.odometry.twist.twist.angular = Vector3(*r.omega)
        self.transform = transform_msg(odom_frame, base_frame,
                                       (r.pos[0], r.pos[1], r.altitude), r.quat, stamp)
        self.navdata_altitude = (navdata_altitude_msg(self.navdata.header, nav, r.altitude)
                                 if with_altitude else None)


def navdata_altitude_msg(header, nav, altitude):
    """The driver's altitude option: vision / raw / reference altitude (mm) are the sim's
    true one, the observer's state its altitude (m) and climb rate (m/s)."""
    out = navdata_altitude()
    out.header = header
    out.drone_time = nav['tm'] / 1e6
    out.tag, out.size = NAVDATA_ALTITUDE_TAG, NAVDATA_ALTITUDE_SIZE
    out.altitude_vision = out.altitude_raw = out.altitude_ref = nav['altd']
    out.altitude_vz = nav['vz']
    out.obs_accZ = nav['az'] * 9.81
    out.obs_alt = max(altitude, 0.0)
    out.obs_x.x, out.obs_x.y = max(altitude, 0.0), nav['vz'] / 1000.0
    out.est_vb.x = nav['vz'] / 1000.0
    return out


def transform_msg(parent, child, xyz, quat_xyzw, stamp):
    t = TransformStamped()
    t.header.stamp, t.header.frame_id, t.child_frame_id = stamp, parent, child
    t.transform.translation = Vector3(*xyz)
    r = t.transform.rotation
    r.x, r.y, r.z, r.w = quat_xyzw
    return t


def camera_info_msg(spec, frame_id):
    """The ideal (undistorted) calibration of a drone.cameras.CameraSpec."""
    info = CameraInfo()
    info.header.frame_id = frame_id
    info.width, info.height = spec.width, spec.height
    info.distortion_model = 'plumb_bob'
    info.D = [0.0] * 5
    info.K, info.P = spec.intrinsics()
    info.R = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]
    return info


def rgb_image_msg(rgb, stamp, frame_id):
    """sensor_msgs/Image (rgb8) of a (H, W, 3) uint8 picture; stamp a rospy.Time."""
    msg = Image()
    msg.header.stamp, msg.header.frame_id = stamp, frame_id
    msg.height, msg.width = rgb.shape[:2]
    msg.encoding, msg.step = 'rgb8', rgb.shape[1] * 3
    msg.data = rgb.tobytes()
    return msg


# -- AR.Drone: the pilot's input and commands --------------------------------------------

def pilot_input(msg):
    """The drone pilot's PilotInput from a leap_teleop/Hand (metres, unit vectors, the
    capture stamp in s)."""
    p, n, d = msg.palm_position, msg.palm_normal, msg.direction
    return PilotInput(msg.present, (p.x, p.y, p.z), (n.x, n.y, n.z), (d.x, d.y, d.z),
                      msg.header.stamp.to_sec())


def twist_msg(twist):
    """A geometry_msgs/Twist from (linear x, y, z, angular x, y, z)."""
    t = Twist()
    t.linear.x, t.linear.y, t.linear.z, t.angular.x, t.angular.y, t.angular.z = twist
    return t


# -- UR10 arm: trajectory commands and status -------------------------------------------

def joint_trajectory(names, points, stamp=0.0):
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


def arm_status_message(status):
    """An ArmStatus from the arm teleop's ArmTeleopStatus, stamped now."""
    msg = ArmStatus(state=status.state, reason=status.reason, origin_set=status.origin_set,
                    rejected_inputs=status.rejected_inputs, ik_failures=status.ik_failures)
    msg.header.stamp = rospy.Time.now()
    if len(status.target) == 3:
        msg.target = Point(*status.target)
    if status.input_stamp > 0:
        msg.input_stamp = rospy.Time.from_sec(status.input_stamp)
    return msg


# -- camera view -----------------------------------------------------------------------

def image_message(bgr, stamp, frame_id):
    """sensor_msgs/Image (encoding bgr8) of a (H, W, 3) uint8 image (no cv_bridge needed)."""
    img = np.ascontiguousarray(bgr, dtype=np.uint8)
    msg = Image()
    msg.header.stamp = rospy.Time.from_sec(stamp)
    msg.header.frame_id = frame_id
    msg.height, msg.width = img.shape[:2]
    msg.encoding = 'bgr8'
    msg.is_bigendian = 0
    msg.step = msg.width * 3
    msg.data = img.tobytes()
    return msg
