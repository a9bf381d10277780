#!/usr/bin/env python3
"""rostest node (fault_robot.test).

Simulator restart: while ur10_1 tracks a hand, the UR10 simulator is SIGKILLed; the arm
node must disarm without crashing or spinning (its CPU use while the robot is gone is
measured), and once roslaunch has respawned the simulator (arm at home) it must send
nothing until a new thumbs-up + rock, then move from the new joint state.

Bad streams: hand messages with old stamps, out of order, or of the wrong side are
dropped, counted in ArmStatus.rejected_inputs and on /diagnostics (arm node and drone
pilot), and the nodes keep running.
"""
import sys
import threading
import time
import unittest

import numpy as np
import psutil
import rospy
import rostest
from sensor_msgs.msg import JointState

from leap_teleop.msg import Hand, leapcobotright
from leap_teleop.ur10 import kinematics as kin

from check_helpers import DiagnosticCounts, Watch, alive, kill, limit, node_pid, pilot_hand, read_limits, wait_for

ARM = 'ur10_1'
LIMITS = {
    'state_timeout_s': limit('the thumbs-up arms, the rock starts tracking within this', 's',
                             gt=0),
    'moving_speed': limit('the arm moves: a joint faster than this', 'rad/s', gt=0),
    'move_timeout_s': limit('... within this of the long move', 's', gt=0),
    'away_rad': limit('... and a joint this far from home before the simulator is killed', 'rad',
                      gt=0),
    'disarm_timeout_s': limit('the simulator killed: disarmed within this', 's', gt=0),
    'respawn_timeout_s': limit('roslaunch respawns the simulator within this', 's', gt=0),
    'max_cpu': limit('the arm node\'s CPU share while the simulator is gone below this',
                     'cores', gt=0),
    'still_speed': limit('after the respawn, no joint faster than this', 'rad/s', gt=0),
    'home_tolerance_rad': limit('the respawned arm is at home within this', 'rad', gt=0),
    'command_timeout_s': limit('re-armed, the first command comes within this', 's', gt=0),
    'max_jump_rad': limit('... at most this far from the new pose', 'rad', gt=0),
    'rejected_timeout_s': limit('bad messages are counted in ArmStatus within this', 's',
                                gt=0),
    'diagnostics_timeout_s': limit('... and on /diagnostics within this', 's', gt=0),
    'connect_timeout_s': limit('the pilot subscribes to the hand within this', 's', gt=0),
}


class HandStream(threading.Thread):
    """A right hand at 100 Hz on leapmotion/data_right; tests change self.pose."""

    def __init__(self):
        super().__init__(daemon=True)
        self.pub = rospy.Publisher('/leapmotion/data_right', leapcobotright, queue_size=50)
        self.lock = threading.Lock()
        self.pose = dict(present=False, palm=(0.0, 200.0, 0.0))
        self.sent = 0
        self.last_stamp = None        # of the last live message handed to the publisher

    def message(self, stamp_offset=0.0, **pose):
        m = leapcobotright()
        m.header.stamp = rospy.Time.from_sec(rospy.get_time() + stamp_offset)
        m.is_right_hand = pose.get('present', True)
        m.right_hand_palmpos.x, m.right_hand_palmpos.y, m.right_hand_palmpos.z = pose['palm']
        m.right_hand_thumb_up = pose.get('thumb_up', False)
        m.right_hand_set_origin_frame_detected = pose.get('rock', False)
        m.right_hand_origin_frame = pose.get('origin', False)
        return m

    def set(self, **pose):
        with self.lock:
            self.pose = pose

    def run(self):
        while not rospy.is_shutdown():
            with self.lock:           # publish under the lock: see older_than_live
                m = self.message(**self.pose)
                self.pub.publish(m)
                self.last_stamp = m.header.stamp.to_sec()
                self.sent += 1
            time.sleep(0.01)

    def older_than_live(self, age, **pose):
        """Publish a message stamped `age` s before the last live one already queued on
        the same connection: out of order however the live stream is paced."""
        with self.lock:
            m = self.message(**pose)
            m.header.stamp = rospy.Time.from_sec(self.last_stamp - age)
            self.pub.publish(m)


