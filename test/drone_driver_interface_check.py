#!/usr/bin/env python3
"""rostest node: the simulator offers the driver's endpoints, and a client written against
the driver's types uses each of them (in the namespace uav, TF frames prefixed uav/)."""
import os
import sys
import time
import unittest

import rosgraph
import rospy
import rosservice
import rostest
from geometry_msgs.msg import Vector3Stamped
from sensor_msgs.msg import CameraInfo, Image
from sensor_msgs.srv import SetCameraInfo
from std_msgs.msg import Empty
from std_srvs.srv import Empty as EmptySrv
from std_srvs.srv import Trigger

from leap_teleop.ros.ardrone_interface import DRIVER_ENDPOINTS, OPTIONAL_ENDPOINTS, PUBLISHER, SERVICE

import ardrone_driver_types as driver
from check_helpers import limit, read_limits

NODE = '/uav/ardrone_sim'
Navdata = driver.message('Navdata')
NavdataAltitude = driver.message('navdata_altitude', ('vector31', 'vector21'))
FlightAnim, CamSelect = driver.service('FlightAnim'), driver.service('CamSelect')
LedAnim, RecordEnable = driver.service('LedAnim'), driver.service('RecordEnable')
LIMITS = {
    'startup_timeout_s': limit('wait this long for the simulator\'s services and images',
                               's', gt=0),
    'message_timeout_s': limit('wait this long for any one message', 's', gt=0),
    'endpoints_offered': limit('endpoints the running node offers', kind='int', ge=0),
    'driver_endpoints': limit('endpoints of the driver\'s default table', kind='int', ge=0),
    'front_size': limit('front camera width, height', 'px', kind='list', item='int', length=2),
    'bottom_size': limit('bottom camera width, height', 'px', kind='list', item='int',
                         length=2),
    'front_focal_px': limit('front camera focal length (K[0]) ...', 'px', gt=0),
    'focal_tolerance_px': limit('... give or take this much', 'px', gt=0),
    'switch_timeout_s': limit('the active camera (and a new calibration) shows within this',
                              's', gt=0),
    'landed_max_altitude_mm': limit('landed: navdata_altitude altitude_raw below this', 'mm'),
    'takeoff_timeout_s': limit('hovering within this after the takeoff', 's', gt=0),
    'hover_altitude_mm': limit('hovering: altitude_raw this ...', 'mm', gt=0),
    'altitude_tolerance_mm': limit('... give or take this much', 'mm', gt=0),
    'min_navdata_gaps': limit('more navdata arrivals than this around a snapshot ...',
                              kind='int', ge=0),
    'max_navdata_gap_s': limit('... none further apart than this', 's', gt=0),
}


