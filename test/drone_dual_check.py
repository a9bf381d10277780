#!/usr/bin/env python3
"""rostest node: two namespaced drones, each following only its own hand. drone1 (right
hand) takes off, flies ~1 m forward, flips and lands; drone2 (left hand) takes off,
flies a shorter hop and lands without a flip. Frames and cameras stay apart."""
import sys
import unittest

import rospy
import rostest
from nav_msgs.msg import Odometry
from sensor_msgs.msg import Image

from check_helpers import NavdataStates, limit, navdata_codes, read_limits, states_limit

DRONES = ('drone1', 'drone2')
LIMITS = {
    'camera_timeout_s': limit('wait this long for each drone\'s first camera image', 's', gt=0),
    'timeout_s': limit('wait this long for both flights to end', 's', gt=0),
    'drone1_states': states_limit('drone1\'s flight in the states of `watched_states`'),
    'drone2_states': states_limit('drone2\'s flight in the states of `watched_states`'),
    'watched_states': states_limit('the states the two sequences are made of'),
    'drone1_forward_m': limit('drone1 lands this far forward (odometry x) ...', 'm'),
    'forward_tolerance_m': limit('... give or take this much', 'm', gt=0),
    'drone2_min_forward_m': limit('drone2 lands further forward than this ...', 'm'),
    'drone2_short_m': limit('... and at least this much short of drone1', 'm'),
    'max_landed_z_m': limit('on the ground: z below this', 'm', gt=0),
}


class DualDrones(unittest.TestCase):
    def test_each_drone_follows_its_own_hand(self):
        nav = {d: NavdataStates('/%s/ardrone/navdata' % d) for d in DRONES}
        odom = {d: [] for d in DRONES}
        for d in DRONES:
            rospy.Subscriber('/%s/ardrone/odometry' % d, Odometry, odom[d].append,
                             queue_size=100)
        lim = read_limits(LIMITS)
        watched = navdata_codes(lim.watched_states)
        want = {'drone1': navdata_codes(lim.drone1_states),
                'drone2': navdata_codes(lim.drone2_states)}
        images = {d: rospy.wait_for_message('/%s/ardrone/front/image_raw' % d, Image,
                                            lim.camera_timeout_s)
                  for d in DRONES}
        deadline = rospy.get_time() + lim.timeout_s
        while rospy.get_time() < deadline and not rospy.is_shutdown():
            states = {d: nav[d].get() for d in DRONES}
            if all(len(states[d]) > 2 and states[d][-1] == want[d][-1] for d in DRONES):
                break
            rospy.sleep(0.1)
        rospy.sleep(0.5)
        states = {d: nav[d].get() for d in DRONES}
        rospy.loginfo('navdata states: %s', states)
        key = {d: [s for s in states[d] if s in watched] for d in DRONES}
        self.assertEqual(key['drone1'], want['drone1'], states)
        self.assertEqual(key['drone2'], want['drone2'], states)
        x = {}
        for d in DRONES:
            self.assertTrue(odom[d], 'no odometry from %s' % d)
            last = odom[d][-1]
            self.assertEqual(last.header.frame_id, '%s/odom' % d)
            self.assertEqual(last.child_frame_id, '%s/ardrone_base_link' % d)
            self.assertEqual(images[d].header.frame_id, '%s/ardrone_base_frontcam' % d)
            self.assertLess(last.pose.pose.position.z, lim.max_landed_z_m)
            x[d] = last.pose.pose.position.x
        rospy.loginfo('final x: %s', x)
        self.assertAlmostEqual(x['drone1'], lim.drone1_forward_m, delta=lim.forward_tolerance_m)
        self.assertGreater(x['drone2'], lim.drone2_min_forward_m)
        self.assertLess(x['drone2'], x['drone1'] - lim.drone2_short_m)


if __name__ == '__main__':
    rospy.init_node('drone_dual_check')
    rostest.rosrun('leap_teleop', 'drone_dual_check', DualDrones, sys.argv)
