"""sender: hand source -> LeapInterface -> leapcobot / Hand / GestureEvent topics, and on
request the leap_motion driver's interface (DriverHuman raw and low-pass filtered, its RViz
markers, the old leap and leapros messages).

Publishes once per source frame from the source's thread (event-driven; no polling).
"""
import gc

import rosgraph
import rospy
import tf2_ros
from geometry_msgs.msg import TransformStamped
from visualization_msgs.msg import MarkerArray

from leap_teleop.control.lowpass import DEFAULT_CUTOFF, LowPass
from leap_teleop.hands.gestures import GestureRecognizer
from leap_teleop.hands.gestures.bindings import load_bindings
from leap_teleop.hands.gestures.recognizer import MIN_CONFIDENCE
from leap_teleop.hands.leap_interface import LeapInterface
from leap_teleop.hands.sources import SOURCES, SourceError, make_source
from leap_teleop.hands.sources.camera_params import CAMERA_PARAMS, CAMERA_SOURCES, camera_source_kwargs
from leap_teleop.hands.tracker import DEAD_BANDS
from leap_teleop.msg import DriverHuman, GestureEvent, Hand, leap, leapros
from leap_teleop.ros import conversions
from leap_teleop.ros.markers import driver_markers
from leap_teleop.ros.node import Param, RateLimitedLog, package_path, start_node
from leap_teleop.ros.nodes.reconfigure import Reconfigure

PARAMS = {
    'source': Param('scripted', 'hand source', choices=tuple(SOURCES)),
    'script': Param('', 'gesture script YAML for the scripted source '
                        '(default config/gestures/wave_hello.yaml)'),
    'recording': Param('', 'LeapJS recording (.json, .json.lz, .json.gz) for the recording source'),
    'rate': Param(0.0, 'scripted source frame rate; 0 = the script\'s own (video source: pace '
                       'at this many frames/s; 0 = the file\'s own)', unit='Hz',
                  ge=0.0, le=1000.0),
    'loop': Param(False, 'restart the script / recording when it ends'),
    'realtime': Param(True, 'pace frames at their recorded / scripted timing'),
    'freq': Param(0.0, 'the original sender\'s period; > 0 throttles publishing to at '
                       'most one frame per period; 0 = every frame', unit='s',
                  ge=0.0, le=10.0),
    'sides': Param(['right', 'left'], 'hands to publish (one side: right, or [right])',
                   min_length=1, choices=('right', 'left')),
    'leapcobot_topic_right': Param('leapmotion/data_right', 'leapcobotright topic',
                                   empty_ok=False),
    'leapcobot_topic_left': Param('leapmotion/data_left', 'leapcobotleft topic',
                                  empty_ok=False),
    'hand_topic_right': Param('leapmotion/hand_right', 'rich Hand topic, right',
                              empty_ok=False),
    'hand_topic_left': Param('leapmotion/hand_left', 'rich Hand topic, left', empty_ok=False),
    'gesture_topic': Param('leapmotion/gestures', 'GestureEvent topic (both hands)',
                           empty_ok=False),
    'frame_id': Param('leap_hands', 'frame of the hand messages', empty_ok=False),
    'world_frame': Param('world', 'parent frame of the static TF to frame_id', empty_ok=False),
    'leap_xyz': Param([0.0, 0.0, 0.0], 'Leap device position in world_frame', unit='m',
                      length=3, ge=-100.0, le=100.0),
    'shutdown_on_end': Param(True, 'shut the node down when a finite source ends'),
    # Bounded: a slow subscriber holds at most this many frames (~2 s at 120 Hz) per topic.
    'queue_size': Param(200, 'publisher queue size (frames buffered per subscriber)',
                        ge=1, le=1000),
    'leapros_topic': Param('', 'topic for the classic leap_motion/leapros message (as that '
                               'driver: leapmotion/data); empty = not published'),
    'leapros_side': Param('right', 'hand the leapros and leap messages carry (one of ~sides)',
                          choices=('right', 'left')),
    'leap_topic': Param('', 'topic for the old sender\'s leap_motion/leap message (that sender: '
                            'leapmotion/raw); empty = not published'),
    'human_topic': Param('', 'topic for the leap_motion driver\'s Human (DriverHuman; the '
                             'driver: leap_motion/leap_device); empty = not published'),
    'filtered_human_topic': Param('', 'topic for the low-pass filtered DriverHuman (the '
                                      'driver\'s filter node: leap_motion/filtered_values); '
                                      'empty = not published'),
    'filter_cutoff': Param(DEFAULT_CUTOFF, 'the driver\'s filter_cutoff c = cot(pi f_c / '
                                           'f_frames): 1 = a quarter of the frame rate, '
                                           'larger smooths more', gt=0.0, le=1000.0),
    'driver_marker_topic': Param('', 'topic for the driver visualizer\'s MarkerArray (the '
                                     'driver: leap_motion/visualization_marker_array), drawn '
                                     'from the filtered Human when that is published; empty = '
                                     'not published'),
    'publish_tf': Param(True, 'publish the static TF world_frame -> frame_id (one sender per '
                              'graph should)'),
    'wait_for_subscribers': Param(False, 'start the source only once every ~wait_topics topic '
                                         'has a subscriber (so a session is not lost while '
                                         'its consumers start)'),
    'wait_topics': Param([], 'topics the consumers read, to wait for; any topic of the graph '
                             '(e.g. the drone\'s ardrone/takeoff); empty = every published '
                             'leapcobot topic', kind='list', item='str'),
    'rotation_dead_bands': Param(True, 'rotate / turn / swing with the original dead bands '
                                       '(z +-0.40, y -0.15..0.35, x -0.05..0.45 rad); false: '
                                       'the raw rotation since the origin'),
    'gesture_model': Param('', 'Leap-family pose model (.npz, train_gestures --out); '
                               'empty = the shipped one'),
    'keypoint_model': Param('', 'camera keypoint pose model (.npz); empty = the shipped one'),
    'gesture_bindings': Param('', 'gesture -> action bindings YAML (see config/gestures/'
                                  'bindings/default.yaml); empty = those defaults'),
    'recognizer_on_frames': Param(3, 'gesture recognizer: frames a held gesture must be seen '
                                     'before it starts', ge=1, le=100),
    'recognizer_off_frames': Param(3, 'gesture recognizer: frames it must be gone before it '
                                      'stops', ge=1, le=100),
    'recognizer_min_confidence': Param(MIN_CONFIDENCE, 'gesture recognizer: frames of a lower '
                                                       'tracking confidence do not count',
                                       ge=0.0, le=1.0),
}
PARAMS.update(CAMERA_PARAMS)
# Changeable while running (dynamic_reconfigure): the recognizer's thresholds and the driver
# filter's cutoff. Sources, topics, sides and modes are start-up only.
RECONFIGURABLE = ('recognizer_on_frames', 'recognizer_off_frames', 'recognizer_min_confidence',
                  'filter_cutoff')
