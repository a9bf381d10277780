#!/usr/bin/env python3
"""rostest node: a classic consumer, reading leap_motion/leapros (the ros-drivers type
name, built here from the message text) on leapmotion/data, gets well-formed messages
from the sender: the classic units (mm, degrees), unit vectors, angles that agree with
them, finger tips and knuckles, the last pose seen while the hand is away, stamps in
order."""
import math
import sys
import unittest

import genpy.dynamic
import rospy
import rostest

from leap_teleop.msg import Hand, leapros

from check_helpers import limit, read_limits

CLASSIC = genpy.dynamic.generate_dynamic('leap_motion/leapros', leapros._full_text)[
    'leap_motion/leapros']


LIMITS = {
    'duration_s': limit('listen this long', 's', gt=0),
    'min_messages': limit('more leapros messages than this', kind='int', ge=0),
    'min_overlap': limit('more Hand messages than this while both subscriptions were up',
                         kind='int', ge=0),
    'min_present_share': limit('more of the messages than this show the hand', gt=0, le=1),
    'palm_height_mm': limit('a present palm\'s y between these', 'mm', kind='list',
                            item='float', length=2),
    'unit_tolerance': limit('|direction|, |normal| this close to 1; ypr this close (deg)',
                            gt=0),
    'max_tip_distance_mm': limit('finger tips this close to the palm', 'mm', gt=0),
}


def norm(v):
    return math.sqrt(v.x ** 2 + v.y ** 2 + v.z ** 2)


class ClassicConsumer(unittest.TestCase):
    def test_leapros_is_well_formed(self):
        lim = read_limits(LIMITS)
        tol = lim.unit_tolerance
        self.assertEqual(CLASSIC._type, 'leap_motion/leapros')
        self.assertEqual(CLASSIC._md5sum, 'e37447f7532c765d6c587f418fd5dd03')
        got, hands = [], []
        rospy.Subscriber('leapmotion/data', CLASSIC, got.append, queue_size=5000)
        rospy.Subscriber('leapmotion/hand_right', Hand, hands.append, queue_size=5000)
        deadline = rospy.get_time() + lim.duration_s
        while rospy.get_time() < deadline and not rospy.is_shutdown():
            rospy.sleep(0.1)
        self.assertGreater(len(got), lim.min_messages, 'leapros messages received')
        # One leapros per right-hand frame: the same frames (stamps) as the Hand messages,
        # compared where both subscriptions were connected (they connect at different
        # times, and a count over the whole window differs by that gap).
        lo = max(got[0].header.stamp, hands[0].header.stamp)
        hi = min(got[-1].header.stamp, hands[-1].header.stamp)
        both = [[m.header.stamp for m in msgs if lo <= m.header.stamp <= hi]
                for msgs in (got, hands)]
        self.assertGreater(len(both[1]), lim.min_overlap, 'overlap of the two subscriptions')
        self.assertEqual(both[0], both[1])
        present_at = {m.header.stamp: m.present for m in hands}
        present = [m for m in got if present_at.get(m.header.stamp)]
        self.assertGreater(len(present), lim.min_present_share * len(got))
        low, high = lim.palm_height_mm
        for m in present:
            self.assertEqual(m.header.frame_id, 'leap_hands')
            self.assertTrue(low < m.palmpos.y < high, 'palm height %.1f: not mm' % m.palmpos.y)
            self.assertAlmostEqual(norm(m.direction), 1.0, delta=tol)
            self.assertAlmostEqual(norm(m.normal), 1.0, delta=tol)
            d, n = m.direction, m.normal
            # The classic sender's: yaw of the normal, pitch and roll of the direction.
            self.assertAlmostEqual(m.ypr.x, math.degrees(math.atan2(n.x, -n.z)), delta=tol)
            self.assertAlmostEqual(m.ypr.y, math.degrees(math.atan2(d.y, -d.z)), delta=tol)
            self.assertAlmostEqual(m.ypr.z, math.degrees(math.atan2(d.x, -d.y)), delta=tol)
            for finger in ('thumb', 'index', 'middle', 'ring', 'pinky'):
                tip = getattr(m, finger + '_tip')
                self.assertLess(math.dist((tip.x, tip.y, tip.z),
                                          (m.palmpos.x, m.palmpos.y, m.palmpos.z)),
                                lim.max_tip_distance_mm)
                self.assertGreater(norm(getattr(m, finger + '_proximal')), 0.0)
        # The script's absent stretch: the last pose seen, as the classic sender kept it.
        held, last = 0, None
        for m in got:
            if present_at.get(m.header.stamp) is False and last is not None:
                self.assertEqual((m.palmpos, m.index_tip), (last.palmpos, last.index_tip))
                held += 1
            elif present_at.get(m.header.stamp):
                last = m
        self.assertGreater(held, 0, 'leapros messages while the hand was away')
        stamps = [m.header.stamp for m in got]
        self.assertEqual(stamps, sorted(stamps))


if __name__ == '__main__':
    rospy.init_node('leapros_check')
    rostest.rosrun('leap_teleop', 'leapros_check', ClassicConsumer, sys.argv)
