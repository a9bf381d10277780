"""What the sender's checked ~params build, without ROS: the hand source, the gesture
recognizers and their live retuning, and the original sender's publishing period."""
from leap_teleop.hands.gestures import GestureRecognizer
from leap_teleop.hands.gestures.bindings import load_bindings
from leap_teleop.hands.sources import SourceError, make_source
from leap_teleop.hands.sources.camera_params import (
    CAMERA_SOURCES,
    camera_source_kwargs,
    check_size,
    source_family,
)

# The sender's output topic parameters; a side's own ones end in _<side>.
OUTPUT_TOPICS = ('leapcobot_topic_right', 'leapcobot_topic_left', 'hand_topic_right',
                 'hand_topic_left', 'gesture_topic', 'leapros_topic', 'leap_topic', 'human_topic',
                 'filtered_human_topic', 'driver_marker_topic', 'annotated_image_topic')


def check_outputs(p, resolve=lambda topic: topic):
    """ValueError when the ~params ask for outputs that cannot be: a side twice, leapros /
    leap carrying a hand the sender does not publish, two outputs on one topic (two
    message types on a topic, or two streams mixed in one), a static TF from a frame to
    itself (tf2 drops it)."""
    if p['publish_tf'] and p['world_frame'].lstrip('/') == p['frame_id'].lstrip('/'):
        raise ValueError('~world_frame and ~frame_id are both %r: the static TF needs two '
                         'frames (or ~publish_tf false)' % p['frame_id'])
    if len(set(p['sides'])) != len(p['sides']):
        raise ValueError('~sides %r: each side once' % (p['sides'],))
    if (p['leapros_topic'] or p['leap_topic']) and p['leapros_side'] not in p['sides']:
        raise ValueError('~leapros_side %r is not in ~sides %r' % (p['leapros_side'], p['sides']))
    used = {}
    for name in OUTPUT_TOPICS:
        side = name.rsplit('_', 1)[-1]
        topic = p.get(name, '')
        if not topic or (side in ('right', 'left') and side not in p['sides']):
            continue
        # as the node resolves them (rospy.resolve_name): 'x' and '/x' are one topic in the
        # root namespace, two inside another
        topic = resolve(topic)
        if topic in used:
            raise ValueError('~%s and ~%s are both %r: one topic per output' % (
                used[topic], name, topic))
        used[topic] = name


def build_source(p, clock, default_script, camera_model=lambda: None, on_image=None):
    """The hand source ~source names, configured from `p`; SourceError when a parameter it
    needs is missing. `clock` stamps frames; `camera_model()` (called only for a camera
    source) gives its CameraModel or None; `on_image` sees each camera image."""
    name = p['source']
    if name in CAMERA_SOURCES:
        if name == 'video' and not p['video']:
            raise SourceError('~source video needs ~video:=PATH (a video, an image, a folder '
                              'or a glob of images)')
        check_size(p)                   # before camera_model(): it may wait for CameraInfo
        return make_source(name, **camera_source_kwargs(name, p, clock, camera_model(),
                                                        on_image))
    if name == 'scripted':
        return make_source('scripted', script=p['script'] or default_script,
                           rate_hz=p['rate'] or None, loop=p['loop'], realtime=p['realtime'],
                           clock=clock, sides=p['sides'])
    if name == 'recording':
        if not p['recording']:
            raise SourceError('~source recording needs ~recording:=PATH to a LeapJS file')
        return make_source('recording', path=p['recording'], loop=p['loop'],
                           realtime=p['realtime'], clock=clock)
    return make_source(name, clock=clock)      # a device too: sim time under /use_sim_time


def source_and_bindings(p, recognizer, clock, default_script, camera_model=lambda: None,
                        on_image=None):
    """(source, bindings): build_source and checked_bindings (`recognizer`: one of the
    factory's), a bad ~gesture_bindings refused before anything can wait (a camera source
    waits up to 10 s for its CameraInfo, then loads MediaPipe and opens its device): the
    source's name tells its hand family. A recording's hands are known only from its file
    (a camera take's are keypoints): it is read first, which never waits."""
    if p['source'] != 'recording':
        bindings = checked_bindings(p, recognizer)
        return build_source(p, clock, default_script, camera_model, on_image), bindings
    source = build_source(p, clock, default_script, camera_model, on_image)
    return source, checked_bindings(p, recognizer, source.hand_family)


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


def checked_bindings(p, recognizer, family=None):
    """The ~gesture_bindings, checked against what the source's hands can show: a camera
    hand is judged by the keypoint model, any other by the Leap one, so a class of the other
    model never fires (BindingError). `family`: the source's hand_family, when it knows."""
    family = family or source_family(p['source'])
    model = '~keypoint_model' if family == 'keypoints' else '~gesture_model'
    return load_bindings(p['gesture_bindings']).check(
        recognizer.user_gestures_of[family],
        ': the %s source\'s hands are judged by %s' % (p['source'], model))


def retune_recognizers(recognizers, changes):
    """Apply checked changes of the recognizer_* parameters to running recognizers (the
    source thread reads each per frame)."""
    for recognizer in recognizers:
        if 'recognizer_on_frames' in changes:
            recognizer.filter.on_frames = changes['recognizer_on_frames']
        if 'recognizer_off_frames' in changes:
            recognizer.filter.off_frames = changes['recognizer_off_frames']
        if 'recognizer_min_confidence' in changes:
            recognizer.min_confidence = changes['recognizer_min_confidence']


def retune_sender(recognizers, lowpass, changes):
    """Apply checked changes of the sender's reconfigurable parameters: the recognizer_*
    ones to the running recognizers, filter_cutoff to the driver topics' LowPass."""
    retune_recognizers(recognizers, changes)
    if 'filter_cutoff' in changes:
        lowpass.set_cutoff(changes['filter_cutoff'])


class PeriodThrottle:
    """The original sender's ~freq: one frame per `period` (s, by frame timestamp) for
    each key, on a schedule that keeps its phase, so the rate is 1 / period as the
    original's sleep gave (the first frame a period after the last one sent halved a
    110 Hz stream to 55 Hz at 0.01 s); a period of 0 lets every frame through. A stamp
    before the last one sent (a /clock that restarts, a looped bag) starts afresh: it
    goes out."""

    def __init__(self, period):
        self.period = float(period)
        self._sent = {}         # key: (stamp of the last frame sent, when the next is due)

    def due(self, key, timestamp, change=False):
        """True when a frame of `key` stamped `timestamp` goes out (and counts as sent);
        a `change` (a hand appeared or went) always does: held back, a short loss (the one
        hand-less frame between a recording's passes) would never reach the consumers."""
        if self.period <= 0:
            return True
        sent = self._sent.get(key)
        # Time gone back: measured from the old stamps, nothing went out until the clock
        # had passed them again.
        if not change and sent is not None and sent[0] <= timestamp < sent[1] - 1e-6:
            return False        # (1e-6: the schedule's sums of periods round)
        next_due = timestamp + self.period
        if not change and sent is not None and sent[0] <= timestamp < sent[1] + self.period:
            next_due = sent[1] + self.period        # on schedule; after a gap, from now
        self._sent[key] = (timestamp, next_due)
        return True
