"""HandState -> leapcobot / Hand / GestureEvent messages."""
import math

import pytest

from leap_teleop.hands.frame import Frame
from leap_teleop.hands.gestures import GestureRecognizer
from leap_teleop.hands.leap_interface import LeapInterface
from leap_teleop.hands.rendered_hand import render_hand
from leap_teleop.msg import Hand, leapcobotleft, leapcobotright
from leap_teleop.ros import drone_conversions, hand_conversions


def per_frame():
    """Single-frame checks: no temporal filtering."""
    return GestureRecognizer(stateless=True)


def states(*hands, ts=1234.5):
    li = LeapInterface(recognizer_factory=per_frame)
    return li.on_frame(Frame(id=42, timestamp=ts, hands=list(hands)))


@pytest.mark.parametrize('side, msg_type', [('right', leapcobotright), ('left', leapcobotleft)])
def test_leapcobot_keeps_original_semantics(side, msg_type):
    s = states(render_hand(side, 'pinch', [12.5, 210.0, -30.0], pinch_value=0.45))[side]
    msg = hand_conversions.to_leapcobot(s)
    assert isinstance(msg, msg_type)
    assert msg.header.stamp.to_sec() == pytest.approx(1234.5)
    assert msg.header.frame_id == 'leap_hands'
    assert getattr(msg, 'is_%s_hand' % side)
    palm = getattr(msg, '%s_hand_palmpos' % side)
    assert (palm.x, palm.y, palm.z) == (12.5, 210.0, -30.0)          # Leap mm, as the original
    assert getattr(msg, '%s_hand_pinch' % side)
    assert getattr(msg, '%s_hand_pinch_value' % side) == pytest.approx(0.45)
    back = hand_conversions.from_leapcobot(msg)
    assert back['side'] == side and back['present'] and back['palmpos'] == (12.5, 210.0, -30.0)
    assert back['pinch_value'] == pytest.approx(0.45)


@pytest.mark.parametrize('side', ['right', 'left'])
def test_a_refilled_leapcobot_serializes_like_a_new_one(side):
    from io import BytesIO

    def wire(msg):
        buf = BytesIO()
        msg.serialize(buf)
        return buf.getvalue()
    reused = hand_conversions.LEAPCOBOT_TYPES[side]()
    poses = [('pinch', [12.5, 210.0, -30.0]), ('fist', [-80.0, 150.0, 40.0]), (None, None),
             ('open', [0.0, 300.0, 0.0])]
    for k, (pose, palm) in enumerate(poses):
        hands = [render_hand(side, pose, palm, pinch_value=0.3)] if pose else []
        s = states(*hands, ts=100.0 + k)[side]
        assert hand_conversions.to_leapcobot(s, msg=reused) is reused
        assert wire(reused) == wire(hand_conversions.to_leapcobot(s))     # nothing left over


def test_absent_hand_gives_an_all_clear_leapcobot():
    msg = hand_conversions.to_leapcobot(states()['left'])
    assert not msg.is_left_hand and not msg.left_hand_fist and msg.left_hand_pinch_value == 0.0


def test_rich_hand_is_in_metres_with_side_and_frame_id():
    s = states(render_hand('left', 'fist', [100.0, 200.0, 50.0]))['left']
    msg = hand_conversions.to_hand(s)
    assert msg.side == Hand.SIDE_LEFT and msg.present and msg.leap_frame_id == 42
    assert (msg.palm_position.x, msg.palm_position.y, msg.palm_position.z) == pytest.approx(
        (0.1, 0.2, 0.05))
    assert msg.fist and not msg.open
    assert len(msg.finger_tips) == 5 and all(abs(t.y - 0.2) < 0.1 for t in msg.finger_tips)


def test_gesture_events_carry_name_side_and_stamp():
    li = LeapInterface()      # the streaming recognizer: events come from transitions
    events = []
    for i in range(10):
        st = li.on_frame(Frame(id=i, timestamp=5.0 + i, hands=[render_hand('right', 'fist', [0, 200, 0])]))
        events += hand_conversions.to_gesture_events(st['right'])
    names = [e.gesture for e in events]
    assert names[0] == 'hand_found' and 'fist' in names
    assert all(e.side == Hand.SIDE_RIGHT for e in events)
    assert events[0].header.stamp.to_sec() == 5.0


def test_leapros_has_the_classic_drivers_units_and_angles():
    hand = render_hand('right', 'open', [12.5, 210.0, -30.0])
    hand.direction = direction = [0.5, 0.5, -0.5 ** 0.5]        # up and to the right
    hand.palm_normal = [-0.5, -0.5, -0.5 ** 0.5]                # at right angles to it
    s = states(hand)['right']
    msg = hand_conversions.to_leapros(s, hand)
    assert msg._type == 'leap_teleop/leapros'
    assert msg.header.stamp.to_sec() == pytest.approx(1234.5)
    assert (msg.palmpos.x, msg.palmpos.y, msg.palmpos.z) == (12.5, 210.0, -30.0)    # mm
    assert (msg.direction.x, msg.direction.y, msg.direction.z) == pytest.approx(direction)
    assert msg.normal.x == pytest.approx(-0.5)
    # (yaw, pitch, roll) in degrees as the classic sender: the Leap SDK's Vector.yaw of the
    # normal (atan2(x, -z)), .pitch (atan2(y, -z)) and .roll (atan2(x, -y)) of the direction.
    a = math.degrees(math.atan(0.5 ** 0.5))                     # 35.26 deg
    assert (msg.ypr.x, msg.ypr.y, msg.ypr.z) == pytest.approx((-a, a, 135.0), abs=1e-9)
    index = hand.fingers[1]
    assert (msg.index_tip.x, msg.index_tip.y, msg.index_tip.z) == pytest.approx(tuple(s.finger_tips[1]))
    assert (msg.index_proximal.x, msg.index_proximal.z) == pytest.approx((index.mcp[0], index.mcp[2]))
    assert msg.index_distal.z == pytest.approx(index.dip[2])
    assert msg.index_intermediate.z == pytest.approx(index.pip[2])
    assert (msg.index_metacarpal.x, msg.index_metacarpal.y, msg.index_metacarpal.z) == (0, 0, 0)


