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

from leap_teleop.msg import Navdata

DRONES = ('drone1', 'drone2')


class DualDrones(unittest.TestCase):
    def test_each_drone_follows_its_own_hand(self):
        states = {d: [] for d in DRONES}
        odom = {d: [] for d in DRONES}

        def on_nav(drone, msg):
            if not states[drone] or states[drone][-1] != msg.state:
                states[drone].append(msg.state)

        for d in DRONES:
            rospy.Subscriber('/%s/ardrone/navdata' % d, Navdata,
                             lambda m, d=d: on_nav(d, m), queue_size=100)
            rospy.Subscriber('/%s/ardrone/odometry' % d, Odometry, odom[d].append,
                             queue_size=100)
        images = {d: rospy.wait_for_message('/%s/ardrone/front/image_raw' % d, Image, 60)
                  for d in DRONES}
        deadline = rospy.get_time() + rospy.get_param('~timeout', 60.0)
        while rospy.get_time() < deadline and not rospy.is_shutdown():
            if all(len(s) > 2 and s[-1] == 2 for s in states.values()):
                break
            rospy.sleep(0.1)
        rospy.sleep(0.5)
        rospy.loginfo('navdata states: %s', states)
        key = {d: [s for s in states[d] if s in (6, 9, 8, 2)] for d in DRONES}
        self.assertEqual(key['drone1'], [2, 6, 9, 8, 2], states)
        self.assertEqual(key['drone2'], [2, 6, 8, 2], states)       # never flipped
        x = {}
        for d in DRONES:
            self.assertTrue(odom[d], 'no odometry from %s' % d)
            last = odom[d][-1]
            self.assertEqual(last.header.frame_id, '%s/odom' % d)
            self.assertEqual(last.child_frame_id, '%s/ardrone_base_link' % d)
            self.assertEqual(images[d].header.frame_id, '%s/ardrone_base_frontcam' % d)
            self.assertLess(last.pose.pose.position.z, 0.03)
            x[d] = last.pose.pose.position.x
        rospy.loginfo('final x: %s', x)
        self.assertAlmostEqual(x['drone1'], 1.0, delta=0.35)
        self.assertGreater(x['drone2'], 0.15)
        self.assertLess(x['drone2'], x['drone1'] - 0.25)


if __name__ == '__main__':
    rospy.init_node('drone_dual_check')
    rostest.rosrun('leap_teleop', 'drone_dual_check', DualDrones, sys.argv)
