"""The camera sources' node parameters (declared once, used by the sender) and their
mapping onto make_source('webcam' | 'video', ...) keywords."""
import numbers

from leap_teleop.hands.sources.landmarks import DEFAULT_CAMERA_POSITION_MM, DEFAULT_HFOV_DEG, DEFAULT_PALM_LENGTH_MM
from leap_teleop.hands.sources.source import SourceError
from leap_teleop.params import Param, ParamError

CAMERA_SOURCES = ('webcam', 'video')


def source_family(source):
    """The pose model family that judges a source's hands: 'keypoints' for a camera
    source, 'leap' for any other."""
    return 'keypoints' if source in CAMERA_SOURCES else 'leap'


# Per axis: a hand up to 1 m from a camera placed this far from the device stays within
# the 2000 mm the tracker takes a palm from (tracker.MAX_PALM_MM); further, every hand
# would be refused as a tracking error.
MAX_CAMERA_OFFSET_MM = 1000.0
# The sender's ~width / ~height defaults. The offline tools (classify_frames, record_frames,
# record_gestures, recording_to_bag --video) letterbox camera images to them too: the
# landmark model reads an image otherwise, and they would see other hands than the sender.
DEFAULT_SIZE = (640, 480)


class DeviceParam(Param):
    """~device: a string, or an index as an integer: YAML (`_device:=1`, `device: 1` in a
    camera_config) reads a bare number as one. Checked as its text."""

    def check(self, name, value):
        if isinstance(value, numbers.Integral) and not isinstance(value, bool):
            if value < 0:
                raise ParamError('~%s = %r: a negative index; allowed: %s' % (name, value, self.allowed()))
            value = str(value)
        return super().check(name, value)

    def allowed(self):
        return 'an index (0 or more) or a device path (not empty)'

CAMERA_PARAMS = {
    'device': DeviceParam('0', 'webcam source: V4L2 device index or /dev/videoN', empty_ok=False),
    'video': Param('', 'video source: a video file, an image, a folder or a glob of images',
                   path=True),
    'width': Param(DEFAULT_SIZE[0], 'camera sources: images are letterboxed to width x height, '
                                    'keeping their aspect ratio (webcam: also the size asked of '
                                    'the device); video: 0 with ~height 0 = as they come; one of '
                                    'the two 0 alone is refused',
                   unit='px', ge=0, le=7680),
    'height': Param(DEFAULT_SIZE[1], 'camera sources: see ~width', unit='px', ge=0, le=4320),
    'camera_fps': Param(30.0, 'webcam: frame rate asked of the device', unit='Hz', gt=0.0,
                        le=240.0),
    'mirror': Param(False, 'camera sources: flip images left-right before processing (a '
                           'selfie view); hands keep the person\'s side and axes either way'),
    'input_mirrored': Param(False, 'camera sources: the images already are mirror images (a '
                                   'camera or driver that mirrors)'),
    'hfov_deg': Param(DEFAULT_HFOV_DEG, 'camera sources: horizontal field of view, used when '
                                        '~camera_info_topic is empty', unit='deg', ge=1.0,
                      le=179.0),
    'camera_info_topic': Param('', 'camera sources: sensor_msgs/CameraInfo topic with the '
                                   'intrinsics (one message is read at start-up); empty = '
                                   '~hfov_deg', ros_name=True),
    'palm_length_mm': Param(DEFAULT_PALM_LENGTH_MM, 'camera sources: the user\'s palm length '
                                                    '(wrist crease to middle-finger knuckle); '
                                                    'depth scales with it',
                            unit='mm', ge=50.0, le=150.0),
    'camera_position_mm': Param(list(DEFAULT_CAMERA_POSITION_MM),
                                'camera sources: the camera\'s position in the Leap frame (a '
                                'hand 500 mm in front of the camera is at y 200, z 0 by '
                                'default); within 1000 mm of the device per axis, so that a '
                                'hand in view is within the 2000 mm palms are taken from',
                                unit='mm', length=3, ge=-MAX_CAMERA_OFFSET_MM,
                                le=MAX_CAMERA_OFFSET_MM),
    'model': Param('full', 'camera sources: MediaPipe hand landmark model',
                   choices=('full', 'lite')),
    'max_hands': Param(2, 'camera sources: hands tracked at most', ge=1, le=2),
    'detect_every': Param(8, 'camera sources: while fewer than ~max_hands are tracked, look '
                             'for another hand every this many frames', ge=1, le=60),
    'search_thread': Param(True, 'camera sources, live or paced: look for hands on a worker '
                                 'thread (the other core) and publish each frame after '
                                 'tracking only; off = in the frame\'s own processing, which '
                                 'makes that frame late'),
    'min_detection_confidence': Param(0.5, 'camera sources: MediaPipe palm detection '
                                           'threshold', gt=0.0, lt=1.0),
    'video_drop_late': Param(False, 'video source, paced: behave like a live camera (a frame '
                                   'that arrives while the previous one is being processed '
                                   'replaces it) instead of processing every frame'),
    'annotated_image_topic': Param('', 'camera sources: publish the annotated camera view '
                                       '(sensor_msgs/Image: landmarks, side, gestures, fps) '
                                       'on this topic; empty = off', ros_name=True),
}


def check_size(p):
    """SourceError when checked params `p` give ~width or ~height 0 without the other: one
    alone was silently unused (no letterbox at all)."""
    if (p['width'] == 0) != (p['height'] == 0):
        raise SourceError('~width %d and ~height %d: both more than 0 (the size images are '
                          'letterboxed to) or both 0 (images as they come)'
                          % (p['width'], p['height']))


def camera_source_kwargs(name, p, clock, camera=None, on_image=None):
    """make_source keywords for camera source `name` from checked params `p` (the
    sender's: CAMERA_PARAMS plus realtime, loop, rate); SourceError for a size check_size
    refuses."""
    check_size(p)
    common = dict(hfov_deg=p['hfov_deg'], palm_length_mm=p['palm_length_mm'],
                  camera_position_mm=p['camera_position_mm'], max_hands=p['max_hands'],
                  model=p['model'], detect_every=p['detect_every'],
                  search_thread=p['search_thread'],
                  min_detection_confidence=p['min_detection_confidence'],
                  mirror=p['mirror'], input_mirrored=p['input_mirrored'], camera=camera,
                  clock=clock, on_image=on_image)
    if name == 'webcam':
        return dict(common, device=p['device'], width=p['width'], height=p['height'],
                    fps=p['camera_fps'])
    return dict(common, path=p['video'], realtime=p['realtime'], loop=p['loop'],
                rate_hz=p['rate'], width=p['width'], height=p['height'],
                drop_late=p['video_drop_late'])