class DriverInterfaceCheck(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.lim = read_limits(LIMITS)
        # The driver-typed client's first step: wait for the flat-trim service.
        rospy.wait_for_service('ardrone/flattrim', cls.lim.startup_timeout_s)
        rospy.wait_for_message('ardrone/front/image_raw', Image, cls.lim.startup_timeout_s)

    def wait(self, topic, kind):
        return rospy.wait_for_message(topic, kind, self.lim.message_timeout_s)

    def test_1_endpoint_table_matches_the_running_node(self):
        master = rosgraph.Master(rospy.get_name())
        pubs, subs, services = master.getSystemState()
        pubs, subs = dict(pubs), dict(subs)
        services = dict(services)
        types = dict(master.getTopicTypes())
        offered = 0
        for kind, name, msg_type, _ in DRIVER_ENDPOINTS + OPTIONAL_ENDPOINTS:
            full = rospy.resolve_name(name)
            if kind == SERVICE:
                self.assertIn(NODE, services.get(full, []), full)
                self.assertEqual(rosservice.get_service_type(full), msg_type, full)
            else:
                table = pubs if kind == PUBLISHER else subs
                self.assertIn(NODE, table.get(full, []), '%s %s' % (kind, full))
                self.assertEqual(types[full], msg_type, full)
            offered += 1
        self.assertEqual(offered, self.lim.endpoints_offered)
        self.assertEqual(len(DRIVER_ENDPOINTS), self.lim.driver_endpoints)

    def test_2_cameras_and_the_active_channel(self):
        (fw, fh), (bw, bh) = self.lim.front_size, self.lim.bottom_size
        front = self.wait('ardrone/front/image_raw', Image)
        self.assertEqual((front.width, front.height, front.encoding), (fw, fh, 'rgb8'))
        self.assertEqual(front.header.frame_id, 'uav/ardrone_base_frontcam')
        self.assertEqual(len(front.data), fw * fh * 3)
        bottom = self.wait('ardrone/bottom/image_raw', Image)
        self.assertEqual((bottom.width, bottom.height), (bw, bh))
        info = self.wait('ardrone/front/camera_info', CameraInfo)
        self.assertEqual((info.width, info.height), (fw, fh))
        self.assertAlmostEqual(info.K[0], self.lim.front_focal_px,
                               delta=self.lim.focal_tolerance_px)
        self.assertEqual(self.wait('ardrone/bottom/camera_info', CameraInfo).width, bw)
        self.assertEqual(self.wait('ardrone/image_raw', Image).width, fw)    # front at start
        self.assertEqual(self.wait('ardrone/camera_info', CameraInfo).width, fw)
        rospy.ServiceProxy('ardrone/togglecam', EmptySrv)()
        self.assertTrue(self._active_becomes(bw))
        self.assertTrue(rospy.ServiceProxy('ardrone/setcamchannel', CamSelect)(channel=0).result)
        self.assertTrue(self._active_becomes(fw))

    def _active_becomes(self, width):
        deadline = rospy.get_time() + self.lim.switch_timeout_s
        while rospy.get_time() < deadline:
            if self.wait('ardrone/image_raw', Image).width == width:
                return True
        return False

    def test_3_set_camera_info(self):
        setter = rospy.ServiceProxy('ardrone/bottom/set_camera_info', SetCameraInfo)
        info = self.wait('ardrone/bottom/camera_info', CameraInfo)
        info.K = list(info.K)
        info.K[0] = info.K[4] = 300.0
        self.assertTrue(setter(camera_info=info).success)
        deadline = rospy.get_time() + self.lim.switch_timeout_s
        while rospy.get_time() < deadline:
            if self.wait('ardrone/bottom/camera_info', CameraInfo).K[0] == 300.0:
                break
        else:
            self.fail('the new calibration was not published')
        info.width = 640                      # 640 x 240: neither camera's size
        front = rospy.ServiceProxy('ardrone/front/set_camera_info', SetCameraInfo)
        for service in (setter, front):
            res = service(camera_info=info)
            self.assertFalse(res.success)
            self.assertIn('got 640x240', res.status_message)

    def test_4_navdata_mag_altitude_leds_record_flat_trim_flight(self):
        nav = self.wait('ardrone/navdata', Navdata)
        self.assertEqual(nav.state, 2)
        mag = self.wait('ardrone/mag', Vector3Stamped)
        self.assertEqual(mag.header.frame_id, 'uav/ardrone_base_link')
        self.assertLess(mag.vector.z, 0)
        alt = self.wait('ardrone/navdata_altitude', NavdataAltitude)
        self.assertEqual((alt.tag, alt.size), (10, 56))
        self.assertLess(alt.altitude_raw, self.lim.landed_max_altitude_mm)
        self.assertTrue(rospy.ServiceProxy('ardrone/setledanimation', LedAnim)(
            type=3, freq=2.0, duration=2).result)
        self.assertTrue(rospy.ServiceProxy('ardrone/setrecord', RecordEnable)(enable=True).result)
        rospy.ServiceProxy('ardrone/flattrim', EmptySrv)()
        # The driver answers true even where the firmware ignores the animation (landed).
        anim = rospy.ServiceProxy('ardrone/setflightanimation', FlightAnim)
        self.assertTrue(anim(type=19, duration=0).result)
        rospy.sleep(0.5)
        self.assertEqual(self.wait('ardrone/navdata', Navdata).state, 2)
        takeoff = rospy.Publisher('ardrone/takeoff', Empty, queue_size=1, latch=True)
        takeoff.publish(Empty())
        deadline = rospy.get_time() + self.lim.takeoff_timeout_s
        while rospy.get_time() < deadline and self.wait('ardrone/navdata', Navdata).state != 4:
            pass
        self.assertEqual(self.wait('ardrone/navdata', Navdata).state, 4)
        alt = self.wait('ardrone/navdata_altitude', NavdataAltitude)
        self.assertAlmostEqual(alt.altitude_raw, self.lim.hover_altitude_mm,
                               delta=self.lim.altitude_tolerance_mm)
        rospy.ServiceProxy('ardrone/flattrim', EmptySrv)()     # aloft: answered, ignored
        self.assertIn(self.wait('ardrone/navdata', Navdata).state, (3, 4))

    def test_5_snapshot_keeps_navdata_flowing(self):
        # The simulator's own ardrone/snapshot: the picture is drawn outside the physics
        # loop, so navdata never goes stale (the pilot hovers / lands after 0.5 s).
        arrivals = []
        sub = rospy.Subscriber('ardrone/navdata', Navdata,
                               lambda _: arrivals.append(time.monotonic()))
        try:
            self.wait('ardrone/navdata', Navdata)
            snapshot = rospy.ServiceProxy('ardrone/snapshot', Trigger)
            for _ in range(2):        # the first one also starts the renderer process
                t0 = time.monotonic()
                res = snapshot()
                t1 = time.monotonic()
                self.assertTrue(res.success, res.message)
                with open(res.message, 'rb') as f:
                    self.assertEqual(f.read(8), b'\x89PNG\r\n\x1a\n')
                os.remove(res.message)
                rospy.sleep(0.3)
                during = [t for t in arrivals if t0 - 0.3 <= t <= t1 + 0.3]
                gaps = [b - a for a, b in zip(during, during[1:])]
                rospy.loginfo('snapshot in %.2f s, longest navdata gap %.3f s', t1 - t0,
                              max(gaps, default=float('nan')))
                self.assertTrue(len(gaps) > self.lim.min_navdata_gaps
                                and max(gaps) < self.lim.max_navdata_gap_s, (t1 - t0, gaps))
        finally:
            sub.unregister()


if __name__ == '__main__':
    rospy.init_node('driver_client')
    rostest.rosrun('leap_teleop', 'drone_driver_interface_check', DriverInterfaceCheck, sys.argv)
