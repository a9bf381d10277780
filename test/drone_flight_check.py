#!/usr/bin/env python3
"""rostest node: the replayed gesture session takes off, flies ~1 m forward, flips, lands."""
import sys
import unittest

import rospy
import rostest
from nav_msgs.msg import Odometry

from leap_teleop.msg import Navdata


class DroneFlight(unittest.TestCase):
    def test_takeoff_forward_flip_land(self):
        states, odom = [], []

        def on_nav(msg):
            if not states or states[-1] != msg.state:
                states.append(msg.state)

        rospy.Subscriber('ardrone/navdata', Navdata, on_nav, queue_size=100)
        rospy.Subscriber('ardrone/odometry', Odometry, odom.append, queue_size=100)
        deadline = rospy.get_time() + rospy.get_param('~timeout', 50.0)
        while rospy.get_time() < deadline and not rospy.is_shutdown():
            if 9 in states and states[-1] == 2 and len(states) > 2:
                break
            rospy.sleep(0.1)
        rospy.sleep(0.5)
        rospy.loginfo('navdata states: %s', states)
        self.assertEqual(states[0], 2, states)                      # landed at start
        order = [s for s in states if s in (6, 9, 8, 2)]
        self.assertEqual(order, [2, 6, 9, 8, 2], 'state sequence %s' % states)
        self.assertIn(4, states)                                     # hovered after takeoff
        self.assertTrue(odom, 'no odometry')
        p = odom[-1].pose.pose.position
        rospy.loginfo('final position x %.2f y %.2f z %.2f', p.x, p.y, p.z)
        self.assertAlmostEqual(p.x, 1.0, delta=0.35)                 # ~1 m forward
        self.assertLess(abs(p.y), 0.35)
        self.assertLess(p.z, 0.03)                                   # on the ground


if __name__ == '__main__':
    rospy.init_node('drone_flight_check')
    rostest.rosrun('leap_teleop', 'drone_flight_check', DroneFlight, sys.argv)
