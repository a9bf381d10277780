#!/usr/bin/env python3
"""rostest node: the pilot's watchdog hovers on a lost hand, then lands."""
import sys
import time
import unittest

import rospy
import rostest
from geometry_msgs.msg import Twist

from leap_teleop.msg import GestureEvent, Hand, Navdata


class DroneWatchdog(unittest.TestCase):
    def setUp(self):
        self.state = None
        self.twists = []          # (wall time, Twist)
        rospy.Subscriber('ardrone/navdata', Navdata, self.on_nav, queue_size=10)
        rospy.Subscriber('cmd_vel', Twist, lambda m: self.twists.append((time.monotonic(), m)),
                         queue_size=100)
        self.hand_pub = rospy.Publisher('leapmotion/hand_right', Hand, queue_size=10)
        self.gesture_pub = rospy.Publisher('leapmotion/gestures', GestureEvent, queue_size=10)

    def on_nav(self, msg):
        self.state = msg.state

    def hand(self, z=0.0, present=True):
        h = Hand()
        h.header.stamp = rospy.Time.now()
        h.side, h.present = Hand.SIDE_RIGHT, present
        if present:
            h.palm_position.y, h.palm_position.z = 0.2, z
            h.palm_normal.y, h.direction.z = -1.0, -1.0
        self.hand_pub.publish(h)

    def wait_for(self, cond, timeout, hand_z=None):
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline and not rospy.is_shutdown():
            if cond():
                return True
            if hand_z is not None:
                self.hand(hand_z)
            time.sleep(0.01)
        return cond()

    def fly_forward(self):
        """Engage with an unfold, take off, then hold the hand 100 mm forward."""
        self.assertTrue(self.wait_for(lambda: self.state == 2
                                      and self.hand_pub.get_num_connections() > 0
                                      and self.gesture_pub.get_num_connections() > 0, 20.0))
        self.hand(0.0)
        time.sleep(0.1)
        ev = GestureEvent(side=GestureEvent.SIDE_RIGHT, gesture='unfold', active=True)
        ev.header.stamp = rospy.Time.now()
        self.gesture_pub.publish(ev)
        self.assertTrue(self.wait_for(lambda: self.state in (3, 4), 10.0, hand_z=0.0),
                        'no takeoff (state %s)' % self.state)
        self.assertTrue(self.wait_for(lambda: self.twists and self.twists[-1][1].linear.x > 0.5,
                                      3.0, hand_z=-0.1), 'no forward command')

    def test_silent_hand_hovers_then_lands(self):
        self.fly_forward()
        self.hand(-0.1)
        last = time.monotonic()              # the hand goes silent from here
        self.assertTrue(self.wait_for(lambda: self.twists[-1][1].linear.x == 0.0, 1.0))
        zero_at = next(t for t, m in self.twists if t > last and m.linear.x == 0.0)
        rospy.loginfo('zero twist %.3f s after the last hand message', zero_at - last)
        self.assertLess(zero_at - last, 0.25)    # 0.2 s spec + slack for a loaded machine
        z = self.twists[-1][1]
        self.assertEqual((z.linear.x, z.linear.y, z.linear.z, z.angular.x, z.angular.y,
                          z.angular.z), (0.0,) * 6)          # exact zero: auto-hover
        self.assertTrue(self.wait_for(lambda: self.state == 4, 2.0))
        self.assertFalse(self.wait_for(lambda: self.state in (8, 2), 2.3))   # not before 3 s
        self.assertTrue(self.wait_for(lambda: self.state in (8, 2), 2.0), 'no landing')
        land_at = time.monotonic()
        rospy.loginfo('landing started %.2f s after the hand went silent', land_at - last)
        self.assertTrue(self.wait_for(lambda: self.state == 2, 5.0))

        # Again, with the hand reported absent (present = false) instead of silence.
        self.twists.clear()
        self.fly_forward()
        self.hand(present=False)
        gone = time.monotonic()
        self.assertTrue(self.wait_for(lambda: self.twists[-1][1].linear.x == 0.0, 1.0))
        zero_at = next(t for t, m in self.twists if t > gone and m.linear.x == 0.0)
        self.assertLess(zero_at - gone, 0.2)
        self.assertTrue(self.wait_for(lambda: self.state in (8, 2), 5.0), 'no landing')


if __name__ == '__main__':
    rospy.init_node('drone_watchdog_check')
    rostest.rosrun('leap_teleop', 'drone_watchdog_check', DroneWatchdog, sys.argv)
