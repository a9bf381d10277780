#!/usr/bin/env python3
"""rostest node: the replayed gesture session takes off, flies ~1 m forward, flips, lands."""
import sys
import unittest

import rospy
import rostest
from nav_msgs.msg import Odometry

from check_helpers import NavdataStates, limit, navdata_code, navdata_codes, read_limits, state_limit, states_limit

LIMITS = {
    'timeout_s': limit('wait this long for the flight to end', 's', gt=0),
    'key_states': states_limit('the flight, in these states (others left out)'),
    'hover_state': state_limit('a state seen after the takeoff'),
    'forward_m': limit('the drone lands this far forward (odometry x) ...', 'm'),
    'forward_tolerance_m': limit('... give or take this much', 'm', gt=0),
    'max_sideways_m': limit('|y| where it lands', 'm', gt=0),
    'max_landed_z_m': limit('on the ground: z below this', 'm', gt=0),
}


class DroneFlight(unittest.TestCase):
    def test_takeoff_forward_flip_land(self):
        nav, odom = NavdataStates(), []
        rospy.Subscriber('ardrone/odometry', Odometry, odom.append, queue_size=100)
        lim = read_limits(LIMITS)
        key = navdata_codes(lim.key_states)
        deadline = rospy.get_time() + lim.timeout_s
        while rospy.get_time() < deadline and not rospy.is_shutdown():
            states = nav.get()
            if set(key) <= set(states) and states[-1] == key[-1] and len(states) > 2:
                break
            rospy.sleep(0.1)
        rospy.sleep(0.5)
        states = nav.get()
        rospy.loginfo('navdata states: %s', states)
        self.assertEqual(states[0], key[0], states)
        order = [s for s in states if s in key]
        self.assertEqual(order, key, 'state sequence %s' % states)
        self.assertIn(navdata_code(lim.hover_state), states)
        self.assertTrue(odom, 'no odometry')
        p = odom[-1].pose.pose.position
        rospy.loginfo('final position x %.2f y %.2f z %.2f', p.x, p.y, p.z)
        self.assertAlmostEqual(p.x, lim.forward_m, delta=lim.forward_tolerance_m)
        self.assertLess(abs(p.y), lim.max_sideways_m)
        self.assertLess(p.z, lim.max_landed_z_m)


if __name__ == '__main__':
    rospy.init_node('drone_flight_check')
    rostest.rosrun('leap_teleop', 'drone_flight_check', DroneFlight, sys.argv)
