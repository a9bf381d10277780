"""The wire formats: the original messages and ardrone_autonomy's keep their MD5 sums."""
from leap_teleop.msg import GestureEvent, Hand, Navdata, leapcobotleft, leapcobotright
from leap_teleop.srv import FlightAnim


def test_original_and_driver_md5_sums():
    assert leapcobotright._md5sum == '94b2619f50143aa1e3cbb0c0a4e13ad5'
    assert leapcobotleft._md5sum == 'c8e1001e2314fcf4a06c83cc02625a74'
    assert Navdata._md5sum == 'e1169f766234363125ac62c9a3f87eeb'
    assert FlightAnim._md5sum == 'b67c0059d7339761bcde13f61a58763f'


def test_rich_messages_have_documented_fields():
    hand = Hand()
    assert len(hand.finger_extended) == 5 and len(hand.finger_tips) == 5
    assert (Hand.SIDE_RIGHT, Hand.SIDE_LEFT) == (GestureEvent.SIDE_RIGHT, GestureEvent.SIDE_LEFT)
    assert set(GestureEvent.__slots__) >= {'header', 'side', 'gesture', 'active', 'value'}