def test_leapros_leaves_a_joint_beyond_any_hands_reach_at_zero():
    # Before: a corrupt recording's 1e30 mm knuckle went out as is, while the tracker drops
    # such a tip and the driver's Human the whole skeleton.
    hand = render_hand('right', 'open', [0.0, 200.0, 0.0])
    hand.fingers[1].mcp = [1e30, 200.0, -20.0]
    hand.fingers[2].dip = [-7e300, 200.0, -60.0]
    hand.fingers[3].pip = [0.0, math.nan, -40.0]
    hand.fingers[4].pip = [0.0, 2000.0, -2000.0]                # at the bound: kept
    msg = hand_conversions.to_leapros(states(hand)['right'], hand)
    for name in ('index_proximal', 'middle_distal', 'ring_intermediate'):
        p = getattr(msg, name)
        assert (p.x, p.y, p.z) == (0, 0, 0), name
    assert (msg.pinky_intermediate.y, msg.pinky_intermediate.z) == (2000.0, -2000.0)
    assert msg.index_intermediate.z == pytest.approx(hand.fingers[1].pip[2])     # the rest stays
    assert msg.middle_proximal.z == pytest.approx(hand.fingers[2].mcp[2])


def test_leapros_metacarpal_is_the_carpal_joint_where_the_source_measures_it():
    # The classic sender filled <finger>_metacarpal with bone(TYPE_METACARPAL).prev_joint,
    # the carpal joint (mm); it was always 0 here, the Leap sources included.
    hand = render_hand('right', 'open', [12.5, 210.0, -30.0])
    carpals = [[-40.0 + 20.0 * i, 150.0, 40.0] for i in range(5)]
    for f, c in zip(hand.fingers, carpals):
        f.carpal = c
    hand.fingers[0].carpal = None                               # unmeasured: 0, as before
    hand.fingers[2].carpal = [0.0, 2001.0, 0.0]                 # beyond any hand: 0
    hand.fingers[3].carpal = [math.nan, 150.0, 40.0]
    msg = hand_conversions.to_leapros(states(hand)['right'], hand)
    got = [(p.x, p.y, p.z) for p in (getattr(msg, name + '_metacarpal') for name in
                                     ('thumb', 'index', 'middle', 'ring', 'pinky'))]
    assert got == [(0, 0, 0), tuple(carpals[1]), (0, 0, 0), (0, 0, 0), tuple(carpals[4])]
    assert msg.index_proximal.z == pytest.approx(hand.fingers[1].mcp[2])      # the rest stays


def test_leapros_of_an_absent_hand_is_all_zero_but_the_header():
    msg = hand_conversions.to_leapros(states()['right'])
    assert msg.header.stamp.to_sec() == pytest.approx(1234.5)
    assert (msg.palmpos.x, msg.ypr.y, msg.thumb_tip.z, msg.direction.z) == (0, 0, 0, 0)


def test_a_hand_message_becomes_the_pilots_input_and_a_twist_its_cmd_vel():
    import rospy
    msg = Hand(present=True)
    msg.header.stamp = rospy.Time(12, 500000000)
    msg.palm_position.x, msg.palm_position.y, msg.palm_position.z = 0.01, 0.2, -0.03
    msg.palm_normal.y, msg.direction.z = -1.0, -1.0
    got = drone_conversions.pilot_input(msg)
    assert got.present and got.palm == (0.01, 0.2, -0.03) and got.stamp == 12.5
    assert got.normal == (0.0, -1.0, 0.0) and got.direction == (0.0, 0.0, -1.0)
    t = drone_conversions.twist_msg((0.1, 0.2, 0.3, 0.0, 0.0, -0.5))
    assert (t.linear.x, t.linear.y, t.linear.z, t.angular.z) == (0.1, 0.2, 0.3, -0.5)


@pytest.mark.parametrize('lead, stamped', [(0.0, False), (0.008, True)])
def test_arm_trajectories_start_at_their_stamp_only_with_a_command_lead(monkeypatch, lead, stamped):
    # A command_lead is what lets a command that arrives within it continue the last one;
    # it did nothing while every trajectory went out stamped 0.
    import rospy

    from leap_teleop.ros import arm_topics
    from leap_teleop.ur10.teleop import ArmCommand

    sent = []

    class Publisher:
        def __init__(self, name, *args, **kwargs):
            self.name = name

        def publish(self, msg):
            sent.append((self.name, msg))
    monkeypatch.setattr(rospy, 'Publisher', Publisher)
    monkeypatch.setattr(rospy, 'get_time', lambda: 100.0)
    topics = arm_topics.ArmCommandTopics('ur10_1/')
    topics.send(ArmCommand(points=[(0.024, [0.0] * 6, [0.0] * 6)], stamp=100.0 + lead), stamped)
    (name, msg), = sent
    assert name == 'arm_controller/command'
    assert msg.header.stamp.to_sec() == (pytest.approx(100.008) if stamped else 0.0)
