#!/usr/bin/env python3
"""rostest node (fault_drone.test).

Navdata never starts (blind_pilot): an unfold sends no takeoff and a forward hand no
twist beyond hover; /diagnostics says why.

Simulator hangs (SIGSTOP) while the drone flies forward, with a flip requested right
after: the pilot's watchdog keeps running on its own thread: it hovers once navdata is
stale, repeats the hover, reports the flip call that never answered (timed out or failed)
and lands after land_after; then the simulator is resumed (SIGCONT).
"""
import os
import signal
import sys
import threading
import time
import unittest

import rospy
import rostest
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import Twist
from std_msgs.msg import Empty

from leap_teleop.drone.sim import FLYING, HOVERING, LANDED
from leap_teleop.msg import GestureEvent, Hand, Navdata

from check_helpers import limit, node_pid, pilot_hand, read_limits, wait_for

ZERO = (0.0,) * 6
LIMITS = {
    'ready_timeout_s': limit('wait this long for the drone landed and both pilots listening',
                             's', gt=0),
    'takeoff_timeout_s': limit('the unfold takes off within this', 's', gt=0),
    'forward_timeout_s': limit('the forward hand gives forward twists within this', 's', gt=0),
    'diagnostics_timeout_s': limit('a diagnostics report comes within this', 's', gt=0),
    'flip_altitude_mm': limit('climb to this (navdata altd) before the hang', 'mm', gt=0),
    'climb_timeout_s': limit('... within this', 's', gt=0),
    'hover_slack_s': limit('hover within navdata_timeout + this after the hang', 's', ge=0),
    'min_hovers': limit('the watchdog repeats the hover: at least this many zero twists',
                        kind='int', ge=1),
    'land_early_s': limit('landing no earlier than land_after - this after the hover', 's',
                          ge=0),
    'land_late_s': limit('... and no later than land_after + this', 's', ge=0),
    'landing_report_within_s': limit('the pilot reports on /diagnostics within this after '
                                     'landing', 's', gt=0),
    'unanswered_flips': limit('flip calls reported timed out or failed', kind='int', ge=0),
}


def twist_tuple(m):
    return (m.linear.x, m.linear.y, m.linear.z, m.angular.x, m.angular.y, m.angular.z)


