#!/usr/bin/env python3
"""rostest node (fault_consumer_stop.test): hands stream at 100 Hz into ur10_1's arm node
(tracking) and the pilot (engaged, navdata from here: hovering) through publishers that
queue 500 messages per connection; both consumers are SIGSTOPped for stop_s, so a backlog
of old hands piles up for them, then resumed (SIGCONT). The old hands must not drive them:
the arm re-arms on a fresh thumbs-up and the pilot steers on a fresh unfold and offset,
each within fresh_within_s of those gestures, and the arm's commands then follow hands no
older than max_fresh_age_s. What piled up is read, not lost: each consumer's count of the
hands it missed (gaps in their sequence numbers, on /diagnostics) stays within
max_missed."""
import os
import signal
import sys
import threading
import time
import unittest

import rospy
import rostest

from leap_teleop.msg import ArmStatus

from check_helpers import (
    DiagnosticCounts,
    RightHands,
    Watch,
    arm_track_and_unfold,
    limit,
    node_pid,
    read_limits,
    start_streaming,
    wait_for,
)

ARM = 'ur10_1'
NEUTRAL = dict(palm=(0.0, 250.0, 0.0))
LIMITS = {
    'ready_timeout_s': limit('wait this long for the arm node and the pilot to listen', 's',
                             gt=0),
    'state_timeout_s': limit('the thumbs-up arms, the rock starts tracking within this', 's',
                             gt=0),
    'stop_s': limit('both consumers are stopped this long', 's', gt=0),
    'settle_s': limit('the fresh gestures start this long after the resume', 's', ge=0),
    'fresh_within_s': limit('each consumer acts on them within this (+ arm_hold_s)', 's', gt=0),
    'max_fresh_age_s': limit("the arm's next commands follow hands no older than this", 's',
                             gt=0),
    'min_twist': limit('the pilot steers: a twist component at least this large', gt=0),
    'max_missed': limit('hand messages each consumer may miss (sequence gaps) in the run', ge=0),
}
MISSED = 'hand messages missed (sequence gaps)'


def fresh_tracking(statuses, max_age, after):
    """The latest ArmStatus (ROS receipt time, msg), received at or after `after`, is
    tracking and its command follows a hand captured at most max_age before it was
    received."""
    if not statuses:
        return False
    t, st = statuses[-1]
    return (t >= after and st.state == 'tracking'
            and 0.0 <= t - st.input_stamp.to_sec() <= max_age)


def steering(twists, after, least):
    return next((t for t, m in list(twists) if t > after
                 and max(abs(m.linear.x), abs(m.linear.y), abs(m.linear.z)) >= least), None)


