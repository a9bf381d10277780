#!/usr/bin/env python3
"""rostest node: the drone, landed, takes off on the gesture the video source reads in a
real person's clip (the takeoff event the sender sends for it, per its bindings)."""
import os
import sys
import unittest

import rospy
import rostest

from leap_teleop.msg import GestureEvent

from check_helpers import NavdataStates, limit, navdata_code, navdata_codes, read_limits, state_limit, states_limit

LIMITS = {
    'timeout_s': limit('wait this long for the drone to be airborne', 's', gt=0),
    'start_state': state_limit('the first navdata state'),
    'takeoff_state': state_limit('a state that shows the takeoff'),
    'airborne_states': states_limit('the last state must be one of these'),
    'gesture': limit('the event that takes off, seen on leapmotion/gestures', kind='str'),
}


class CameraFliesDrone(unittest.TestCase):
    def test_gesture_from_video_takes_off(self):
        lim = read_limits(LIMITS)
        start, taking_off = navdata_code(lim.start_state), navdata_code(lim.takeoff_state)
        airborne = navdata_codes(lim.airborne_states)
        video = rospy.get_param('~video')
        self.assertTrue(os.path.exists(video), 'clip %s absent' % video)
        nav, gestures = NavdataStates(), []
        rospy.Subscriber('leapmotion/gestures', GestureEvent,
                         lambda m: gestures.append(m.gesture), queue_size=1000)
        deadline = rospy.get_time() + lim.timeout_s
        while rospy.get_time() < deadline and not rospy.is_shutdown():
            states = nav.get()
            if taking_off in states and states[-1] in airborne:
                break
            rospy.sleep(0.1)
        states = nav.get()
        self.assertTrue(states and states[0] == start, 'not %s at start: %s'
                        % (lim.start_state, states))
        self.assertIn(taking_off, states, 'no takeoff; gestures seen: %s' % sorted(set(gestures)))
        self.assertIn(states[-1], airborne, 'not airborne: %s' % states)
        self.assertIn(lim.gesture, gestures)


if __name__ == '__main__':
    rospy.init_node('camera_video_drone_check')
    rostest.rosrun('leap_teleop', 'camera_video_drone_check', CameraFliesDrone, sys.argv)
