"""hand_markers: the sender's rich Hand messages -> RViz markers.

Subscribes leap_teleop/Hand on each of ~hand_topics (default leapmotion/hand_right and
leapmotion/hand_left) and publishes visualization_msgs/MarkerArray on ~marker_topic:
palm and fingertip spheres, palm -> tip lines, a palm-normal arrow and a label, coloured
by the recognised state (grey open, red fist, green thumbs-up, blue pinch, yellow rock,
purple thumbs-down),
deleted when the hand leaves. The frame is the message's (leap_hands; the sender
publishes the static TF world -> leap_hands). With ~latency_text, a text marker above the
hands (namespace 'latency', once a second) shows the input ages reported on /diagnostics:
the sender's capture -> published and each arm's and pilot's capture -> command, p50 / p99.
A /clock that stopped leaves it a minute at most (it is then refreshed on wall time).
"""
import threading

import rospy
from visualization_msgs.msg import MarkerArray

from leap_teleop.msg import Hand
from leap_teleop.params import Param
from leap_teleop.ros.graph import TopicTypeWatch
from leap_teleop.ros.latency_monitor import LatencyMonitor
from leap_teleop.ros.markers import HandMarkerThrottle, latency_marker
from leap_teleop.ros.node import RateLimitedLog, start_node
from leap_teleop.ros.signals import closed_at_shutdown

PARAMS = {
    'hand_topics': Param(['leapmotion/hand_right', 'leapmotion/hand_left'],
                         'leap_teleop/Hand topics to draw', min_length=1, empty_ok=False, ros_name=True),
    'marker_topic': Param('leapmotion/hand_markers', 'MarkerArray output topic',
                          empty_ok=False, ros_name=True),
    'max_rate': Param(30.0, 'max marker updates per hand (state changes and deletes always '
                            'go out); 0 = every message', unit='Hz', ge=0.0, le=1000.0),
    'lifetime': Param(0.5, 'marker lifetime, so markers vanish when input stops; 0 = forever',
                      unit='s', ge=0.0, le=3600.0),
    'frame_id': Param('', 'frame for the markers; empty = the Hand message\'s frame'),
    'scale': Param(1.0, 'size factor for spheres, lines and text', gt=0.0, le=100.0),
    'latency_text': Param(True, 'show the input ages from /diagnostics (capture -> published, '
                                'capture -> command) as a text marker'),
    'latency_frame': Param('leap_hands', 'frame of the latency text', empty_ok=False),
    'latency_position': Param([0.0, 0.4, 0.3], 'where the latency text stands in latency_frame '
                              '(leap_hands: y up, z toward the user): above the hands, in front',
                              unit='m', length=3, ge=-100.0, le=100.0),
}


class HandMarkersNode:
    def __init__(self, p):
        if rospy.resolve_name(p['marker_topic']) in map(rospy.resolve_name, p['hand_topics']):
            raise ValueError('~marker_topic %r is one of ~hand_topics: markers and hands need '
                             'topics of their own' % p['marker_topic'])
        self.throttle = HandMarkerThrottle(float(p['max_rate']), str(p['frame_id']),
                                           float(p['lifetime']), float(p['scale']))
        self.pub = rospy.Publisher(p['marker_topic'], MarkerArray, queue_size=10)
        self.log = RateLimitedLog()
        self.type_watch = TopicTypeWatch('hand_markers', self.log)
        self.subs = [self.type_watch.subscribe(t, Hand, self.on_hand, 'hand_markers', 'no hand is drawn; '
                                               'give ~hand_topics the sender\'s Hand topics', queue_size=5)
                     for t in p['hand_topics']]
        self.p = p
        self.latency_shown = False
        if p['latency_text']:
            self.latency, self.latency_lock = LatencyMonitor(), threading.Lock()
            # reset: survives a /clock jumping back (a looped bag)
            self.timer = rospy.Timer(rospy.Duration(1.0), self.on_latency_timer, reset=True)
            # A stopped /clock stops that timer and RViz's marker expiry: the text stayed for ever.
            self.closing = threading.Event()
            rospy.on_shutdown(self.closing.set)
            threading.Thread(target=self.while_clock_stopped, daemon=True).start()

    def while_clock_stopped(self):
        """The latency text each wall second ROS time stands still (till shutdown or time unset)."""
        last = rospy.get_time()
        while not self.closing.wait(1.0) and rospy.rostime.is_rostime_initialized():
            before, last = last, rospy.get_time()
            if last == before:
                self.on_latency_timer(None)

    def on_latency_timer(self, _event):
        with self.latency_lock:                # the timer's thread and while_clock_stopped's
            now = rospy.get_time()
            try:                # an exception would end the timer's thread for good
                lines = self.latency.notes()
            except Exception as e:  # noqa: BLE001 - logged; the next tick tries again
                rospy.logwarn_throttle(10.0, 'hand_markers: no latency text: %s' % e)
                return
            if lines or self.latency_shown:        # one DELETE once reports stop
                with closed_at_shutdown():         # a last tick can race the shutdown
                    self.pub.publish(MarkerArray([latency_marker(
                        lines, self.p['latency_frame'], self.p['latency_position'], now,
                        self.p['scale'])]))
            self.latency_shown = bool(lines)

    def on_hand(self, msg):
        try:
            out = self.throttle.update(msg, rospy.get_time())
        except ValueError as e:
            self.log.warn('bad-hand', 'hand_markers: skipping a Hand message: %s', e)
            return
        if out is not None:
            with closed_at_shutdown():         # a message can arrive while it shuts down
                self.pub.publish(out)


def main(argv=None):
    p, node = start_node('hand_markers.py', 'hand_markers', __doc__, PARAMS, HandMarkersNode,
                         argv)
    rospy.loginfo('hand_markers: %s -> %s', ', '.join(s.resolved_name for s in node.subs),
                  node.pub.resolved_name)
    rospy.spin()