class ConsumerStop(unittest.TestCase):
    def test_stopped_consumers_act_on_fresh_input_after_the_resume(self):
        lim = read_limits(LIMITS)
        w = Watch(arm=ARM, drone=True)
        missed = DiagnosticCounts(MISSED)
        statuses = []
        rospy.Subscriber('/%s/ur10_arm/status' % ARM, ArmStatus,
                         lambda m: statuses.append((rospy.get_time(), m)), queue_size=50)
        hands = RightHands()
        pose = {'now': dict(NEUTRAL)}
        stop = threading.Event()

        def stream():
            k = 0
            while not stop.is_set() and not rospy.is_shutdown():
                p = dict(pose['now'])      # a palm that keeps moving: commands keep coming
                p['palm'] = (p['palm'][0] + 20.0 * (k % 100) / 100.0,) + tuple(p['palm'][1:])
                hands.publish(rospy.get_time(), **p)
                k += 1
                time.sleep(0.01)
        start_streaming(ARM, hands, stream, stop, lim.ready_timeout_s)
        try:
            arm_track_and_unfold(w, hands, pose, NEUTRAL, lim.state_timeout_s)
            pids = [node_pid('/%s/ur10_arm' % ARM), node_pid('/drone_pilot')]
            time.sleep(0.5)
            for pid in pids:
                os.kill(pid, signal.SIGSTOP)
            try:
                time.sleep(lim.stop_s)
            finally:
                # Taken before the resume: what the arm says after it is heard later.
                t_cont, t_cont_ros = time.monotonic(), rospy.get_time()
                for pid in pids:
                    os.kill(pid, signal.SIGCONT)
            time.sleep(lim.settle_s)
            hold = rospy.get_param('/%s/ur10_arm/arm_hold_s' % ARM)
            # The arm either kept tracking on the newest hands or its watchdog disarmed it
            # (which of its threads ran first after the resume); disarmed, it re-arms on a
            # fresh thumbs-up and rock. Either way its commands must follow fresh hands.
            # Which one is known from what it says after the resume, however late that is
            # heard: the status it had before the stop says nothing.

            def outcome():
                if w.first_status('disarmed', t_cont)[0] is not None:
                    return 'disarmed'
                if fresh_tracking(statuses, lim.max_fresh_age_s, t_cont_ros):
                    return 'tracking'
                return None
            self.assertTrue(wait_for(lambda: outcome() is not None, lim.fresh_within_s),
                            'no disarm and no fresh tracking after the resume: %s' % statuses[-3:])
            t_fresh, t_fresh_ros = time.monotonic(), rospy.get_time()
            deadline = lim.fresh_within_s
            if outcome() == 'disarmed':
                rospy.loginfo('FAULT consumers stopped: the arm disarmed on the stall')
                pose['now'] = dict(NEUTRAL, thumb_up=True)
                self.assertTrue(wait_for(lambda: w.first_status('armed', t_fresh)[0] is not None,
                                         lim.fresh_within_s + hold),
                                ['%.2f %s: %s' % (t - t_fresh, st.state, st.reason)
                                 for t, st in w.status[-8:]])
                pose['now'] = dict(NEUTRAL, rock=True)
                deadline += hold + lim.fresh_within_s
            self.assertTrue(wait_for(lambda: fresh_tracking(statuses, lim.max_fresh_age_s,
                                                            t_fresh_ros),
                                     deadline), statuses[-3:])
            t_arm = time.monotonic() - t_cont
            # The pilot: a fresh unfold and a palm 80 mm to the side steer it.
            pose['now'] = dict(NEUTRAL)
            time.sleep(0.05)
            t_unfold = time.monotonic()
            hands.unfold()
            time.sleep(0.05)
            pose['now'] = dict(palm=(80.0, 250.0, 0.0))
            wait_for(lambda: steering(w.twists, t_unfold, lim.min_twist) is not None,
                     lim.fresh_within_s + 2.0)
            t_steer = steering(w.twists, t_unfold, lim.min_twist)
            rospy.loginfo('FAULT consumers stopped %.1f s: the arm acted on fresh hands %.2f s '
                          'after the resume, the pilot steered %s s after the unfold',
                          lim.stop_s, t_arm,
                          'never' if t_steer is None else '%.2f' % (t_steer - t_unfold))
            self.assertIsNotNone(t_steer, 'the pilot never steered on the fresh hand')
            self.assertLess(t_steer - t_unfold, lim.fresh_within_s)
            missed.values.clear()            # reports from now on: the backlog was read
            wait_for(lambda: None not in (missed.get('ur10_arm'), missed.get('pilot')), 5.0)
            counts = (missed.get('ur10_arm'), missed.get('pilot'))
            rospy.loginfo('FAULT consumers stopped: hand messages missed: arm %s, pilot %s',
                          *counts)
            self.assertNotIn(None, counts, 'no diagnostics report after the resume')
            self.assertLessEqual(max(counts), lim.max_missed, counts)
        finally:
            stop.set()


if __name__ == '__main__':
    rospy.init_node('fault_consumer_stop_check')
    rostest.rosrun('leap_teleop', 'fault_consumer_stop_check', ConsumerStop, sys.argv)
