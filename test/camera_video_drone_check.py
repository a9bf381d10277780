#!/usr/bin/env python3
"""rostest node: the drone, landed, takes off on the unfold the video source reads in a
real person's clip."""
import os
import sys
import unittest

import rospy
import rostest

from leap_teleop.msg import GestureEvent, Navdata

LANDED, FLYING, HOVERING, TAKING_OFF = 2, 3, 4, 6


class CameraFliesDrone(unittest.TestCase):
    def test_unfold_from_video_takes_off(self):
        video = rospy.get_param('~video')
        self.assertTrue(os.path.exists(video), 'clip %s absent' % video)
        states, gestures = [], []

        def on_nav(msg):
            if not states or states[-1] != msg.state:
                states.append(msg.state)

        rospy.Subscriber('ardrone/navdata', Navdata, on_nav, queue_size=100)
        rospy.Subscriber('leapmotion/gestures', GestureEvent,
                         lambda m: gestures.append(m.gesture), queue_size=1000)
        deadline = rospy.get_time() + 60.0
        while rospy.get_time() < deadline and not rospy.is_shutdown():
            if TAKING_OFF in states and states[-1] in (FLYING, HOVERING):
                break
            rospy.sleep(0.1)
        self.assertTrue(states and states[0] == LANDED, 'not landed at start: %s' % states)
        self.assertIn(TAKING_OFF, states, 'no takeoff; gestures seen: %s' % sorted(set(gestures)))
        self.assertIn(states[-1], (FLYING, HOVERING), 'not airborne: %s' % states)
        self.assertIn('unfold', gestures)


if __name__ == '__main__':
    rospy.init_node('camera_video_drone_check')
    rostest.rosrun('leap_teleop', 'camera_video_drone_check', CameraFliesDrone, sys.argv)
