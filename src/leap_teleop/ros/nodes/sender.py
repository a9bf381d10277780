"""sender: hand source -> LeapInterface -> leapcobot / Hand / GestureEvent topics, and on
request the leap_motion driver's interface (DriverHuman raw and low-pass filtered, its RViz
markers, the old leap and leapros messages).

Publishes once per source frame from the source's thread (event-driven; no polling).
"""
import gc

import rospy
import tf2_ros
from geometry_msgs.msg import TransformStamped

from leap_teleop.hands.gestures.bindings import load_bindings
from leap_teleop.hands.leap_interface import LeapInterface
from leap_teleop.hands.sender_params import SENDER_PARAMS, SENDER_RECONFIGURABLE
from leap_teleop.hands.sender_setup import (
    PeriodThrottle,
    build_source,
    check_leapros,
    recognizer_factory,
    retune_recognizers,
)
from leap_teleop.hands.sources import SourceError
from leap_teleop.hands.tracker import DEAD_BANDS
from leap_teleop.msg import GestureEvent, Hand, leap, leapros
from leap_teleop.ros import conversions
from leap_teleop.ros.camera_topics import camera_model, camera_view
from leap_teleop.ros.driver_topics import DriverInterface
from leap_teleop.ros.graph import wait_for_subscribers
from leap_teleop.ros.node import package_path, start_node
from leap_teleop.ros.reconfigure import Reconfigure

# The declarations live beside the hand source and recognizer; re-exported for --help and
# the docs.
PARAMS = SENDER_PARAMS
RECONFIGURABLE = SENDER_RECONFIGURABLE
# Leap axes (x right, y up, z toward the user) in a ROS world frame (x forward, z up).
LEAP_IN_WORLD_XYZW = (0.5, -0.5, -0.5, 0.5)


class Sender:
    def __init__(self, p, interface):
        self.p = p
        self.sides = list(p['sides'])
        q = int(p['queue_size'])
        gestures = rospy.Publisher(p['gesture_topic'], GestureEvent, queue_size=q)
        self.pubs = {side: {'leapcobot': rospy.Publisher(p['leapcobot_topic_' + side],
                                                         conversions.LEAPCOBOT_TYPES[side],
                                                         queue_size=q),
                            'hand': rospy.Publisher(p['hand_topic_' + side], Hand, queue_size=q),
                            'gesture': gestures}
                     for side in self.sides}
        # One leapcobot message per side, refilled every frame (conversions.to_leapcobot).
        self._leapcobot = {side: conversions.LEAPCOBOT_TYPES[side]() for side in self.sides}
        self.throttle = PeriodThrottle(p['freq'])
        self.published = 0
        self.leapros_side = p['leapros_side']
        self.leapros = (rospy.Publisher(p['leapros_topic'], leapros, queue_size=q)
                        if p['leapros_topic'] else None)
        self.leap = (rospy.Publisher(p['leap_topic'], leap, queue_size=q)
                     if p['leap_topic'] else None)
        interface.add_hand_listener(self.on_hand)
        self.driver = DriverInterface(p, q)
        if self.driver.pubs:
            interface.add_listener(self.driver.on_frame)

    def wait_for_subscribers(self, topics=()):
        """Block until every topic in `topics` (default: every leapcobot topic) has a
        subscriber; False on shutdown."""
        own = {pub.resolved_name: pub for pubs in self.pubs.values() for pub in pubs.values()}
        for pub in [self.leapros, self.leap] + list(self.driver.pubs.values()):
            if pub is not None:
                own[pub.resolved_name] = pub
        names = [rospy.resolve_name(t) for t in topics] or [
            pubs['leapcobot'].resolved_name for pubs in self.pubs.values()]
        return wait_for_subscribers(own, names, 'sender')

    def on_hand(self, frame, state):
        """Publish one side's messages as soon as that side is recognised."""
        side = state.side
        pubs = self.pubs.get(side)
        if pubs is None or not self.throttle.due(side, frame.timestamp):
            return
        for kind, msg in conversions.hand_messages(state, self.p['frame_id'],
                                                   self._leapcobot[side]):
            pubs[kind].publish(msg)
        if side == self.leapros_side:
            if self.leapros is not None:
                self.leapros.publish(conversions.to_leapros(state, frame.hand(side),
                                                            self.p['frame_id']))
            if self.leap is not None:
                self.leap.publish(conversions.to_leap(state, self.p['frame_id']))
        self.published += 1


