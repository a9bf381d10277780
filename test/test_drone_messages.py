"""The AR.Drone driver's messages ardrone_sim publishes, built from a DroneReading."""
import math

import numpy as np
import rospy

from leap_teleop.drone import cameras
from leap_teleop.drone.sim_runner import DroneReading, sensor_readings
from leap_teleop.ros.ardrone_interface import NAVDATA_ALTITUDE_TAG
from leap_teleop.ros.drone_conversions import DroneMessages
from leap_teleop.ros.sensor_conversions import camera_info_msg, rgb_image_msg, transform_msg

NAV = {'state': 3, 'batteryPercent': 80.0, 'rotX': 1.0, 'rotY': -2.0, 'rotZ': 90.0,
       'altd': 1500, 'vx': 500.0, 'vy': -250.0, 'vz': 100.0, 'ax': 0.1, 'ay': 0.0, 'az': 1.0,
       'tm': 2.5e6}
YAW_90 = (0.0, 0.0, math.sqrt(0.5), math.sqrt(0.5))


def reading():
    nav = dict(NAV, **sensor_readings(NAV, 1.5))
    return DroneReading(2.5, nav, (1.0, 2.0, 1.5), YAW_90, (0.0, 0.1, 0.2), 1.5, '')


def test_state_messages_share_stamp_frames_and_the_drivers_units():
    stamp = rospy.Time(12, 500)
    m = DroneMessages(reading(), stamp, 'd/base', 'd/odom')
    assert m.navdata.header.stamp == stamp and m.navdata.header.frame_id == 'd/base'
    assert (m.navdata.rotZ, m.navdata.altd, m.navdata.magY, m.navdata.temp) == (90.0, 1500, -200, 25)
    assert (m.mag.vector.x, m.mag.vector.y, m.mag.vector.z) == (0.0, -200.0, -400.0)
    assert m.mag.header.frame_id == 'd/base'
    a = m.imu.linear_acceleration
    assert (a.x, a.z) == (0.1 * 9.8, 9.8) and m.imu.angular_velocity.z == 0.2
    o = m.odometry.pose.pose
    assert (o.position.x, o.position.y, o.position.z) == (1.0, 2.0, 1.5)
    assert (o.orientation.z, o.orientation.w) == YAW_90[2:]
    assert (m.odometry.header.frame_id, m.odometry.child_frame_id) == ('d/odom', 'd/base')
    v = m.odometry.twist.twist.linear
    assert (v.x, v.y, v.z) == (0.5, -0.25, 0.1)                # mm/s -> m/s
    t = m.transform
    assert (t.header.frame_id, t.child_frame_id) == ('d/odom', 'd/base')
    assert t.transform.translation.z == 1.5 and t.transform.rotation.w == YAW_90[3]
    assert m.navdata_altitude is None


def test_navdata_altitude_only_when_asked_for():
    m = DroneMessages(reading(), rospy.Time(3), 'base', 'odom', with_altitude=True)
    alt = m.navdata_altitude
    assert alt.header.stamp == rospy.Time(3) and alt.tag == NAVDATA_ALTITUDE_TAG
    assert alt.altitude_vision == alt.altitude_raw == alt.altitude_ref == 1500
    assert (alt.drone_time, alt.obs_alt, alt.obs_x.y, alt.est_vb.x) == (2.5, 1.5, 0.1, 0.1)


def test_transform_camera_info_and_image():
    t = transform_msg('a', 'b', (1.0, 2.0, 3.0), (0.0, 0.0, 0.0, 1.0), rospy.Time(1))
    assert (t.header.frame_id, t.child_frame_id, t.transform.translation.y) == ('a', 'b', 2.0)
    info = camera_info_msg(cameras.FRONT, 'front_optical')
    K, _ = cameras.FRONT.intrinsics()
    assert (info.width, info.height, info.header.frame_id) == (640, 360, 'front_optical')
    assert tuple(info.K) == K and list(info.D) == [0.0] * 5
    rgb = np.zeros((4, 6, 3), np.uint8)
    rgb[1, 2] = (10, 20, 30)
    img = rgb_image_msg(rgb, rospy.Time(5), 'cam')
    assert (img.height, img.width, img.step, img.encoding) == (4, 6, 18, 'rgb8')
    assert img.data[(1 * 6 + 2) * 3:(1 * 6 + 2) * 3 + 3] == bytes((10, 20, 30))
