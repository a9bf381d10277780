"""The leap_motion driver's topics, published by the sender on request: DriverHuman raw and
low-pass filtered, and its visualizer's RViz markers."""
import genpy
import rospy
from visualization_msgs.msg import MarkerArray

from leap_teleop.control.lowpass import LowPass
from leap_teleop.msg import DriverHuman
from leap_teleop.params import ParamError
from leap_teleop.ros import hand_conversions
from leap_teleop.ros.markers import driver_markers
from leap_teleop.ros.node import RateLimitedLog

# What publish() raises for a message that cannot be serialised: a float beyond float32
# (OverflowError, which rospy passes on), an integer beyond its field (SerializationError,
# which rospy wraps), a value of the wrong type (ValueError).
SERIALIZATION_ERRORS = (OverflowError, ValueError, genpy.SerializationError,
                        rospy.ROSSerializationException)


def use_driver_globals(p, table):
    """The leap_motion driver's own parameters, which its nodes read by absolute name (its
    demo.launch loads them at the root): /filter_cutoff stands for an unset ~filter_cutoff
    (one info line; checked as it is); /enable_filter cannot switch ~filtered_human_topic,
    so a value that disagrees with it is named as ignored (one warning). Updates p."""
    if rospy.has_param('/filter_cutoff'):
        value = rospy.get_param('/filter_cutoff')
        if not rospy.has_param('~filter_cutoff'):
            try:
                p['filter_cutoff'] = table['filter_cutoff'].check('filter_cutoff', value)
            except ParamError as e:
                raise ParamError('the driver\'s /filter_cutoff, used as ~filter_cutoff is not '
                                 'set: %s' % e)
            rospy.loginfo('sender: ~filter_cutoff not set: using the leap_motion driver\'s '
                          '/filter_cutoff = %g', p['filter_cutoff'])
        elif value != p['filter_cutoff']:
            rospy.logwarn('sender: the leap_motion driver\'s /filter_cutoff = %r is ignored: '
                          '~filter_cutoff = %g is set', value, p['filter_cutoff'])
    if rospy.has_param('/enable_filter'):
        value = rospy.get_param('/enable_filter')
        if value is not bool(p['filtered_human_topic']):
            rospy.logwarn('sender: the leap_motion driver\'s /enable_filter = %r is ignored: the '
                          'filtered Human is %s (~filtered_human_topic; leap_motion.launch: '
                          'enable_filter:=true / false)', value,
                          'on ' + p['filtered_human_topic'] if p['filtered_human_topic'] else 'off')
    return p


class LeapMotionTopics:
    """The leap_motion driver's topics: DriverHuman raw and filtered, and its visualizer's
    markers. Each is built only while it has subscribers; the filter forgets its history
    while nobody reads the filtered Human (it restarts from the next frame), and the builder
    its hands' time_visible and the frame rate while nobody reads either Human."""

    def __init__(self, p, queue_size):
        self.builder = hand_conversions.DriverHumanBuilder(p['frame_id'])
        self.lowpass = LowPass(p['filter_cutoff'])
        self.pubs = {}
        for kind, topic, msg_type in (('raw', p['human_topic'], DriverHuman),
                                      ('filtered', p['filtered_human_topic'], DriverHuman),
                                      ('markers', p['driver_marker_topic'], MarkerArray)):
            if topic:
                self.pubs[kind] = rospy.Publisher(topic, msg_type, queue_size=queue_size)
        self.log = RateLimitedLog()

    def _wanted(self, kind):
        pub = self.pubs.get(kind)
        return pub is not None and pub.get_num_connections() > 0

    def on_frame(self, frame, states):
        # Every frame, whatever ~freq (the old sender's throttle): the driver publishes each
        # one, and its filter's cut-off is relative to the frame rate.
        markers = self._wanted('markers')
        filtered = self._wanted('filtered') or (markers and 'filtered' in self.pubs)
        raw = self._wanted('raw') or (markers and not filtered)
        if not (raw or filtered):
            self.lowpass.reset()
            self.builder.reset()        # it sees no frames now: time_visible, rate go stale
            return
        if not filtered:
            self.lowpass.reset()
        human, smooth = self.builder.human_msgs(frame, states, raw=raw,
                                                lowpass=self.lowpass if filtered else None)
        if human is not None and 'raw' in self.pubs:
            self._publish('raw', human, frame)
        if smooth is not None and 'filtered' in self.pubs:
            self._publish('filtered', smooth, frame)
        if markers:
            try:
                msg = driver_markers(smooth or human)
            except ValueError as e:
                self.log.warn('markers', 'sender: no driver markers for frame %d: %s',
                              frame.id, e)
            else:
                self._publish('markers', msg, frame)

    def _publish(self, kind, msg, frame):
        """Publish; a message that cannot be serialised (a value no source should give) drops
        this frame's message with a warning: raised, it ended the sender."""
        pub = self.pubs[kind]
        try:
            pub.publish(msg)
        except SERIALIZATION_ERRORS as e:
            # rospy clears its publisher's buffer only after a message went out: the failed
            # one's bytes would go out in front of the next and break every connection.
            impl = getattr(pub, 'impl', None)
            if getattr(impl, 'buff', None) is not None:
                impl.acquire()
                try:
                    impl.buff.seek(0)
                    impl.buff.truncate(0)
                finally:
                    impl.release()
            self.log.warn('serialize ' + kind, 'sender: frame %d dropped from %s: it cannot be '
                          'serialised (%s)', frame.id, pub.resolved_name, e)
