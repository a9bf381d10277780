"""drone_pilot: flies an AR.Drone (ardrone_autonomy interface) from Leap hand gestures.

Reads leap_teleop/Hand (~hand_topic), GestureEvent (~gesture_topic, of ~side) and
ardrone/navdata; publishes cmd_vel, ardrone/takeoff and ardrone/land, and calls
ardrone/setflightanimation: unfold = takeoff, fold = land, circle = flip; ~mode tilt (palm
offset -> tilt) or paper (the original drone paper's, see the README). Callbacks only queue;
a worker thread runs the watchdog and publishes (a takeoff or land waits for the driver, a
takeoff at most ~takeoff_hold; the flip call has its own thread, abandoned after
~service_timeout; an ending pilot sends a zero twist: the driver holds the last). No navdata
for ~navdata_timeout: no takeoff, hover, land after ~land_after. Rejections, faults and flip
outcomes go to /diagnostics; the parameters --help marks live change while it runs.
"""
import threading

import rospy

from leap_teleop.control.service_call import ServiceCall
from leap_teleop.drone.pilot import DronePilot, PilotParams, PilotWorker
from leap_teleop.drone.pilot_params import PILOT_NODE_PARAMS as PARAMS
from leap_teleop.drone.pilot_params import PILOT_PARAMS
from leap_teleop.drone.pilot_params import PILOT_RECONFIGURABLE as RECONFIGURABLE
from leap_teleop.msg import Hand
from leap_teleop.ros import drone_conversions, hand_conversions
from leap_teleop.ros.ardrone_commands import ArdroneCommands
from leap_teleop.ros.diagnostics import diagnostics_updater
from leap_teleop.ros.drone_inputs import subscribe_pilot_inputs
from leap_teleop.ros.hand_subscription import HandSubscription
from leap_teleop.ros.node import RateLimitedLog, start_node
from leap_teleop.ros.reconfigure import Reconfigure
from leap_teleop.ros.signals import closed_at_shutdown


class DronePilotNode:
    def __init__(self, p):
        self.side, self.name = hand_conversions.SIDE_CODES[p['side']], rospy.get_name().lstrip('/')
        self.log = RateLimitedLog(2.0)
        self.pilot = DronePilot(PilotParams().update({k: p[k] for k in PILOT_PARAMS}), warn=self.warn)
        self.commands = ArdroneCommands(p['service_timeout'], p['takeoff_hold'], lambda: (
            self.pilot.takeoff_still_wanted(rospy.get_time())), self.warn)
        hand_topic = p['hand_topic'] or hand_conversions.default_topics(p['side'])['hand']
        self.hand_topic = rospy.resolve_name(hand_topic)
        self.hand_sub = HandSubscription(hand_topic, Hand, self.on_hand, self.name, p,
                                         self.pilot.new_input_connection)
        self.type_watch = subscribe_pilot_inputs(hand_topic, p['gesture_topic'], p['side'],
                                                 self.on_gesture, self.on_navdata, self.log)
        self.diagnostics = diagnostics_updater('drone_pilot_%s' % p['side'], 'pilot', self.report,
                                               self.commands.input_age)
        self.worker = PilotWorker(self.pilot, self.commands.send,
                                  ServiceCall(self.commands.flip, p['service_timeout'], 'flip'),
                                  rospy.get_time, warn=self.warn, extra=self.diagnostics.update,
                                  info=lambda text: rospy.loginfo('%s: %s', self.name, text),
                                  send_held=self.commands.send_held)
        self._stop = threading.Event()
        self.thread = threading.Thread(target=self.run_worker, name='drone_pilot', daemon=True)

    def warn(self, key, text):
        self.log.warn(key, '%s: %s', self.name, text)

    # -- callbacks: convert and queue, nothing else -----------------------------------
    def on_hand(self, msg):
        if msg.side != self.side:      # the other hand on this hand's topic: miswired
            self.pilot.rejected_inputs += 1
            self.log.warn('side', '%s: ignored a Hand of side %d on %s (following side %d)',
                          self.name, msg.side, self.hand_topic, self.side)
            return 'side %d' % msg.side
        return self.pilot.on_hand(drone_conversions.pilot_input(msg), rospy.get_time())

    def on_gesture(self, msg):
        if msg.side not in hand_conversions.SIDE_CODES.values():
            self.log.warn('gesture_side', '%s: ignored GestureEvent %r of side %d (0 right, 1 left)',
                          self.name, msg.gesture, msg.side)
        elif msg.side == self.side:     # the other hand's events share the topic
            self.pilot.on_gesture(msg.gesture, msg.active, rospy.get_time(), msg.value,
                                  msg.header.stamp.to_sec())

    def on_navdata(self, msg):
        self.pilot.on_navdata(msg.state, msg.altd, rospy.get_time())

    # -- the worker: the only thread that publishes (the flip call runs on its own) ------
    def run_worker(self):
        with closed_at_shutdown():
            self.worker.run(lambda: self._stop.is_set() or rospy.is_shutdown())

    def report(self):     # the diagnostics, on the worker's thread (its `extra`)
        level, summary, values = self.worker.diagnostics(rospy.get_time())
        return level, summary, values + self.commands.diagnostic_values() + self.hand_sub.diagnostic_values()

    def retune(self, changes):
        vars(self.pilot.cfg).update(changes)

    def stop(self):     # in rospy's shutdown hook, while the topics are open for the last hover
        self._stop.set()
        self.pilot.queue.wake()
        if self.thread.ident is not None and self.thread.is_alive():
            self.thread.join(1.0)
            self.commands.flush(0.5)    # the hover leaves on rospy's sender thread


def main(argv=None):
    p, node = start_node('drone_pilot.py', 'drone_pilot', __doc__, PARAMS, DronePilotNode, argv)
    rospy.on_shutdown(node.stop)
    try:
        if not rospy.core.is_shutdown_requested():
            node.reconfigure = Reconfigure(node.name, PARAMS, RECONFIGURABLE, vars(node.pilot.cfg),
                                           node.retune)
            node.thread.start()
            rospy.loginfo('%s: %s mode, following the %s hand', node.name, p['mode'], p['side'])
            rospy.spin()
    finally:
        node.stop()             # also when a signal came before on_shutdown was registered
