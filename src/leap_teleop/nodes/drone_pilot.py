"""drone_subscriber: flies an AR.Drone (ardrone_autonomy interface) from Leap hand gestures.

Reads leap_teleop/Hand (~hand_topic) and leap_teleop/GestureEvent (~gesture_topic, only
events of ~side) and ardrone/navdata; publishes cmd_vel, ardrone/takeoff, ardrone/land
and calls ardrone/setflightanimation. unfold = takeoff, fold = land, circle = flip;
~mode tilt (palm offset -> tilt) or paper (the paper's Algorithm 1). Callbacks only
queue commands; a worker thread publishes them and calls the service. See
leap_teleop.drone.pilot for the mapping and the watchdog. Rejected Hand messages
(non-finite, out of order, late) are counted and reported on /diagnostics.
"""
import threading
import time

import diagnostic_updater
import rospy
from diagnostic_msgs.msg import DiagnosticStatus
from geometry_msgs.msg import Twist
from std_msgs.msg import Empty

from leap_teleop.drone.pilot import DronePilot, HandInput, PilotConfig
from leap_teleop.msg import GestureEvent, Hand, Navdata
from leap_teleop.nodes.common import Param, RateLimitedLog, start_node
from leap_teleop.srv import FlightAnim

_C = PilotConfig()
PARAMS = {
    'mode': Param(_C.mode, 'tilt (palm offset -> tilt, dead zone, clamps) or paper '
                           '(Algorithm 1 exactly)'),
    'side': Param('right', 'hand to follow: right or left'),
    'hand_topic': Param('', 'Hand topic (default leapmotion/hand_<side>)'),
    'gesture_topic': Param('leapmotion/gestures', 'GestureEvent topic'),
    'rate': Param(_C.rate, 'max twist publishing rate, Hz (queue drain rate)'),
    'queue_size': Param(_C.queue_size, 'command FIFO bound (oldest twist dropped when full)'),
    'flip_type': Param(_C.flip_type, 'flight animation for a circle gesture (19 = flip right)'),
    'flip_duration': Param(_C.flip_duration, 'its duration, ms (0 = default)'),
    'flip_min_altitude': Param(_C.flip_min_altitude, 'no flip below this altitude, m'),
    'flip_min_radius': Param(_C.flip_min_radius, 'no flip on a smaller circle, m (fingertip '
                                                 'loops are 4-20 mm)'),
    'hand_timeout': Param(_C.hand_timeout, 's without a Hand message = hand lost (hover)'),
    'land_after': Param(_C.land_after, 's of lost hand before landing'),
    'dead_zone': Param(_C.dead_zone, 'tilt: horizontal palm dead zone, m'),
    'full_scale': Param(_C.full_scale, 'tilt: offset beyond the dead zone for full tilt, m'),
    'z_dead_zone': Param(_C.z_dead_zone, 'tilt: vertical dead zone, m'),
    'z_full_scale': Param(_C.z_full_scale, 'tilt: offset beyond it for full climb rate, m'),
    'yaw_dead_zone': Param(_C.yaw_dead_zone, 'tilt: hand yaw dead zone, deg'),
    'yaw_full_scale': Param(_C.yaw_full_scale, 'tilt: yaw beyond it for full yaw rate, deg'),
    'max_cmd': Param(_C.max_cmd, 'tilt: cap on every cmd_vel component (0..1)'),
    'max_input_age': Param(_C.max_input_age, 'drop a Hand arriving this much later than the '
                                             'stream\'s best latency, s (0 = off)'),
    'service_timeout': Param(0.5, 'wait for ardrone/setflightanimation at most this long, s'),
}
SIDE_CODES = {'right': Hand.SIDE_RIGHT, 'left': Hand.SIDE_LEFT}


class DronePilotNode:
    def __init__(self, p):
        if p['side'] not in SIDE_CODES:
            raise ValueError('~side must be right or left, got %r' % p['side'])
        self.p = p
        self.side = SIDE_CODES[p['side']]
        self.log = RateLimitedLog(2.0)
        cfg = PilotConfig().update({k: v for k, v in p.items()})
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
        self.diagnostics = diagnostic_updater.Updater()
        self.diagnostics.setHardwareID('drone_pilot_%s' % p['side'])
        self.diagnostics.add('pilot', self.diagnose)
        self._stop = threading.Event()
        self.worker = threading.Thread(target=self.run_worker, name='drone_pilot', daemon=True)

    # -- callbacks: convert and queue, nothing else -----------------------------------
    def on_hand(self, msg):
        if msg.side != self.side:      # the other hand on this hand's topic: miswired
            self.pilot.rejected_inputs += 1
            self.log.warn('side', 'pilot: ignored a Hand of side %d on %s (following side %d)',
                          msg.side, self.hand_topic, self.side)
            return
        p, n, d = msg.palm_position, msg.palm_normal, msg.direction
        self.pilot.on_hand(HandInput(msg.present, (p.x, p.y, p.z), (n.x, n.y, n.z),
                                     (d.x, d.y, d.z), msg.header.stamp.to_sec()),
                           rospy.get_time())

    def on_gesture(self, msg):
        if msg.side == self.side:
            self.pilot.on_gesture(msg.gesture, msg.active, rospy.get_time(), msg.value)

    def on_navdata(self, msg):
        self.pilot.on_navdata(msg.state, msg.altd)

    # -- worker: the only place that publishes or calls services ----------------------
    def run_worker(self):
        while not self._stop.is_set() and not rospy.is_shutdown():
            self.pilot.watchdog(rospy.get_time())
            self.diagnostics.update()
            cmd, wait = self.pilot.pop(time.monotonic())
            if cmd is None:
                if wait:
                    time.sleep(min(wait, 0.02))
                else:
                    self.pilot.queue.wait(0.02)
                continue
            try:
                self.execute(cmd)
            except rospy.ROSException as e:     # shutting down, or the publisher closed
                self.log.warn('publish', 'pilot: could not send %s: %s', cmd.kind, e)

    def execute(self, cmd):
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
        elif cmd.kind == 'flip':
            try:
                self.flip_srv.wait_for_service(self.p['service_timeout'])
                ok = self.flip_srv(*cmd.anim).result
            except (rospy.ROSException, rospy.ServiceException) as e:
                self.log.warn('flip', 'pilot: ardrone/setflightanimation failed: %s', e)
                return
            rospy.loginfo('pilot: flight animation %d -> %s', cmd.anim[0], ok)

    def diagnose(self, stat):
        pl = self.pilot
        lost = pl.lost_since is not None
        stat.summary(DiagnosticStatus.WARN if lost and pl.drone_state in (3, 4, 6, 7, 9)
                     else DiagnosticStatus.OK,
                     'hand %s, drone state %s' % ('lost' if lost else 'tracked'
                                                  if pl.hand_present else 'not seen yet',
                                                  pl.drone_state))
        stat.add('rejected inputs', pl.rejected_inputs)
        stat.add('twists superseded or dropped', pl.queue.dropped)
        stat.add('twists published', self.published)
        return stat

    def start(self):
        self.worker.start()

    def stop(self):
        self._stop.set()
        self.pilot.queue.wake()


def main(argv=None):
    p, node = start_node('drone_subscriber.py', 'drone_pilot', __doc__, PARAMS, DronePilotNode,
                         argv)
    rospy.on_shutdown(node.stop)
    node.start()
    rospy.loginfo('drone_pilot: %s mode, following the %s hand', p['mode'], p['side'])
    rospy.spin()
