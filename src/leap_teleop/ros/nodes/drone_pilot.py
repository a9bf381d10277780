"""drone_pilot: flies an AR.Drone (ardrone_autonomy interface) from Leap hand gestures.

Reads leap_teleop/Hand (~hand_topic) and leap_teleop/GestureEvent (~gesture_topic, only
events of ~side) and ardrone/navdata; publishes cmd_vel, ardrone/takeoff, ardrone/land
and calls ardrone/setflightanimation. unfold = takeoff, fold = land, circle = flip;
~mode tilt (palm offset -> tilt) or paper (the paper's Algorithm 1). Callbacks only
queue commands; a worker thread runs the watchdog and publishes them; the flip service
call runs on a thread of its own and is abandoned after ~service_timeout, so a hung
simulator or driver never stops a hover or a landing. Without navdata for
~navdata_timeout the drone state is unknown: no takeoff, hover, land after ~land_after.
See leap_teleop.drone.pilot for the mapping and the watchdogs. Rejected Hand messages
(non-finite, out of order, late), worker faults and flip call outcomes are counted and
reported on /diagnostics. RECONFIGURABLE parameters (dead zones, scales, the command cap,
the flip's thresholds) can be changed while running with dynamic_reconfigure; modes, rates,
watchdog times and topics are start-up only.
"""
import threading
import time

import diagnostic_updater
import rospy
from diagnostic_msgs.msg import DiagnosticStatus
from geometry_msgs.msg import Twist
from std_msgs.msg import Empty

from leap_teleop.control.input_age import InputAgeWindow
from leap_teleop.drone.pilot import DronePilot, PilotConfig, PilotInput, PilotWorker
from leap_teleop.drone.pilot_params import PILOT_NODE_PARAMS, PILOT_RECONFIGURABLE
from leap_teleop.msg import GestureEvent, Hand, Navdata
from leap_teleop.ros.node import RateLimitedLog, start_node
from leap_teleop.ros.reconfigure import Reconfigure
from leap_teleop.ros.service_call import ServiceCall
from leap_teleop.ros.signals import closed_at_shutdown
from leap_teleop.srv import FlightAnim

# The declarations live beside the pilot they configure; re-exported for --help and the docs.
PARAMS = PILOT_NODE_PARAMS
RECONFIGURABLE = PILOT_RECONFIGURABLE
SIDE_CODES = {'right': Hand.SIDE_RIGHT, 'left': Hand.SIDE_LEFT}
LEVELS = {'ok': DiagnosticStatus.OK, 'warn': DiagnosticStatus.WARN,
          'error': DiagnosticStatus.ERROR}