class FaultRobot(unittest.TestCase):
    def arm_and_track(self, hand, w, palm0, after):
        hand.set(palm=palm0, thumb_up=True)
        self.assertTrue(wait_for(lambda: w.first_status('armed', after)[0] is not None,
                                 self.lim.state_timeout_s),
                        [s.state + ': ' + s.reason for _, s in w.status[-5:]])
        hand.set(palm=palm0, rock=True)
        self.assertTrue(wait_for(lambda: w.first_status('tracking', after)[0] is not None,
                                 self.lim.state_timeout_s))
        time.sleep(0.2)
        return w.first_status('tracking', after)[0]

    def test_sim_restart_then_bad_streams(self):
        self.lim = lim = read_limits(LIMITS)
        w = Watch(arm=ARM)
        diag = DiagnosticCounts('rejected inputs')
        hand = HandStream()
        rospy.wait_for_message('/%s/joint_states' % ARM, JointState, timeout=60)
        hand.start()
        arm_pid, sim_pid = node_pid('/%s/ur10_arm' % ARM), node_pid('/ur10_sim')
        t0 = time.monotonic()
        self.arm_and_track(hand, w, (0.0, 250.0, 0.0), t0)
        hand.set(palm=(150.0, 300.0, -80.0))          # a long move
        self.assertTrue(wait_for(lambda: (w.arm_speed(time.monotonic() - 0.1, time.monotonic())
                                          or 0) > lim.moving_speed, lim.move_timeout_s),
                        'the arm never moved')
        # Far enough from home that the respawned simulator is told from a stall.
        self.assertTrue(wait_for(lambda: np.max(np.abs(w.q_at(time.monotonic()) - kin.HOME_Q))
                                 > lim.away_rad, lim.move_timeout_s), 'the arm never left home')
        t_kill = kill(sim_pid)
        # While the robot is gone: alive, not spinning, not commanding. Measured from the kill:
        # the respawn can come before the disarm, which left a window of a few ms (one clock
        # tick in it read as 138 % of a core).
        c0, m0 = sum(psutil.Process(arm_pid).cpu_times()[:2]), time.monotonic()
        self.assertTrue(wait_for(lambda: w.first_status('disarmed', t_kill)[0] is not None,
                                 lim.disarm_timeout_s),
                        [s.state + ': ' + s.reason for _, s in w.status[-5:]])
        t_dis, st = w.first_status('disarmed', t_kill)
        rospy.loginfo('FAULT sim kill: arm disarmed %.3f s after (%s)', t_dis - t_kill, st.reason)
        self.assertIn('joint states', st.reason)
        self.assertTrue(wait_for(lambda: node_pid('/ur10_sim') != sim_pid,
                                 lim.respawn_timeout_s),
                        'the simulator was not respawned')
        t_back = time.monotonic()
        cpu = (sum(psutil.Process(arm_pid).cpu_times()[:2]) - c0) / (t_back - m0)
        rospy.loginfo('FAULT sim restart: simulator back after %.1f s; arm node CPU while it '
                      'was gone %.1f %% (over %.2f s)', t_back - t_kill, 100 * cpu, t_back - m0)
        self.assertTrue(alive(arm_pid))
        self.assertEqual(node_pid('/%s/ur10_arm' % ARM), arm_pid, 'the arm node restarted')
        self.assertLess(cpu, lim.max_cpu, 'arm node busy while the robot is gone')
        rospy.wait_for_message('/%s/joint_states' % ARM, JointState, timeout=lim.respawn_timeout_s)
        t_js = time.monotonic()
        time.sleep(1.0)              # the hand still says "far away": nothing may move
        late = [t for t, _ in w.arm_cmds if t > t_dis + 0.05]
        self.assertEqual(late, [], 'commands while disarmed after the restart')
        self.assertLess(w.arm_speed(t_js, time.monotonic()), lim.still_speed)
        q_home = w.q_at(time.monotonic())
        np.testing.assert_allclose(q_home, kin.HOME_Q, atol=lim.home_tolerance_rad)
        # Re-arm: the new origin is the new pose; the first command starts there.
        t_origin = self.arm_and_track(hand, w, (150.0, 300.0, -80.0), t_js)
        hand.set(palm=(150.0, 320.0, -80.0))
        self.assertTrue(wait_for(lambda: any(t > t_origin for t, _ in w.arm_cmds),
                                 lim.command_timeout_s))
        t_cmd, q_cmd = next((t, q) for t, q in list(w.arm_cmds) if t > t_origin)
        jump = float(np.max(np.abs(q_cmd - w.q_at(t_cmd))))
        rospy.loginfo('FAULT sim restart: first command after re-arming %.4f rad from the '
                      'new pose', jump)
        self.assertLess(jump, lim.max_jump_rad)

        # -- bad streams into the arm node ------------------------------------------------
        with w.lock:
            before = w.status[-1][1].rejected_inputs
        pose = dict(palm=(150.0, 320.0, -80.0))
        n_late = 5
        for k in range(n_late):
            hand.pub.publish(hand.message(stamp_offset=-1.0, **pose))       # held up 1 s
            time.sleep(0.02)
        # Out of order: older than a live message sent before it (a fixed offset from now
        # is not, when the live stream has been starved for longer than the offset).
        hand.older_than_live(0.05, **pose)
        hand.pub.publish(hand.message(**dict(palm=(float('nan'), 0.0, 0.0))))
        bad = n_late + 2                   # + the out-of-order one and the NaN palm
        self.assertTrue(wait_for(lambda: w.status[-1][1].rejected_inputs >= before + bad,
                                 lim.rejected_timeout_s),
                        'rejected_inputs %d -> %d' % (before, w.status[-1][1].rejected_inputs))
        self.assertEqual(w.status[-1][1].rejected_inputs, before + bad)
        self.assertTrue(wait_for(lambda: (diag.get('ur10_arm') or 0) >= before + bad,
                                 lim.diagnostics_timeout_s), diag.values)
        self.assertEqual(w.status[-1][1].state, 'tracking')   # the live stream goes on

        # -- bad streams into the drone pilot ----------------------------------------------
        pub = rospy.Publisher('/leapmotion/hand_right', Hand, queue_size=50)
        self.assertTrue(wait_for(lambda: pub.get_num_connections() > 0, lim.connect_timeout_s))
        for k in range(20):
            pub.publish(pilot_hand(rospy.get_time()))
            time.sleep(0.01)
        n_late = 3
        for k in range(n_late):
            pub.publish(pilot_hand(rospy.get_time() - 1.0))
            time.sleep(0.01)
        pub.publish(pilot_hand(rospy.get_time(), side=Hand.SIDE_LEFT))
        self.assertTrue(wait_for(lambda: diag.get('drone_pilot') == n_late + 1,
                                 lim.diagnostics_timeout_s), diag.values)
        self.assertTrue(alive(node_pid('/drone_pilot')))


if __name__ == '__main__':
    rospy.init_node('fault_robot_check')
    rostest.rosrun('leap_teleop', 'fault_robot_check', FaultRobot, sys.argv)
