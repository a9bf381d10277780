"""The sender's parameters, declared once: its hand source, recognizer, topics and the
leap_motion driver interface. The table is the sender node's ~params and --help, its
dynamic_reconfigure server's and the docs' parameter table (re-exported by the node).
"""
import math

from leap_teleop.control.lowpass import DEFAULT_CUTOFF
from leap_teleop.hands.gestures.recognizer import MIN_CONFIDENCE
from leap_teleop.hands.sources import SOURCES
from leap_teleop.hands.sources.camera_params import CAMERA_PARAMS
from leap_teleop.params import Param, ParamError

# Leap axes (x right, y up, z toward the user) in a ROS world frame (REP 103: x forward, z up).
LEAP_IN_WORLD_XYZW = (0.5, -0.5, -0.5, 0.5)

SENDER_PARAMS = {
    'source': Param('scripted', 'hand source', choices=tuple(SOURCES)),
    'script': Param('', 'gesture script YAML for the scripted source '
                        '(default config/gestures/wave_hello.yaml)', path=True),
    'recording': Param('', 'LeapJS recording (.json, .json.lz, .json.gz) for the recording source',
                       path=True),
    'rate': Param(0.0, 'scripted source frame rate; 0 = the script\'s own (video source: pace '
                       'at this many frames/s; 0 = the file\'s own)', unit='Hz',
                  ge=0.0, le=1000.0),
    'loop': Param(False, 'restart the script / recording when it ends'),
    'realtime': Param(True, 'pace frames at their recorded / scripted timing'),
    'freq': Param(0.0, 'the original sender\'s period; > 0 throttles its topics (leapcobot, Hand, '
                       'leapros, leap) to one frame per period on a steady '
                       'schedule (a frame with gesture events, or where a hand comes or goes, '
                       'always goes out; the leap_motion driver\'s topics carry every frame); '
                       '0 = every frame', unit='s',
                  ge=0.0, le=10.0),
    'sides': Param(['right', 'left'], 'hands to publish (one side: right, or [right])',
                   min_length=1, choices=('right', 'left')),
    'leapcobot_topic_right': Param('leapmotion/data_right', 'leapcobotright topic',
                                   empty_ok=False, ros_name=True),
    'leapcobot_topic_left': Param('leapmotion/data_left', 'leapcobotleft topic',
                                  empty_ok=False, ros_name=True),
    'hand_topic_right': Param('leapmotion/hand_right', 'rich Hand topic, right',
                              empty_ok=False, ros_name=True),
    'hand_topic_left': Param('leapmotion/hand_left', 'rich Hand topic, left', empty_ok=False, ros_name=True),
    'gesture_topic': Param('leapmotion/gestures', 'GestureEvent topic (both hands)',
                           empty_ok=False, ros_name=True),
    'frame_id': Param('leap_hands', 'frame of the hand messages', empty_ok=False),
    'world_frame': Param('world', 'parent frame of the static TF to frame_id', empty_ok=False),
    'leap_xyz': Param([0.0, 0.0, 0.0], 'Leap device position in world_frame', unit='m',
                      length=3, ge=-100.0, le=100.0),
    'leap_rotation_xyzw': Param(list(LEAP_IN_WORLD_XYZW), 'rotation of frame_id in world_frame '
                                '(x, y, z, w; a unit quaternion): by default Leap axes as REP 103 '
                                'ones (x forward, z up); the leap_motion driver\'s is [0.707, 0, 0, '
                                '0.707] (90 deg about x; leap_motion.launch sets it)',
                                length=4, ge=-1.0, le=1.0),
    'shutdown_on_end': Param(True, 'shut the node down when a finite source ends (a source '
                                   'that fails, e.g. a camera unplugged, always does: status 2)'),
    # Bounded: a slow subscriber holds at most this many frames (~2 s at 120 Hz) per topic.
    'queue_size': Param(200, 'publisher queue size (frames buffered per subscriber)',
                        ge=1, le=1000),
    'leapros_topic': Param('', 'topic for the classic leap_motion/leapros message (as that '
                               'driver: leapmotion/data); empty = not published', ros_name=True),
    'leapros_side': Param('right', 'hand the leapros and leap messages carry (one of ~sides)',
                          choices=('right', 'left')),
    'leap_topic': Param('', 'topic for the old sender\'s leap_motion/leap message (that sender: '
                            'leapmotion/raw); empty = not published', ros_name=True),
    'human_topic': Param('', 'topic for the leap_motion driver\'s Human (DriverHuman; the '
                             'driver: leap_motion/leap_device); empty = not published', ros_name=True),
    'filtered_human_topic': Param('', 'topic for the low-pass filtered DriverHuman (the '
                                      'driver\'s filter node: leap_motion/filtered_values); '
                                      'empty = not published', ros_name=True),
    'filter_cutoff': Param(DEFAULT_CUTOFF, 'the driver\'s filter_cutoff c = cot(pi f_c / '
                                           'f_frames): 1 = a quarter of the frame rate, '
                                           'larger smooths more', gt=0.0, le=1000.0),
    'driver_marker_topic': Param('', 'topic for the driver visualizer\'s MarkerArray (the '
                                     'driver: leap_motion/visualization_marker_array), drawn '
                                     'from the filtered Human when that is published; empty = '
                                     'not published', ros_name=True),
    'publish_tf': Param(True, 'publish the static TF world_frame -> frame_id (one sender per '
                              'graph should)'),
    'wait_for_subscribers': Param(False, 'start the source only once every ~wait_topics topic '
                                         'has a subscriber (so a session is not lost while '
                                         'its consumers start)'),
    'wait_topics': Param([], 'topics the consumers read, to wait for; any topic of the graph '
                             '(e.g. the drone\'s ardrone/takeoff); empty = every published '
                             'leapcobot topic', kind='list', item='str', ros_name=True),
    'rotation_dead_bands': Param(True, 'rotate / turn / swing with the original dead bands '
                                       '(z +-0.40, y -0.15..0.35, x -0.05..0.45 rad); false: '
                                       'the raw rotation since the origin'),
    'gesture_model': Param('', 'Leap-family pose model (.npz, train_gestures --out); '
                               'empty = the shipped one', path=True),
    'keypoint_model': Param('', 'camera keypoint pose model (.npz); empty = the shipped one',
                            path=True),
    'gesture_bindings': Param('', 'gesture -> action bindings YAML (see config/gestures/'
                                  'bindings/default.yaml); empty = those defaults', path=True),
    'recognizer_on_frames': Param(3, 'gesture recognizer: frames a held gesture must be seen '
                                     'before it starts', ge=1, le=100),
    'recognizer_off_frames': Param(3, 'gesture recognizer: frames it must be gone before it '
                                      'stops', ge=1, le=100),
    'recognizer_min_confidence': Param(MIN_CONFIDENCE, 'gesture recognizer: frames of a lower '
                                                       'tracking confidence do not count',
                                       ge=0.0, le=1.0),
}
SENDER_PARAMS.update(CAMERA_PARAMS)
# Changeable while running (dynamic_reconfigure): the recognizer's thresholds and the driver
# filter's cutoff. Sources, topics, sides and modes are start-up only.
SENDER_RECONFIGURABLE = ('recognizer_on_frames', 'recognizer_off_frames',
                         'recognizer_min_confidence', 'filter_cutoff')


def leap_rotation(xyzw, tolerance=0.01):
    """~leap_rotation_xyzw as a unit quaternion [x, y, z, w]; ParamError when its norm is not
    within `tolerance` of 1 (a typo, not a rotation). Normalised: the driver's 0.707s are 4
    digits, and TF consumers expect a unit quaternion."""
    norm = math.sqrt(sum(float(v) ** 2 for v in xyzw))
    if abs(norm - 1.0) > tolerance:
        raise ParamError('~leap_rotation_xyzw = %r: not a unit quaternion (norm %.4g); allowed: '
                         'x, y, z, w with x^2 + y^2 + z^2 + w^2 = 1 (within %g)'
                         % (list(xyzw), norm, tolerance))
    return [float(v) / norm for v in xyzw]
