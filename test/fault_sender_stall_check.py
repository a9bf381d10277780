#!/usr/bin/env python3
"""rostest node (fault_sender_stall.test): SIGSTOP the sender for stall_s while ur10_1
moves (a stall shorter than disarm_after), then SIGCONT. The arm holds at once,
commands nothing while the input is stale, resumes tracking when the input returns
without a new thumbs-up (never disarmed), its first command after that starts at the pose
it is at (no jump), and it moves on with the session. The limits: ~limits in
fault_sender_stall.test."""
import os
import signal
import sys
import time
import unittest

import numpy as np
import rospy
import rostest

from check_helpers import Watch, limit, node_pid, read_limits, wait_for

ARM = 'ur10_1'
LIMITS = {
    'stall_s': limit('the sender is stopped this long (less than disarm_after - 0.2 s)', 's',
                     gt=0),
    'moving_timeout_s': limit('wait this long for the arm moving', 's', gt=0),
    'moving_speed': limit('the arm moves: a joint faster than this', 'rad/s', gt=0),
    'resume_timeout_s': limit('tracking again within this of the stop', 's', gt=0),
    'hold_within_s': limit('the arm holds within this of the stop', 's', gt=0),
    'max_jump_rad': limit('the first commands after the resume: at most this far from the '
                          'arm\'s pose', 'rad', gt=0),
    'moving_again_speed': limit('the session goes on: a joint faster than this ...', 'rad/s',
                                gt=0),
    'moving_again_timeout_s': limit('... within this of the resume', 's', gt=0),
    'min_silence_fraction': limit('the command stream falls silent between the hold and '
                                  'the resume for at least this share of the time between '
                                  'their status messages', gt=0, le=1),
}


class FaultSenderStall(unittest.TestCase):
    def test_short_sender_stall_holds_then_resumes(self):
        lim = read_limits(LIMITS)
        w = Watch(arm=ARM)
        disarm_after = rospy.get_param('/%s/ur10_arm/disarm_after' % ARM)
        self.assertLess(lim.stall_s + 0.2, disarm_after)
        pid = node_pid('/leap_sender')
        self.assertTrue(wait_for(lambda: (w.arm_speed(time.monotonic() - 0.1, time.monotonic())
                                          or 0) > lim.moving_speed, lim.moving_timeout_s),
                        'the arm never moved: %s' % [(s.state, s.reason)
                                                     for _, s in w.status[-3:]])
        t_stop_stamp = rospy.get_time()
        os.kill(pid, signal.SIGSTOP)
        t_stop = time.monotonic()
        try:
            time.sleep(lim.stall_s)
        finally:
            os.kill(pid, signal.SIGCONT)
        t_cont = time.monotonic()
        rospy.loginfo('sender stopped for %.2f s', t_cont - t_stop)
        self.assertTrue(wait_for(lambda: w.first_status('tracking', t_stop, 'input back')[0]
                                 is not None, lim.resume_timeout_s),
                        'no resume: %s' % [(s.state, s.reason) for _, s in w.status[-5:]])
        t_resume, st_resume = w.first_status('tracking', t_stop, 'input back')
        t_hold, st_hold = w.first_status('holding', t_stop, 'no hand input')
        self.assertIsNotNone(t_hold)
        held_in = st_hold.header.stamp.to_sec() - t_stop_stamp
        rospy.loginfo('FAULT sender stall: held %.3f s after the stop; %s', held_in,
                      st_resume.reason)
        self.assertLess(held_in, lim.hold_within_s)
        self.assertLess(t_hold, t_resume)
        time.sleep(2.0)
        states = [s.state for t, s in list(w.status) if t >= t_stop]
        self.assertNotIn('disarmed', states, 'a short stall disarmed the arm')
        self.assertNotIn('armed', states, 'the arm needed a new thumbs-up')
        # Stale input moves nothing: from the hold until the resume the arm sends nothing
        # but the hold itself (tracking, it sends a command every control period). Judged
        # as a silence in the command stream, not by the statuses' receipt times: commands
        # and statuses come on two connections, which a loaded machine delays differently.
        cmds = list(w.arm_cmds)
        near = [t for t, _ in cmds if t_hold - 1.0 < t < t_resume + 1.0]
        gaps = [(b - a, a, b) for a, b in zip(near, near[1:]) if a < t_resume and b > t_hold]
        silence, start, end = max(gaps) if gaps else (0.0, t_hold, t_hold)
        rospy.loginfo('FAULT sender stall: commands silent for %.3f s of the %.3f s from hold '
                      'to resume', silence, t_resume - t_hold)
        self.assertGreaterEqual(
            silence, lim.min_silence_fraction * (t_resume - t_hold),
            'the arm went on commanding while the input was stale: its longest silence around '
            'the stall %.3f s (from %.3f to %.3f s after the hold status), hold to resume '
            '%.3f s' % (silence, start - t_hold, end - t_hold, t_resume - t_hold))
        # No jump: the first commands after the resume start where the arm is.
        after = [(t, q) for t, q in cmds if t >= t_resume - 0.05][:10]
        self.assertTrue(after, 'no command after the resume')
        worst = max(float(np.max(np.abs(q - w.q_at(t)))) for t, q in after)
        rospy.loginfo('FAULT sender stall: first commands after the resume at most %.4f rad '
                      'from the arm\'s pose', worst)
        self.assertLess(worst, lim.max_jump_rad, 'a command %.3f rad away from the arm\'s pose' % worst)
        # ... and the session goes on: the arm moves again.
        self.assertTrue(wait_for(lambda: (w.arm_speed(t_resume, time.monotonic()) or 0)
                                 > lim.moving_again_speed, lim.moving_again_timeout_s),
                        'the arm did not move after the resume')


if __name__ == '__main__':
    rospy.init_node('fault_sender_stall_check')
    rostest.rosrun('leap_teleop', 'fault_sender_stall_check', FaultSenderStall, sys.argv)
