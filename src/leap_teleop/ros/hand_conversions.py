"""Hand messages <-> the library's data, without a ROS master (so it is unit-testable):
HandState -> leapcobot, leapros, Hand, GestureEvent, one function per message type, both
hands alike, and the leap_motion driver's Human from whole frames (DriverHumanBuilder)."""
import math

import numpy as np
import rospy
from geometry_msgs.msg import Point, Vector3

from leap_teleop.hands import skeleton
from leap_teleop.hands.frame import FINGER_NAMES
from leap_teleop.hands.tracker import hand_angles
from leap_teleop.msg import (
    DriverBone,
    DriverFinger,
    DriverGesture,
    DriverHuman,
    GestureEvent,
    Hand,
    leap,
    leapcobotleft,
    leapcobotright,
    leapros,
)

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
# nearer the wrist), the metacarpal's the carpal joint (only where the source measures it).
_LEAPROS_BONES = (('metacarpal', 'carpal'), ('proximal', 'mcp'), ('intermediate', 'pip'),
                  ('distal', 'dip'))


def classic_ypr(normal, direction):
    """(yaw, pitch, roll) in degrees as the classic sender computed them for its leapros and
    leap messages: yaw of the palm normal, pitch and roll of the direction, each the Leap
    SDK's Vector angle (yaw atan2(x, -z), pitch atan2(y, -z), roll atan2(x, -y)). Not the
    hand angles of DriverHand (roll of the normal, pitch and yaw of the direction): the
    classic consumers were written against these numbers."""
    n, d = normal, direction
    return (math.degrees(math.atan2(n[0], -n[2])), math.degrees(math.atan2(d[1], -d[2])),
            math.degrees(math.atan2(d[0], -d[1])))


def to_leapros(state, hand=None, frame_id=LEAP_FRAME):
    """The classic leap_motion/leapros message for one side, in that driver's units: Leap
    axes, millimetres, ypr in degrees as (yaw, pitch, roll) of classic_ypr. Finger tips come
    from the state; bone bases (metacarpal = carpal joint, proximal = knuckle, intermediate,
    distal) from `hand` (a hands.frame.TrackedHand) where its source tracks them; anything
    untracked stays 0 (the carpal joint of scripted and camera hands), as does a joint
    beyond skeleton.MAX_JOINT (a tracking error, as the tracker takes such a tip; the
    driver's Human has no bones then). A frame without the hand gives a message with only
    the header set."""
    msg = _header(leapros(), state, frame_id)
    if not state.present:
        return msg
    d, n = state.direction, state.palm_normal
    msg.direction = Vector3(*d)
    msg.normal = Vector3(*n)
    msg.palmpos = Point(*state.palm_position)
    msg.ypr = Vector3(*classic_ypr(n, d))
    fingers = hand.fingers if hand is not None else ()
    for i, name in enumerate(FINGER_NAMES):
        setattr(msg, name + '_tip', Point(*state.finger_tips[i]))
        if i < len(fingers):
            for bone, joint in _LEAPROS_BONES:
                xyz = getattr(fingers[i], joint, None)
                if xyz is None:
                    continue
                xyz = [float(v) for v in xyz]
                # NaN compares false
                if len(xyz) == 3 and all(abs(v) <= skeleton.MAX_JOINT for v in xyz):
                    setattr(msg, '%s_%s' % (name, bone), Point(*xyz))
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


# Gesture codes of the driver's Gesture message (the Leap SDK's enums).
GESTURE_TYPES = {'swipe': 1, 'circle': 4, 'screenTap': 5, 'keyTap': 6}
GESTURE_STATES = {'start': 1, 'update': 2, 'stop': 3}

# Recognizer events with a driver counterpart: both circle directions are its circle.
# fold / unfold, hand_found / hand_lost and the held poses have none.
EVENT_GESTURE_TYPES = {'circle_cw': GESTURE_TYPES['circle'],
                       'circle_ccw': GESTURE_TYPES['circle']}


