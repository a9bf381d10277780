#!/usr/bin/env python3
"""rostest node: the sender's messages follow its gesture script frame by frame."""
import sys
import unittest

import rospy
import rostest

from leap_teleop.msg import Hand, leapcobotleft, leapcobotright
from leap_teleop.sources.scripted import GestureScript


class SenderFollowsScript(unittest.TestCase):
    def test_messages_follow_the_script(self):
        script = GestureScript.load(rospy.get_param('~script'))
        hands, cobots_right, cobots_left = [], [], []
        rospy.Subscriber('leapmotion/hand_right', Hand, hands.append, queue_size=2000)
        rospy.Subscriber('leapmotion/data_right', leapcobotright, cobots_right.append,
                         queue_size=2000)
        rospy.Subscriber('leapmotion/data_left', leapcobotleft, cobots_left.append,
                         queue_size=2000)
        deadline = rospy.Time.now() + rospy.Duration(rospy.get_param('~duration', 6.0))
        while rospy.Time.now() < deadline and not rospy.is_shutdown():
            rospy.sleep(0.1)
        self.assertGreater(len(hands), 300)

        # Palm positions follow the script within 1 mm; presence matches.
        n_frames = int(round(script.duration * script.rate_hz))   # the sender loops
        for msg in hands:
            t = ((msg.leap_frame_id - 1) % n_frames) / script.rate_hz
            expected = script.hand_at('right', t)
            self.assertEqual(msg.present, expected is not None, 'frame %d' % msg.leap_frame_id)
            if expected is not None:
                got = [msg.palm_position.x * 1000, msg.palm_position.y * 1000,
                       msg.palm_position.z * 1000]
                for g, e in zip(got, expected.palm_position):
                    self.assertAlmostEqual(g, e, delta=1.0)

        # Stamps strictly increase on every topic.
        for msgs in (hands, cobots_right, cobots_left):
            stamps = [m.header.stamp.to_sec() for m in msgs]
            self.assertTrue(all(b > a for a, b in zip(stamps, stamps[1:])))

        # Flags were raised while the hand was there, and all clear while it was gone.
        self.assertTrue(any(m.right_hand_fist for m in cobots_right))
        self.assertTrue(any(m.right_hand_origin_frame for m in cobots_right))
        absent = [m for m in cobots_right if not m.is_right_hand]
        self.assertGreater(len(absent), 50)
        for m in absent:
            self.assertFalse(m.right_hand_fist or m.right_hand_thumb_up or m.right_hand_pinch
                             or m.right_hand_origin_frame
                             or m.right_hand_set_origin_frame_detected)
            self.assertEqual(m.right_hand_pinch_value, 0.0)
        self.assertFalse(any(m.is_left_hand for m in cobots_left))


if __name__ == '__main__':
    rospy.init_node('sender_check')
    rostest.rosrun('leap_teleop', 'sender_check', SenderFollowsScript, sys.argv)
