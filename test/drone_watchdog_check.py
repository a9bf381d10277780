#!/usr/bin/env python3
"""rostest node: the pilot's watchdog hovers on a lost hand, then lands."""
import sys
import time
import unittest

import rospy
import rostest
from geometry_msgs.msg import Twist

from leap_teleop.drone.sim import FLYING, HOVERING, LANDED, LANDING
from leap_teleop.msg import GestureEvent, Hand, Navdata

from check_helpers import limit, pilot_hand, publishes_to_a_subscriber, read_limits, wait_for

LIMITS = {
    'ready_timeout_s': limit('wait this long for the drone landed and the pilot listening',
                             's', gt=0),
    'takeoff_timeout_s': limit('the unfold takes off within this', 's', gt=0),
    'forward_timeout_s': limit('the forward hand gives a forward twist within this', 's', gt=0),
    'zero_twist_within_s': limit('a silent hand: zero twist within this', 's', gt=0),
    'zero_twist_absent_within_s': limit('a hand reported absent: zero twist within this', 's',
                                        gt=0),
    'hover_within_s': limit('hovering within this once the twist is zero', 's', gt=0),
    'no_landing_for_s': limit('no landing for this long after hovering', 's', gt=0),
    'landing_within_s': limit('... then landing within this much more', 's', gt=0),
    'landed_within_s': limit('landed within this once landing', 's', gt=0),
    'absent_landing_within_s': limit('a hand reported absent: landing within this', 's', gt=0),
}


class DroneWatchdog(unittest.TestCase):
    def setUp(self):
        self.lim = read_limits(LIMITS)
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
        self.hand_pub.publish(pilot_hand(rospy.get_time(), (0.0, 0.2, z), present=present))

    def wait_for(self, cond, timeout, hand_z=None):
        """wait_for, sending the hand at hand_z meanwhile (unless None)."""
        if hand_z is None:
            return wait_for(cond, timeout, step=0.01)

        def sending():
            self.hand(hand_z)
            return cond()
        return cond() or wait_for(sending, timeout, step=0.01)

    def fly_forward(self):
        """Engage with an unfold, take off, then hold the hand 100 mm forward."""
        lim = self.lim
        # ... and the pilot's takeoff reaches the simulator (sent once, on the unfold)
        self.assertTrue(self.wait_for(lambda: self.state == LANDED
                                      and self.hand_pub.get_num_connections() > 0
                                      and self.gesture_pub.get_num_connections() > 0
                                      and publishes_to_a_subscriber('/drone_pilot',
                                                                    '/ardrone/takeoff'),
                                      lim.ready_timeout_s))
        self.hand(0.0)
        time.sleep(0.1)
        ev = GestureEvent(side=GestureEvent.SIDE_RIGHT, gesture='unfold', active=True)
        ev.header.stamp = rospy.Time.now()
        self.gesture_pub.publish(ev)
        self.assertTrue(self.wait_for(lambda: self.state in (FLYING, HOVERING),
                                      lim.takeoff_timeout_s, hand_z=0.0),
                        'no takeoff (state %s)' % self.state)
        self.assertTrue(self.wait_for(lambda: self.twists and self.twists[-1][1].linear.x > 0.5,
                                      lim.forward_timeout_s, hand_z=-0.1), 'no forward command')

    def test_silent_hand_hovers_then_lands(self):
        lim = self.lim
        self.fly_forward()
        self.hand(-0.1)
        last = time.monotonic()              # the hand goes silent from here
        self.assertTrue(self.wait_for(lambda: self.twists[-1][1].linear.x == 0.0, 1.0))
        zero_at = next(t for t, m in self.twists if t > last and m.linear.x == 0.0)
        rospy.loginfo('zero twist %.3f s after the last hand message', zero_at - last)
        self.assertLess(zero_at - last, lim.zero_twist_within_s)
        z = self.twists[-1][1]
        self.assertEqual((z.linear.x, z.linear.y, z.linear.z, z.angular.x, z.angular.y,
                          z.angular.z), (0.0,) * 6)          # exact zero: auto-hover
        self.assertTrue(self.wait_for(lambda: self.state == HOVERING, lim.hover_within_s))
        self.assertFalse(self.wait_for(lambda: self.state in (LANDING, LANDED),
                                       lim.no_landing_for_s))
        self.assertTrue(self.wait_for(lambda: self.state in (LANDING, LANDED),
                                      lim.landing_within_s), 'no landing')
        land_at = time.monotonic()
        rospy.loginfo('landing started %.2f s after the hand went silent', land_at - last)
        self.assertTrue(self.wait_for(lambda: self.state == LANDED, lim.landed_within_s))

        # Again, with the hand reported absent (present = false) instead of silence.
        self.twists.clear()
        self.fly_forward()
        # taken before the publish: the pilot's zero twist can come back before this
        # thread runs again on a loaded machine
        gone = time.monotonic()
        self.hand(present=False)
        self.assertTrue(self.wait_for(lambda: self.twists[-1][1].linear.x == 0.0, 1.0))
        zero_at = next(t for t, m in self.twists if t > gone and m.linear.x == 0.0)
        self.assertLess(zero_at - gone, lim.zero_twist_absent_within_s)
        self.assertTrue(self.wait_for(lambda: self.state in (LANDING, LANDED),
                                      lim.absent_landing_within_s), 'no landing')


if __name__ == '__main__':
    rospy.init_node('drone_watchdog_check')
    rostest.rosrun('leap_teleop', 'drone_watchdog_check', DroneWatchdog, sys.argv)