MAX_DURATION_US = 2 ** 63 - 1


def _int32(x):
    return ((int(x) + 2 ** 31) % 2 ** 32) - 2 ** 31


def _sdk_gesture(g):
    """DriverGesture from a recorded SDK gesture dict (LeapJS: type, state, id, duration in
    us, pointableIds); None for a type the driver does not have."""
    # A recording's fields may be any JSON: a list as a dict key raised, and ended the source.
    kind, state = g.get('type'), g.get('state')
    gtype = GESTURE_TYPES.get(kind) if isinstance(kind, str) else None
    if gtype is None:
        return None
    msg = DriverGesture()
    msg.lmc_gesture_id = _int32(g.get('id', 0)) if isinstance(g.get('id'), int) else 0
    msg.gesture_type = gtype
    msg.gesture_state = GESTURE_STATES.get(state, -1) if isinstance(state, str) else -1
    msg.is_valid = msg.gesture_state != -1
    duration = g.get('duration', 0)
    if (isinstance(duration, bool) or not isinstance(duration, (int, float)) or duration < 0
            or (isinstance(duration, float) and not math.isfinite(duration))):
        duration = 0
    # Within int64 microseconds (292,000 years): beyond, serialising it ended the source.
    duration = int(min(duration, MAX_DURATION_US))
    msg.duration_us = duration
    msg.duration_s = duration * 1e-6
    ids = g.get('pointableIds')
    msg.pointable_ids = [_int32(i) for i in ids if isinstance(i, int)] if isinstance(ids, list) \
        else []
    msg.to_string = 'Gesture id:%d type:%s state:%s' % (msg.lmc_gesture_id, kind, state)
    return msg


def _bone_widths(widths):
    """Four bone widths (mm) from a source's bone_widths; 0 (unmeasured) for a missing one
    or one beyond skeleton.MAX_SIZE."""
    try:
        widths = list(() if widths is None else widths)[:4]
    except TypeError:
        widths = []
    widths += [None] * (4 - len(widths))
    return tuple(skeleton.bounded_size(w) or 0.0 for w in widths)