def retune(interface, sender, changes):
    """Apply checked changes of RECONFIGURABLE parameters to the running recognizers and
    the driver filter."""
    retune_recognizers(interface.recognizers().values(), changes)
    if 'filter_cutoff' in changes:
        sender.driver.lowpass.set_cutoff(changes['filter_cutoff'])


def publish_leap_tf(p):
    broadcaster = tf2_ros.StaticTransformBroadcaster()
    t = TransformStamped()
    t.header.stamp = rospy.Time.now()
    t.header.frame_id = p['world_frame']
    t.child_frame_id = p['frame_id']
    t.transform.translation.x, t.transform.translation.y, t.transform.translation.z = p['leap_xyz']
    r = t.transform.rotation
    r.x, r.y, r.z, r.w = LEAP_IN_WORLD_XYZW
    broadcaster.sendTransform(t)
    return broadcaster


def main(argv=None):
    def build(p):
        check_leapros(p)
        factory = recognizer_factory(p)
        bindings = load_bindings(p['gesture_bindings']).check(factory().user_gestures)
        view = camera_view(p)
        source = build_source(p, rospy.get_time, package_path('config', 'gestures', 'wave_hello.yaml'),
                              lambda: camera_model(p), view.on_image if view is not None else None)
        return source, view, factory, bindings
    p, (source, view, factory, bindings) = start_node(
        'sender.py', 'leap_sender', __doc__, PARAMS, build, argv, errors=(SourceError, ValueError))
    interface = LeapInterface(source, recognizer_factory=factory, sides=list(p['sides']),
                              dead_bands=DEAD_BANDS if p['rotation_dead_bands'] else None,
                              bindings=bindings)
    sender = Sender(p, interface)
    reconfigure = Reconfigure('sender', PARAMS, RECONFIGURABLE, p,  # noqa: F841 (kept alive)
                              lambda changes: retune(interface, sender, changes))
    if view is not None:
        interface.add_listener(view.on_frame)    # after the hand messages: adds no latency
    tf_broadcaster = publish_leap_tf(p) if p['publish_tf'] else None  # noqa: F841 (kept alive for the latched topic)
    rospy.loginfo('sender: publishing %s hands from the %s source on %s',
                  '/'.join(sender.sides), p['source'],
                  ', '.join(pubs['leapcobot'].resolved_name for pubs in sender.pubs.values()))
    rospy.on_shutdown(interface.stop)
    # Everything built so far lives as long as the node: keep the cyclic collector off it,
    # so its passes stay short on the per-frame path.
    gc.collect()
    gc.freeze()
    try:
        if p['wait_for_subscribers'] and not sender.wait_for_subscribers(p['wait_topics']):
            return
        if rospy.core.is_shutdown_requested():
            return
        interface.start()
        while not rospy.is_shutdown() and not interface.finished.wait(0.2):
            pass
    finally:
        if rospy.core.is_shutdown_requested():
            interface.stop()    # also when a signal came before on_shutdown was registered
    if interface.error is not None:
        rospy.logerr('sender: the hand source failed: %s', interface.error)
    if interface.finished.is_set() and not rospy.is_shutdown():
        rospy.loginfo('sender: source ended after %d frames', interface.frames_seen)
        if p['shutdown_on_end']:
            rospy.sleep(0.5)   # let subscribers drain the last frames
            rospy.signal_shutdown('source ended')
        else:
            rospy.spin()
    if interface.error is not None:
        raise SystemExit(2)
