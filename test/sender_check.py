#!/usr/bin/env python3
"""rostest node: the sender's messages follow its gesture script frame by frame."""
import sys
import unittest

import rospy
import rostest
import tf2_ros

from leap_teleop.hands.sources.scripted import GestureScript
from leap_teleop.msg import Hand, leapcobotleft, leapcobotright

from check_helpers import limit, read_limits

LIMITS = {
    'duration_s': limit('listen this long', 's', gt=0),
    'min_messages': limit('more messages than this on each topic', kind='int', ge=0),
    'palm_tolerance_mm': limit('palm positions follow the script this closely', 'mm', gt=0),
    'min_absent': limit('more messages without the hand than this', kind='int', ge=0),
    'tf_places': limit('the leap frame sits where the launch file puts it, to these decimal '
                       'places', kind='int', ge=0),
}


class SenderFollowsScript(unittest.TestCase):
    def test_messages_follow_the_script(self):
        lim = read_limits(LIMITS)
        script = GestureScript.load(rospy.get_param('~script'))
        hands, cobots_right, cobots_left = [], [], []
        rospy.Subscriber('leapmotion/hand_right', Hand, hands.append, queue_size=2000)
        rospy.Subscriber('leapmotion/data_right', leapcobotright, cobots_right.append,
                         queue_size=2000)
        rospy.Subscriber('leapmotion/data_left', leapcobotleft, cobots_left.append,
                         queue_size=2000)
        deadline = rospy.Time.now() + rospy.Duration(lim.duration_s)
        while rospy.Time.now() < deadline and not rospy.is_shutdown():
            rospy.sleep(0.1)
        # The script has a right hand and no left one; both sides are published each frame.
        self.assertGreater(len(hands), lim.min_messages)
        self.assertGreater(len(cobots_right), lim.min_messages)
        self.assertGreater(len(cobots_left), lim.min_messages)

        # Palm positions follow the script; presence matches.
        n_frames = int(round(script.duration * script.rate_hz))   # the sender loops
        for msg in hands:
            t = ((msg.leap_frame_id - 1) % n_frames) / script.rate_hz
            expected = script.hand_at('right', t)
            self.assertEqual(msg.present, expected is not None, 'frame %d' % msg.leap_frame_id)
            if expected is not None:
                got = [msg.palm_position.x * 1000, msg.palm_position.y * 1000,
                       msg.palm_position.z * 1000]
                for g, e in zip(got, expected.palm_position):
                    self.assertAlmostEqual(g, e, delta=lim.palm_tolerance_mm)

        # Stamps strictly increase on every topic.
        for msgs in (hands, cobots_right, cobots_left):
            stamps = [m.header.stamp.to_sec() for m in msgs]
            self.assertTrue(all(b > a for a, b in zip(stamps, stamps[1:])))

        # Flags were raised while the hand was there, and all clear while it was gone.
        self.assertTrue(any(m.right_hand_fist for m in cobots_right))
        self.assertTrue(any(m.right_hand_origin_frame for m in cobots_right))
        absent = [m for m in cobots_right if not m.is_right_hand]
        self.assertGreater(len(absent), lim.min_absent)
        for m in absent:
            self.assertFalse(m.right_hand_fist or m.right_hand_thumb_up or m.right_hand_pinch
                             or m.right_hand_origin_frame
                             or m.right_hand_set_origin_frame_detected)
            self.assertEqual(m.right_hand_pinch_value, 0.0)
        self.assertFalse(any(m.is_left_hand for m in cobots_left))

    def test_leap_frame_sits_where_the_launch_file_puts_it(self):
        places = read_limits(LIMITS).tf_places
        buffer = tf2_ros.Buffer()
        listener = tf2_ros.TransformListener(buffer)  # noqa: F841 (fills the buffer)
        t = buffer.lookup_transform('world', 'leap_hands', rospy.Time(0), rospy.Duration(10.0))
        p = t.transform.translation
        for got, want in zip((p.x, p.y, p.z), rospy.get_param('~leap_xyz')):
            self.assertAlmostEqual(got, want, places=places)
        # Leap axes in world: x (user's right) -> -y, y (up) -> z, z (toward the user) -> -x
        q = t.transform.rotation
        x, y, z, w = q.x, q.y, q.z, q.w
        columns = ((1 - 2 * (y * y + z * z), 2 * (x * y + z * w), 2 * (x * z - y * w)),
                   (2 * (x * y - z * w), 1 - 2 * (x * x + z * z), 2 * (y * z + x * w)),
                   (2 * (x * z + y * w), 2 * (y * z - x * w), 1 - 2 * (x * x + y * y)))
        for got, want in zip(columns, ((0, -1, 0), (0, 0, 1), (-1, 0, 0))):
            for g, e in zip(got, want):
                self.assertAlmostEqual(g, e, places=places)


if __name__ == '__main__':
    rospy.init_node('sender_check')
    rostest.rosrun('leap_teleop', 'sender_check', SenderFollowsScript, sys.argv)
