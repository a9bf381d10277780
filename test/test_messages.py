"""The wire formats: the original messages and ardrone_autonomy's keep their MD5 sums."""
from leap_teleop.msg import (
    GestureEvent,
    Hand,
    Navdata,
    leapcobotleft,
    leapcobotright,
    leapros,
    navdata_altitude,
    vector21,
    vector31,
)
from leap_teleop.srv import CamSelect, FlightAnim, LedAnim, RecordEnable


def test_original_and_driver_md5_sums():
    assert leapcobotright._md5sum == '94b2619f50143aa1e3cbb0c0a4e13ad5'
    assert leapcobotleft._md5sum == 'c8e1001e2314fcf4a06c83cc02625a74'
    assert Navdata._md5sum == 'e1169f766234363125ac62c9a3f87eeb'
    assert FlightAnim._md5sum == 'b67c0059d7339761bcde13f61a58763f'
    assert leapros._md5sum == 'e37447f7532c765d6c587f418fd5dd03'   # ros-drivers leap_motion's


def test_leapros_md5_computed_by_genmsg_from_the_msg_file():
    # Not only the generated class: the .msg file itself hashes to the classic sum.
    import os

    import genmsg.gentools
    import genmsg.msg_loader
    here = os.path.dirname(os.path.abspath(__file__))
    ctx = genmsg.msg_loader.MsgContext.create_default()
    spec = genmsg.msg_loader.load_msg_from_file(
        ctx, os.path.join(here, '..', 'msg', 'leapros.msg'), 'leap_motion/leapros')
    search = {pkg: [os.path.join('/usr/share', pkg, 'msg')] for pkg in ('std_msgs', 'geometry_msgs')}
    genmsg.msg_loader.load_depends(ctx, spec, search)
    assert genmsg.gentools.compute_md5(ctx, spec) == 'e37447f7532c765d6c587f418fd5dd03'


def test_the_drivers_other_services_and_navdata_altitude_md5_sums():
    # ardrone_autonomy's generated code carries these sums (service, request, response).
    assert CamSelect._md5sum == 'bbeb5212f8ee1d6da7ff0d1169124280'
    assert CamSelect._request_class._md5sum == 'c27320df100593b008f1bb2e1302dbb6'
    assert LedAnim._md5sum == '0447d1620f8ba70a5b1fc2d89e406549'
    assert LedAnim._request_class._md5sum == '23392fc8200b12a3585ff6a32d597821'
    assert RecordEnable._md5sum == '29d58f387352c15c4e4f5763022ae875'
    assert RecordEnable._request_class._md5sum == '8c1211af706069c994c06e00eb59ac9e'
    for srv in (CamSelect, LedAnim, RecordEnable, FlightAnim):
        assert srv._response_class._md5sum == 'eb13ac1f1354ccecb7941ee8fa2192e8'
    assert navdata_altitude._md5sum == 'f0fd1fd20697e6083c6bc3a308a260dc'
    assert vector31._md5sum == 'cc153912f1453b708d221682bc23d9ac'
    assert vector21._md5sum == 'ff8d7d66dd3e4b731ef14a45d38888b6'


def test_rich_messages_have_documented_fields():
    hand = Hand()
    assert len(hand.finger_extended) == 5 and len(hand.finger_tips) == 5
    assert (Hand.SIDE_RIGHT, Hand.SIDE_LEFT) == (GestureEvent.SIDE_RIGHT, GestureEvent.SIDE_LEFT)
    assert set(GestureEvent.__slots__) >= {'header', 'side', 'gesture', 'active', 'value'}


# The leap_motion driver's current messages (its generated code carries these sums), under
# leap_teleop's names: the Driver* prefix keeps its Hand apart from leap_teleop's Hand.
DRIVER_MD5 = {'DriverHuman': '2817a017ab58b244566892058c4f6e6d',
              'DriverHand': '9054fd3f5821eae3259c31fe94fd08a4',
              'DriverFinger': 'c62c3b47717473d8242b45f476fc55c7',
              'DriverBone': 'ce39afad61bdb16ab802b0100be50795',
              'DriverGesture': 'a3bf4fe2d0e707244a5a679250ea8eba',
              'DriverArm': 'b93012a87e6395b9975695d8d7a942db',
              'leap': '3e9a0dc7fd1a98f1d7489e9011c78807'}


def test_the_drivers_human_types_and_old_leap_md5_sums():
    import leap_teleop.msg as msgs
    for name, md5 in DRIVER_MD5.items():
        assert getattr(msgs, name)._md5sum == md5, name


def test_driver_types_md5_computed_by_genmsg_from_the_msg_files():
    # The .msg files themselves hash to the sums, not only the generated classes.
    import os

    import genmsg.gentools
    import genmsg.msg_loader
    here = os.path.dirname(os.path.abspath(__file__))
    ctx = genmsg.msg_loader.MsgContext.create_default()
    search = {pkg: [os.path.join('/usr/share', pkg, 'msg')]
              for pkg in ('std_msgs', 'geometry_msgs')}
    search['leap_teleop'] = [os.path.join(here, '..', 'msg')]
    for name, md5 in DRIVER_MD5.items():
        spec = genmsg.msg_loader.load_msg_by_type(ctx, 'leap_teleop/' + name, search)
        genmsg.msg_loader.load_depends(ctx, spec, search)
        assert genmsg.gentools.compute_md5(ctx, spec) == md5, name


def test_the_projects_hand_is_not_the_drivers():
    from leap_teleop.msg import DriverHand
    assert Hand._type == 'leap_teleop/Hand' and DriverHand._type == 'leap_teleop/DriverHand'
    assert Hand._md5sum != DriverHand._md5sum