# Leap axes (x right, y up, z toward the user) in a ROS world frame (x forward, z up).
LEAP_IN_WORLD_XYZW = (0.5, -0.5, -0.5, 0.5)


def check_leapros(p):
    """ValueError when leapros / leap would carry a hand the sender does not publish."""
    if (p['leapros_topic'] or p['leap_topic']) and p['leapros_side'] not in p['sides']:
        raise ValueError('~leapros_side %r is not in ~sides %r' % (p['leapros_side'], p['sides']))


def camera_model(p, timeout=10.0):
    """CameraModel from one sensor_msgs/CameraInfo on ~camera_info_topic; None when unset."""
    if not p['camera_info_topic']:
        return None
    from sensor_msgs.msg import CameraInfo

    from leap_teleop.hands.sources.landmarks import CameraModel
    try:
        info = rospy.wait_for_message(p['camera_info_topic'], CameraInfo, timeout)
    except rospy.ROSException:
        raise SourceError('no sensor_msgs/CameraInfo on %s within %.0f s (~camera_info_topic)'
                          % (p['camera_info_topic'], timeout))
    try:
        return CameraModel.from_matrix(info.width, info.height, info.K)
    except ValueError as e:
        raise SourceError('~camera_info_topic %s: %s' % (p['camera_info_topic'], e))


def build_source(p, on_image=None):
    name = p['source']
    if name in CAMERA_SOURCES:
        if name == 'video' and not p['video']:
            raise SourceError('~source video needs ~video:=PATH (a video, an image, a folder '
                              'or a glob of images)')
        return make_source(name, **camera_source_kwargs(name, p, rospy.get_time,
                                                        camera_model(p), on_image))
    if name == 'scripted':
        script = p['script'] or package_path('config', 'gestures', 'wave_hello.yaml')
        return make_source('scripted', script=script, rate_hz=p['rate'] or None,
                           loop=p['loop'], realtime=p['realtime'], clock=rospy.get_time)
    if name == 'recording':
        if not p['recording']:
            raise SourceError('~source recording needs ~recording:=PATH to a LeapJS file')
        return make_source('recording', path=p['recording'], loop=p['loop'],
                           realtime=p['realtime'], clock=rospy.get_time)
    return make_source(name)


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
        self.period = float(p['freq'])
        self._last_sent = {}
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

    def wait_for_subscribers(self, topics=(), log_every=5.0):
        """Block until every topic in `topics` (default: every leapcobot topic) has a
        subscriber; False on shutdown. The sender's own topics count once connected, any
        other topic once the master lists a subscriber."""
        own = {pub.resolved_name: pub for pubs in self.pubs.values() for pub in pubs.values()}
        for pub in [self.leapros, self.leap] + list(self.driver.pubs.values()):
            if pub is not None:
                own[pub.resolved_name] = pub
        names = [rospy.resolve_name(t) for t in topics] or [
            pubs['leapcobot'].resolved_name for pubs in self.pubs.values()]
        master = rosgraph.Master(rospy.get_name())
        last_log = rospy.get_time()
        while not rospy.is_shutdown():
            others = [t for t in names if t not in own]
            listened = set()
            if others:
                try:
                    listened = {t for t, nodes in master.getSystemState()[1] if nodes}
                except (rosgraph.MasterError, OSError):
                    pass
            waiting = [t for t in names if (own[t].get_num_connections() == 0 if t in own
                                            else t not in listened)]
            if not waiting:
                return True
            if rospy.get_time() - last_log >= log_every:
                last_log = rospy.get_time()
                rospy.loginfo('sender: waiting for subscribers on %s', ', '.join(waiting))
            rospy.sleep(0.05)
        return False

    def on_hand(self, frame, state):
        """Publish one side's messages as soon as that side is recognised."""
        side = state.side
        pubs = self.pubs.get(side)
        if pubs is None:
            return
        if self.period > 0:
            last = self._last_sent.get(side)
            if last is not None and frame.timestamp - last < self.period:
                return
            self._last_sent[side] = frame.timestamp
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