class FaultDrone(unittest.TestCase):
    def setUp(self):
        self.lim = read_limits(LIMITS)
        self.lock = threading.Lock()
        self.rec = {'twist': [], 'blind_twist': [], 'land': [], 'blind_takeoff': [],
                    'nav': [], 'diag': {}}
        self.hand_z = None
        sub = rospy.Subscriber
        sub('cmd_vel', Twist, self._add, 'twist', queue_size=500)
        sub('blind/cmd_vel', Twist, self._add, 'blind_twist', queue_size=500)
        sub('ardrone/land', Empty, self._add, 'land', queue_size=10)
        sub('blind/takeoff', Empty, self._add, 'blind_takeoff', queue_size=10)
        sub('ardrone/navdata', Navdata, self._add, 'nav', queue_size=50)
        sub('/diagnostics', DiagnosticArray, self._diag, queue_size=50)
        self.hand_pub = rospy.Publisher('leapmotion/hand_right', Hand, queue_size=10)
        self.gesture_pub = rospy.Publisher('leapmotion/gestures', GestureEvent, queue_size=10)
        threading.Thread(target=self._hand_loop, daemon=True).start()

    def _add(self, msg, key):
        with self.lock:
            self.rec[key].append((time.monotonic(), msg))

    def _diag(self, msg):
        with self.lock:
            for s in msg.status:
                self.rec['diag'][s.name] = (time.monotonic(), s)

    def _hand_loop(self):
        while not rospy.is_shutdown():
            if self.hand_z is not None:
                try:
                    self.hand_pub.publish(pilot_hand(rospy.get_time(), (0.0, 0.2, self.hand_z)))
                except rospy.ROSException:          # shutting down
                    return
            time.sleep(0.01)

    def gesture(self, name, value=0.0):
        ev = GestureEvent(side=GestureEvent.SIDE_RIGHT, gesture=name, active=True, value=value)
        ev.header.stamp = rospy.Time.now()
        self.gesture_pub.publish(ev)

    def state(self):
        with self.lock:
            return self.rec['nav'][-1][1].state if self.rec['nav'] else None

    def diag(self, node):
        with self.lock:
            for name, (t, s) in self.rec['diag'].items():
                if name.startswith(node + ':'):
                    return t, s
        return None, None

    def forward_since(self, n):
        """How many of the latest twists (after the first n) are all forward."""
        with self.lock:
            recent = [m.linear.x > 0.5 for _, m in self.rec['twist'][n:]]
        count = 0
        for forward in reversed(recent):
            if not forward:
                break
            count += 1
        return count

    def test_hung_simulator_and_missing_navdata(self):
        lim = self.lim
        self.assertTrue(wait_for(lambda: self.state() == LANDED
                                 and self.hand_pub.get_num_connections() >= 2
                                 and self.gesture_pub.get_num_connections() >= 2,
                                 lim.ready_timeout_s), 'drone not ready')
        sim_pid = node_pid('/ardrone_sim')
        # Engage both pilots, then fly forward.
        self.hand_z = 0.0
        time.sleep(0.2)
        self.gesture('unfold')
        self.assertTrue(wait_for(lambda: self.state() in (FLYING, HOVERING),
                                 lim.takeoff_timeout_s), 'no takeoff')
        self.hand_z = -0.1
        self.assertTrue(wait_for(lambda: self.rec['twist']
                                 and self.rec['twist'][-1][1].linear.x > 0.5,
                                 lim.forward_timeout_s))
        # Navdata never started for blind_pilot: no takeoff, nothing beyond hover.
        self.assertEqual(self.rec['blind_takeoff'], [])
        moving = [m for _, m in self.rec['blind_twist'] if twist_tuple(m) != ZERO]
        self.assertEqual(moving, [], 'blind pilot sent %d moving twists' % len(moving))
        self.assertTrue(wait_for(lambda: self.diag('blind_pilot')[1] is not None,
                                 lim.diagnostics_timeout_s))
        self.assertIn('no navdata', self.diag('blind_pilot')[1].message)

        # Climb to flip height, fly forward again, then hang the simulator and ask for a
        # flip at once. Forward must be the only hand command in flight at the hang: a
        # centred hand's zero twist arriving after it would pass for the watchdog's hover.
        self.hand_z = 0.0
        self.assertTrue(wait_for(lambda: self.state() in (FLYING, HOVERING)
                                 and self.rec['nav'][-1][1].altd >= lim.flip_altitude_mm,
                                 lim.climb_timeout_s), 'too low')
        self.hand_z = -0.1                           # the user keeps asking for forward
        n_twists = len(self.rec['twist'])
        self.assertTrue(wait_for(lambda: self.forward_since(n_twists) >= 5,
                                 lim.forward_timeout_s),
                        'no steady forward command before the hang')
        os.kill(sim_pid, signal.SIGSTOP)
        t_stop = time.monotonic()
        try:
            self.gesture('circle_cw', 0.035)
            land_after = rospy.get_param('/drone_pilot/land_after')
            timeout = rospy.get_param('/drone_pilot/navdata_timeout', 0.5)
            self.assertTrue(wait_for(lambda: self.rec['land']
                                     and self.rec['land'][-1][0] > t_stop,
                                     timeout + land_after + 3.0), 'no landing')
            t_land = [t for t, _ in self.rec['land'] if t > t_stop][0]
            after = [(t, twist_tuple(m)) for t, m in self.rec['twist'] if t > t_stop]
            hovers = [t for t, tw in after if tw == ZERO]
            self.assertTrue(hovers, 'no hover after the hang')
            t_hover = hovers[0]
            rospy.loginfo('FAULT sim SIGSTOP: hover %.2f s, land %.2f s after; %d hovers',
                          t_hover - t_stop, t_land - t_stop, len(hovers))
            self.assertLess(t_hover - t_stop, timeout + lim.hover_slack_s)
            self.assertGreaterEqual(len(hovers), lim.min_hovers)
            self.assertFalse([tw for t, tw in after if t > t_hover and tw != ZERO])
            self.assertGreater(t_land - t_hover, land_after - lim.land_early_s)
            self.assertLess(t_land - t_hover, land_after + lim.land_late_s)
            # The flip call that never got an answer is reported, the pilot says why.
            self.assertTrue(wait_for(lambda: self.diag('drone_pilot')[0] is not None
                                     and self.diag('drone_pilot')[0] > t_land,
                                     lim.landing_report_within_s))
            _, st = self.diag('drone_pilot')
            values = {kv.key: kv.value for kv in st.values}
            self.assertIn('no navdata', st.message)
            unanswered = int(values['flip calls timeout']) + int(values['flip calls failed'])
            self.assertEqual(unanswered, lim.unanswered_flips, values)
            self.assertEqual(values['worker faults'], '0')
        finally:
            os.kill(sim_pid, signal.SIGCONT)


if __name__ == '__main__':
    rospy.init_node('fault_drone_check')
    rostest.rosrun('leap_teleop', 'fault_drone_check', FaultDrone, sys.argv)
