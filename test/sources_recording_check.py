#!/usr/bin/env python3
"""rostest node: the sender, fed by the recording source, publishes the take's hands."""
import os
import sys
import unittest

import rospy
import rostest

from leap_teleop.msg import GestureEvent, Hand, leapcobotright

from check_helpers import limit, read_limits

LIMITS = {
    'duration_s': limit('listen this long', 's', gt=0),
    'min_hands': limit('more Hand messages than this', kind='int', ge=0),
    'min_present_share': limit('more of them than this show the hand', gt=0, le=1),
    'palm_height_m': limit('every palm\'s y between these', 'm', kind='list', item='float',
                           length=2),
}


class SenderPlaysRecording(unittest.TestCase):
    def test_messages_arrive_with_present_hands(self):
        lim = read_limits(LIMITS)
        path = rospy.get_param('~recording')
        self.assertTrue(os.path.exists(path), 'recording %s absent' % path)
        hands, cobots, events = [], [], []
        rospy.Subscriber('leapmotion/hand_right', Hand, hands.append, queue_size=5000)
        rospy.Subscriber('leapmotion/data_right', leapcobotright, cobots.append, queue_size=5000)
        rospy.Subscriber('leapmotion/gestures', GestureEvent, events.append, queue_size=5000)
        deadline = rospy.Time.now() + rospy.Duration(lim.duration_s)
        while rospy.Time.now() < deadline and not rospy.is_shutdown():
            rospy.sleep(0.1)
        self.assertGreater(len(hands), lim.min_hands)
        present = [m for m in hands if m.present]
        self.assertGreater(len(present), lim.min_present_share * len(hands))
        self.assertTrue(any(m.fist for m in present), 'no fist in the grab take')
        self.assertTrue(any(m.open for m in present), 'no open hand in the grab take')
        self.assertTrue(any(m.right_hand_fist for m in cobots))
        self.assertFalse(any(m.right_hand_pinch for m in cobots), 'a fist is not a pinch')
        for a, b in zip(present, present[1:]):
            self.assertGreaterEqual(b.header.stamp, a.header.stamp)
        ys = [m.palm_position.y for m in present]
        low, high = lim.palm_height_m
        self.assertTrue(all(low < y < high for y in ys), 'palm height out of range (m)')


if __name__ == '__main__':
    rospy.init_node('sources_recording_check')
    rostest.rosrun('leap_teleop', 'sources_recording_check', SenderPlaysRecording, sys.argv)
