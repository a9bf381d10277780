"""HandState -> ROS messages. One function per message type, both hands alike."""
import math

import rospy
from geometry_msgs.msg import Point, Vector3

from leap_teleop.frame import FINGER_NAMES
from leap_teleop.msg import GestureEvent, Hand, leapcobotleft, leapcobotright, leapros

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
    (proximal = knuckle, intermediate, distal) from `hand` (the frame's frame.Hand) where
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
