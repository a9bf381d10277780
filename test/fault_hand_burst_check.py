#!/usr/bin/env python3
"""rostest node (fault_hand_burst.test): a hand source stalls for 2 s, then bursts the
200 messages it captured meanwhile (stamped at capture): for 1.5 s a thumbs-up, a rock
and a palm far up and forward, then 0.5 s of the neutral palm. ur10_1 tracks and the
drone (navdata from here, flying) is engaged before the stall. No robot may act on a
message older than max_input_age: the arm stays disarmed (its watchdog disarmed it
during the stall) and gets no command; the pilot sends nothing beyond hover; both count
the refused messages."""
import sys
import threading
import time
import unittest

import rospy
import rostest
from geometry_msgs.msg import Twist

from check_helpers import (
    DiagnosticCounts,
    RightHands,
    Watch,
    arm_track_and_unfold,
    limit,
    read_limits,
    start_streaming,
    wait_for,
)

ARM = 'ur10_1'
NEUTRAL = dict(palm=(0.0, 250.0, 0.0))
FAR = dict(palm=(0.0, 400.0, -150.0))
LIMITS = {
    'ready_timeout_s': limit('wait this long for the arm node and the pilot to listen', 's',
                             gt=0),
    'state_timeout_s': limit('the thumbs-up arms, the rock starts tracking within this', 's',
                             gt=0),
    'pilot_timeout_s': limit('the engaged pilot sends twists within this', 's', gt=0),
    'min_rejected_arm': limit('of the 200 backlog messages the arm node refuses at least',
                              kind='int', ge=0, le=200),
    'min_rejected_pilot': limit('of the 200 backlog messages the pilot refuses at least',
                                kind='int', ge=0, le=200),
}


class FaultHandBurst(unittest.TestCase):
    def test_stall_then_backlog_burst(self):
        lim = read_limits(LIMITS)
        w = Watch(arm=ARM)
        rejected = DiagnosticCounts('rejected inputs')
        twists = []
        rospy.Subscriber('cmd_vel', Twist, lambda m: twists.append((time.monotonic(), m)),
                         queue_size=500)
        hands = RightHands()
        pose = {'now': dict(NEUTRAL)}
        stop = threading.Event()

        def stream():             # the live hand, 100 Hz, unless stalled (pose None)
            while not stop.is_set() and not rospy.is_shutdown():
                p = pose['now']
                if p is not None:
                    hands.publish(rospy.get_time(), **p)
                time.sleep(0.01)
        start_streaming(ARM, hands, stream, stop, lim.ready_timeout_s)
        try:
            # Arm tracking, pilot engaged.
            arm_track_and_unfold(w, hands, pose, NEUTRAL, lim.state_timeout_s)
            self.assertTrue(wait_for(lambda: twists, lim.pilot_timeout_s),
                            'the pilot sends nothing')
            time.sleep(1.2)                         # diagnostics (1 Hz) before the stall
            arm_rej0, pilot_rej0 = rejected.get(ARM) or 0, rejected.get('pilot') or 0

            # The stall: 2 s of capture, nothing delivered.
            pose['now'] = None
            t_stall = time.monotonic()
            backlog, start = [], rospy.get_time()
            for k in range(200):
                time.sleep(max(0.0, start + 0.01 * k - rospy.get_time()))
                p = (dict(FAR, thumb_up=k < 30) if k < 60 else dict(FAR, rock=k < 90)
                     if k < 150 else dict(NEUTRAL))
                backlog.append((rospy.get_time(), p))
            # The burst, then the live hand again (neutral, no gesture).
            t_burst = time.monotonic()
            for stamp, p in backlog:
                hands.publish(stamp, **p)
                time.sleep(0.0005)
            pose['now'] = dict(NEUTRAL)
            time.sleep(2.5)

            t_dis, st = w.first_status('disarmed', t_stall)
            self.assertIsNotNone(t_dis, 'the watchdog did not disarm during the stall')
            self.assertLess(t_dis, t_burst)
            states = [s.state for t, s in w.status if t > t_dis]
            self.assertNotIn('armed', states, 'the backlog re-armed the arm')
            self.assertNotIn('tracking', states)
            late_cmds = [t for t, _ in w.arm_cmds if t > t_burst]
            self.assertEqual(late_cmds, [], 'arm commands after the burst')
            moving = [m for t, m in twists if t > t_burst and (abs(m.linear.x) > 1e-6
                                                               or abs(m.linear.z) > 1e-6)]
            self.assertEqual(moving, [], 'the pilot flew toward the backlog')
            arm_rej, pilot_rej = rejected.get(ARM) - arm_rej0, rejected.get('pilot') - pilot_rej0
            rospy.loginfo('FAULT hand burst: arm refused %d, pilot refused %d of 200',
                          arm_rej, pilot_rej)
            self.assertGreaterEqual(arm_rej, lim.min_rejected_arm)
            self.assertGreaterEqual(pilot_rej, lim.min_rejected_pilot)
        finally:
            stop.set()


if __name__ == '__main__':
    rospy.init_node('fault_hand_burst_check')
    rostest.rosrun('leap_teleop', 'fault_hand_burst_check', FaultHandBurst, sys.argv)