class DriverInterface:
    """The leap_motion driver's topics: DriverHuman raw and filtered, and its visualizer's
    markers. Each is built only while it has subscribers; the filter forgets its history
    while nobody reads the filtered Human (it restarts from the next frame)."""

    def __init__(self, p, queue_size):
        self.builder = conversions.DriverHumanBuilder(p['frame_id'])
        self.lowpass = LowPass(p['filter_cutoff'])
        self.period = float(p['freq'])
        self._last_sent = None
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
        if self.period > 0:
            if self._last_sent is not None and frame.timestamp - self._last_sent < self.period:
                return
            self._last_sent = frame.timestamp
        markers = self._wanted('markers')
        filtered = self._wanted('filtered') or (markers and 'filtered' in self.pubs)
        raw = self._wanted('raw') or (markers and not filtered)
        if not (raw or filtered):
            self.lowpass.reset()
            return
        if not filtered:
            self.lowpass.reset()
        human, smooth = self.builder.build(frame, states, raw=raw,
                                           lowpass=self.lowpass if filtered else None)
        if human is not None and 'raw' in self.pubs:
            self.pubs['raw'].publish(human)
        if smooth is not None and 'filtered' in self.pubs:
            self.pubs['filtered'].publish(smooth)
        if markers:
            try:
                self.pubs['markers'].publish(driver_markers(smooth or human))
            except ValueError as e:
                self.log.warn('markers', 'sender: no driver markers for frame %d: %s',
                              frame.id, e)


def retune(interface, sender, changes):
    """Apply checked changes of RECONFIGURABLE parameters to the running recognizers and
    the driver filter (the source thread reads each per frame)."""
    for recognizer in interface.recognizers().values():
        if 'recognizer_on_frames' in changes:
            recognizer.filter.on_frames = changes['recognizer_on_frames']
        if 'recognizer_off_frames' in changes:
            recognizer.filter.off_frames = changes['recognizer_off_frames']
        if 'recognizer_min_confidence' in changes:
            recognizer.min_confidence = changes['recognizer_min_confidence']
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


def camera_view(p):
    """The annotated camera view (CameraView publishing on ~annotated_image_topic) when
    that is set and the source is a camera; else None."""
    if p['source'] not in CAMERA_SOURCES or not p['annotated_image_topic']:
        return None
    from sensor_msgs.msg import Image

    from leap_teleop.hands.camera_view import CameraView

    pub = rospy.Publisher(p['annotated_image_topic'], Image, queue_size=2)
    view = CameraView(p['mirror'] != p['input_mirrored'],
                      lambda frame, img: pub.publish(conversions.image_message(img, frame.timestamp,
                                                                   p['frame_id'])),
                      wanted=lambda: pub.get_num_connections() > 0)
    return view


def recognizer_factory(p):
    """A GestureRecognizer per hand with the ~gesture_model / ~keypoint_model (each model
    is loaded once; a bad one raises ModelError, a ValueError)."""
    def make():
        return GestureRecognizer(model=p['gesture_model'] or None,
                                 keypoint_model=p['keypoint_model'] or None,
                                 on_frames=p['recognizer_on_frames'],
                                 off_frames=p['recognizer_off_frames'],
                                 min_confidence=p['recognizer_min_confidence'])
    return make


def main(argv=None):
    def build(p):
        check_leapros(p)
        factory = recognizer_factory(p)
        bindings = load_bindings(p['gesture_bindings']).check(factory().user_gestures)
        view = camera_view(p)
        source = build_source(p, view.on_image if view is not None else None)
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