class DronePilotNode:
    def __init__(self, p):
        self.p = p
        self.side = SIDE_CODES[p['side']]
        self.log = RateLimitedLog(2.0)
        cfg = PilotConfig().update(p)
        self.pilot = DronePilot(cfg, warn=lambda key, text: self.log.warn(key, 'pilot: %s', text))
        self.cmd_pub = rospy.Publisher('cmd_vel', Twist, queue_size=10)
        self.takeoff_pub = rospy.Publisher('ardrone/takeoff', Empty, queue_size=2)
        self.land_pub = rospy.Publisher('ardrone/land', Empty, queue_size=2)
        self.flip_srv = rospy.ServiceProxy('ardrone/setflightanimation', FlightAnim)
        hand_topic = p['hand_topic'] or 'leapmotion/hand_%s' % p['side']
        self.hand_topic = rospy.resolve_name(hand_topic)
        rospy.Subscriber(hand_topic, Hand, self.on_hand, queue_size=5, tcp_nodelay=True)
        rospy.Subscriber(p['gesture_topic'], GestureEvent, self.on_gesture, queue_size=50)
        rospy.Subscriber('ardrone/navdata', Navdata, self.on_navdata, queue_size=5)
        self.published = 0
        self.input_age = InputAgeWindow()      # worker thread only (execute, diagnose)
        self.diagnostics = diagnostic_updater.Updater()
        self.diagnostics.setHardwareID('drone_pilot_%s' % p['side'])
        self.diagnostics.add('pilot', self.diagnose)
        self.flip_call = ServiceCall(self.call_flip, p['service_timeout'], 'flip')
        self.worker = PilotWorker(self.pilot, self.execute, self.flip_call, rospy.get_time,
                                  warn=lambda key, text: self.log.warn(key, 'pilot: %s', text),
                                  info=lambda text: rospy.loginfo('pilot: %s', text),
                                  extra=self.diagnostics.update)
        self._stop = threading.Event()
        self.thread = threading.Thread(target=self.run_worker, name='drone_pilot', daemon=True)

    # -- callbacks: convert and queue, nothing else -----------------------------------
    def on_hand(self, msg):
        if msg.side != self.side:      # the other hand on this hand's topic: miswired
            self.pilot.rejected_inputs += 1
            self.log.warn('side', 'pilot: ignored a Hand of side %d on %s (following side %d)',
                          msg.side, self.hand_topic, self.side)
            return
        p, n, d = msg.palm_position, msg.palm_normal, msg.direction
        self.pilot.on_hand(PilotInput(msg.present, (p.x, p.y, p.z), (n.x, n.y, n.z),
                                     (d.x, d.y, d.z), msg.header.stamp.to_sec()),
                           rospy.get_time())

    def on_gesture(self, msg):
        if msg.side == self.side:
            self.pilot.on_gesture(msg.gesture, msg.active, rospy.get_time(), msg.value,
                                  msg.header.stamp.to_sec())

    def on_navdata(self, msg):
        self.pilot.on_navdata(msg.state, msg.altd, rospy.get_time())

    # -- worker: the only thread that publishes; service calls run on their own ---------
    def run_worker(self):
        with closed_at_shutdown():
            while not self._stop.is_set() and not rospy.is_shutdown():
                wait = self.worker.step()
                if wait and len(self.pilot.queue):
                    time.sleep(wait)           # a twist waits for its slot (pacing)
                elif wait:
                    self.pilot.queue.wait(wait)

    def execute(self, cmd):
        """Publish one command (takeoff / land / twist); never blocks."""
        if cmd.kind == 'twist':
            t = Twist()
            t.linear.x, t.linear.y, t.linear.z, t.angular.x, t.angular.y, t.angular.z = cmd.twist
            self.cmd_pub.publish(t)
            self.published += 1
        elif cmd.kind == 'takeoff':
            rospy.loginfo('pilot: takeoff')
            self.takeoff_pub.publish(Empty())
        elif cmd.kind == 'land':
            rospy.loginfo('pilot: land')
            self.land_pub.publish(Empty())
        self.input_age.add(rospy.get_time(), cmd.input_stamp)

    def call_flip(self, anim_type, duration):
        """On the flip call's own thread (ServiceCall): may block, the worker does not wait."""
        self.flip_srv.wait_for_service(self.p['service_timeout'])
        return self.flip_srv(anim_type, duration).result

    def diagnose(self, stat):
        level, summary, values = self.worker.diagnostics(rospy.get_time())
        stat.summary(LEVELS[level], summary)
        values += [('twists published', self.published)]
        for key, value in values + self.input_age.diagnostic_values(rospy.get_time()):
            stat.add(key, value)
        return stat

    def start_reconfigure(self):
        def apply(changes):
            for name, value in changes.items():
                setattr(self.pilot.cfg, name, value)
        self.reconfigure = Reconfigure('drone_pilot', PARAMS, RECONFIGURABLE,
                                       {k: getattr(self.pilot.cfg, k) for k in RECONFIGURABLE},
                                       apply)

    def start(self):
        self.thread.start()

    def stop(self):
        self._stop.set()
        self.pilot.queue.wake()


def main(argv=None):
    p, node = start_node('drone_pilot.py', 'drone_pilot', __doc__, PARAMS, DronePilotNode,
                         argv)
    rospy.on_shutdown(node.stop)
    try:
        if not rospy.core.is_shutdown_requested():
            node.start_reconfigure()
            node.start()
            rospy.loginfo('drone_pilot: %s mode, following the %s hand', p['mode'], p['side'])
            rospy.spin()
    finally:
        node.stop()             # also when a signal came before on_shutdown was registered