class DriverHumanBuilder:
    """Frames + HandStates -> the leap_motion driver's Human (DriverHuman), metres and
    radians, frame leap_hands. Stateful across frames: each hand's time_visible, the frame
    rate, and ids for the recognizer's gestures.

    Filled from every source: palm centre, velocity, normal, direction, roll / pitch / yaw,
    grab / pinch strength, confidence, time_visible, the fingers' bones (skeleton), the
    recognizer's circles as circle gestures. Filled only where the frames carry them: the
    SDK's swipe, key tap, screen tap and circle gestures (recordings), palm_width,
    sphere_radius, sphere_center, finger and bone widths (0 / empty otherwise), the
    metacarpal's base, the carpal joint (the Leap SDKs, LeapJS recordings; otherwise the
    bone starts at the knuckle, length 0), and the SDK's own time_visible (otherwise
    counted here from when the hand was found). Left empty (no source's frames have them):
    the arm, bone orientations (identity)."""

    def __init__(self, frame_id=LEAP_FRAME):
        self.frame_id = frame_id
        self._found_at = {}
        self._last_stamp = None
        self._fps = 0.0
        self._gesture_ids = 0

    def reset(self):
        """Forget each hand's time found and the frame rate, when frames stop coming through
        (nobody subscribes): a hand that left and came back meanwhile is new, and the rate
        does not average over the gap. Gesture ids keep counting (they stay unique)."""
        self._found_at.clear()
        self._last_stamp = None
        self._fps = 0.0

    def _rate(self, stamp):
        last, self._last_stamp = self._last_stamp, stamp
        if last is not None and stamp > last:
            fps = 1.0 / (stamp - last)
            self._fps = fps if self._fps == 0.0 else 0.9 * self._fps + 0.1 * fps

    @staticmethod
    def _fingers(header, hand_id, joints, fingers=(), carpals=None):
        """Five DriverFingers from (5, 4, 3) joints in mm (mcp, pip, dip, tip) and (5, 3)
        carpals (skeleton.hand_carpals; None: each metacarpal has length 0); widths from
        `fingers` (frame.Finger) where the source measured them."""
        starts, ends = skeleton.bone_ends(joints, carpals)
        lengths = (np.linalg.norm(ends - starts, axis=2) * MM).tolist()
        centers = ((starts + ends) * (MM / 2.0)).tolist()
        starts, ends = (starts * MM).tolist(), (ends * MM).tolist()
        out = []
        for i in range(5):
            f = DriverFinger(header=header, type=i)
            f.lmc_finger_id = _int32(hand_id * 10 + i)
            source = fingers[i] if i < len(fingers) else None
            width = skeleton.bounded_size(getattr(source, 'width', None))
            if width is not None:
                f.width = width * MM
            bone_widths = _bone_widths(getattr(source, 'bone_widths', None))
            for b in range(4):
                bone = DriverBone(header=header, type=b, length=lengths[i][b],
                                  width=bone_widths[b] * MM, center=centers[i][b])
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
        """Fill msg from the state; points: (26, 3) mm, the palm centre, each finger's mcp,
        pip, dip, tip, then each finger's carpal joint (skeleton.hand_carpals) (or (1, 3): the
        palm only, when the source tracks no joints)."""
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
        # Sizes within skeleton's bounds, whatever the source (a corrupt 1e300 is no float32:
        # it ended the sender); beyond, unmeasured.
        palm_width, radius = skeleton.bounded_size(hand.palm_width), skeleton.bounded_size(hand.sphere_radius)
        center = skeleton.bounded_point(hand.sphere_center)
        if palm_width is not None:
            msg.palm_width = palm_width * MM
        if radius is not None:
            msg.sphere_radius = radius * MM
        if center is not None:
            msg.sphere_center = [float(x) * MM for x in center]
        if len(points) > 1:
            msg.finger_list = self._fingers(header, hand.id, points[1:21].reshape(5, 4, 3),
                                            hand.fingers, points[21:26])
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

    def human_msgs(self, frame, states, raw=True, lowpass=None):
        """(raw, filtered) DriverHumans of one frame; states: side -> HandState (a
        LeapInterface listener's). raw=False leaves the raw one out (None); `lowpass`
        (lowpass.LowPass, one key per side) makes the filtered one, as the driver's filter
        node does: the palm centre and every joint, carpal joints too, low-passed (else
        None). A side missing from `states`, or not present in its state, is an absent hand."""
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
            visible = skeleton.bounded_time(hand.time_visible)
            if visible is not None:
                # The tracker's own count where the source measures it (the driver passes the
                # SDK's); kept as the time found, so a frame without one goes on from it.
                self._found_at[side] = state.timestamp - visible
            found = self._found_at.setdefault(side, state.timestamp)
            time_visible = max(state.timestamp - found, 0.0)
            gestures = self._gestures(frame, hand, state)
            joints = skeleton.hand_joints(hand)
            points = np.asarray(state.palm_position, dtype=float).reshape(1, 3)
            if joints is not None:
                # Unmeasured carpal joints are the knuckles: filtered alike, length 0 still.
                points = np.concatenate([points, joints.reshape(20, 3),
                                         skeleton.hand_carpals(hand, joints)])
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
    fed its leapros): Leap axes, millimetres, degrees; the angles as to_leapros's
    (classic_ypr). A frame without the hand gives a message with only the header set."""
    msg = _header(leap(), state, frame_id)
    if not state.present:
        return msg
    msg.hand_direction = list(state.direction)
    msg.hand_normal = list(state.palm_normal)
    msg.hand_palm_pos = list(state.palm_position)
    msg.hand_yaw, msg.hand_pitch, msg.hand_roll = classic_ypr(state.palm_normal, state.direction)
    return msg
