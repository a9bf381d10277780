"""Image capture for the camera hand sources: a V4L2 webcam, a video file, or still images
(one file, a folder, a glob), read on a thread of their own so decoding overlaps the
hand detection.

A reader yields Captured items: the BGR image, the capture time on the caller's clock,
and for files the media time (s from the start of the file).
"""
import glob
import logging
import os
import queue
import threading
import time
from dataclasses import dataclass
from typing import Optional

import numpy as np

from leap_teleop.hands.sources.source import SourceError

log = logging.getLogger(__name__)
IMAGE_EXTENSIONS = ('.jpg', '.jpeg', '.png', '.bmp', '.webp', '.tif', '.tiff')
VIDEO_EXTENSIONS = ('.mp4', '.avi', '.mov', '.mkv', '.webm', '.m4v', '.mpg', '.mpeg', '.ogv')
DEFAULT_STILL_RATE_HZ = 30.0        # still images are frames of a sequence at this rate
SHORT_VIDEO_SHARE = 0.9             # a video that ends before this share of its frames is cut
_SAID_SHORT = set()


def import_cv2():
    from leap_teleop.hands.sources.mediapipe_hands import INSTALL_HINT
    try:
        import cv2
    except ImportError as e:
        raise SourceError('%s (%s)' % (INSTALL_HINT, e))
    return cv2


@dataclass
class Captured:
    index: int                      # 0-based, per pass
    bgr: np.ndarray
    stamp: float                    # caller's clock at capture
    media_time: Optional[float]     # s from the file's start; None for a live camera


def is_image_path(path):
    return str(path).lower().endswith(IMAGE_EXTENSIONS)


def is_video_path(path):
    return str(path).lower().endswith(VIDEO_EXTENSIONS)


def resolve_stills(spec):
    """The image files `spec` names (a folder, a glob, or one image), sorted; [] when
    it names a video."""
    spec = str(spec)
    if os.path.isdir(spec):
        return sorted(os.path.join(spec, n) for n in os.listdir(spec) if is_image_path(n))
    if any(c in spec for c in '*?['):
        return sorted(p for p in glob.glob(spec) if is_image_path(p))
    if is_image_path(spec):
        return [spec]
    return []


class VideoFile:
    """A video file, frame by frame: (bgr, media time s) until the end."""

    def __init__(self, path):
        cv2 = import_cv2()
        if not os.path.isfile(path):
            raise SourceError('video file %s does not exist' % path)
        self.path = path
        self._cap = cv2.VideoCapture(path)
        if not self._cap.isOpened():
            raise SourceError('OpenCV cannot open video %s' % path)
        fps = self._cap.get(cv2.CAP_PROP_FPS)
        self.fps = fps if fps and 0 < fps < 1000 else 30.0
        self.frame_count = int(self._cap.get(cv2.CAP_PROP_FRAME_COUNT) or 0)
        self.width = int(self._cap.get(cv2.CAP_PROP_FRAME_WIDTH))
        self.height = int(self._cap.get(cv2.CAP_PROP_FRAME_HEIGHT))
        self._k = 0

    def read(self):
        ok, bgr = self._cap.read()
        if not ok:
            # The container's count is an estimate for some formats: only a clear shortfall
            # says the file is cut or damaged.
            if self._k < SHORT_VIDEO_SHARE * self.frame_count - 1 and self.path not in _SAID_SHORT:
                _SAID_SHORT.add(self.path)      # once: a looped video is opened on every pass
                log.warning('camera source: video %s ended after %d of the %d frames its '
                            'container lists: a cut or damaged file?', self.path, self._k,
                            self.frame_count)
            return None
        t = self._k / self.fps
        self._k += 1
        return bgr, t

    def close(self):
        self._cap.release()


def jpeg_is_cut(path):
    """Whether `path` is a JPEG whose data ends before its end-of-image marker. OpenCV
    decodes such a file without an error, its missing part grey. The header's segments are
    walked by their lengths to the main image's first scan (an EXIF thumbnail lies inside
    one of them); entropy-coded data escapes every 0xFF, so from there the first end marker
    is the image's: a whole file has one, whatever follows it (phones append videos)."""
    try:
        with open(path, 'rb') as f:
            data = f.read()
    except OSError:
        return False            # imread's problem, reported there
    if not data.startswith(b'\xff\xd8\xff'):
        return False
    k = 2
    while k + 4 <= len(data):
        if data[k] != 0xFF:
            return False        # not a header imread can read either: its problem
        marker = data[k + 1]
        if marker == 0xFF:      # fill byte
            k += 1
            continue
        if marker == 0xDA:      # the main image's first scan
            return data.find(b'\xff\xd9', k) < 0
        k += 2 + int.from_bytes(data[k + 2:k + 4], 'big')
    return True                 # the header itself is cut


class StillImages:
    """Image files as the frames of a sequence at `rate_hz`; unreadable files are skipped
    with a warning."""

    def __init__(self, paths, rate_hz=DEFAULT_STILL_RATE_HZ):
        self.cv2 = import_cv2()
        if not paths:
            raise SourceError('no image files to read')
        self.paths = list(paths)
        self.fps = float(rate_hz)
        self.frame_count = len(self.paths)
        self._k = 0

    def read(self):
        while self._k < len(self.paths):
            path = self.paths[self._k]
            k = self._k
            self._k += 1
            if jpeg_is_cut(path):      # before decoding it: libjpeg's own line would come first
                log.warning('camera source: image %s is cut short (its JPEG data ends before '
                            'the end-of-image marker), skipped', path)
                continue
            # IMREAD_COLOR applies EXIF orientation and drops alpha.
            try:
                bgr = self.cv2.imread(path, self.cv2.IMREAD_COLOR)
            except self.cv2.error as e:      # a header claiming more pixels than OpenCV allows
                log.warning('camera source: cannot read image %s (%s), skipped', path,
                            ' '.join(str(e).split()))
                continue
            if bgr is None:
                log.warning('camera source: cannot read image %s, skipped', path)
                continue
            return bgr, k / self.fps
        return None

    def close(self):
        pass


class Webcam:
    """A V4L2 camera: device index or /dev/videoN; asks for width x height at fps."""

    def __init__(self, device, width=640, height=480, fps=30.0):
        cv2 = import_cv2()
        dev = str(device)
        target = int(dev) if dev.isdigit() else dev
        if isinstance(target, str) and not os.path.exists(target):
            raise SourceError('camera device %s does not exist (is the webcam plugged in? '
                              'list them with `ls /dev/video*`)' % target)
        self._cap = cv2.VideoCapture(target, cv2.CAP_V4L2)
        if not self._cap.isOpened():
            raise SourceError('cannot open camera %s (V4L2); check the device and that no '
                              'other program holds it' % dev)
        self._cap.set(cv2.CAP_PROP_FRAME_WIDTH, int(width))
        self._cap.set(cv2.CAP_PROP_FRAME_HEIGHT, int(height))
        if fps:
            self._cap.set(cv2.CAP_PROP_FPS, float(fps))
        self._cap.set(cv2.CAP_PROP_BUFFERSIZE, 1)     # the newest frame, not a backlog
        got = self._cap.get(cv2.CAP_PROP_FPS)
        self.fps = got if got and 0 < got < 1000 else (fps or 30.0)
        self.frame_count = 0
        self.width = int(self._cap.get(cv2.CAP_PROP_FRAME_WIDTH))
        self.height = int(self._cap.get(cv2.CAP_PROP_FRAME_HEIGHT))

    def read(self):
        ok, bgr = self._cap.read()
        if not ok:
            return None
        return bgr, None

    def close(self):
        self._cap.release()


class CaptureThread:
    """Reads `media` on its own thread into a queue the consumer pulls with get().

    latest_only: keep only the newest capture (live data: when detection falls behind,
    stale frames are dropped, counted in .dropped); else a blocking queue, so every frame
    is processed: one slot when paced (a frame waits at most one processing time after
    its capture stamp; playback slows down when processing cannot keep up), a few when
    unpaced (decoding runs ahead).
    pace_hz: > 0 releases file frames at their media time scaled to this rate, 0 at
    the file's own rate; None as fast as they decode.
    """

    _END = object()

    def __init__(self, media, clock=time.time, latest_only=False, pace_hz=None):
        self.media = media
        self.clock = clock
        self.latest_only = latest_only
        self.pace_scale = None if pace_hz is None else (
            media.fps / pace_hz if pace_hz else 1.0)
        self.q = queue.Queue(1 if latest_only or pace_hz is not None else 4)
        self.dropped = 0
        self.error = None
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name='camera-capture', daemon=True)
        self._thread.start()

    def _put(self, item):
        if self.latest_only and item is not self._END:
            while True:
                try:
                    self.q.put_nowait(item)
                    return
                except queue.Full:
                    try:
                        self.q.get_nowait()
                        self.dropped += 1
                    except queue.Empty:
                        pass
        while not self._stop.is_set():
            try:
                self.q.put(item, timeout=0.1)
                return
            except queue.Full:
                pass

    def _run(self):
        start = time.monotonic()
        k = 0
        try:
            while not self._stop.is_set():
                got = self.media.read()
                if got is None:
                    break
                bgr, media_t = got
                if self.pace_scale is not None and media_t is not None:
                    delay = start + media_t * self.pace_scale - time.monotonic()
                    if delay > 0 and self._stop.wait(delay):
                        break
                self._put(Captured(k, bgr, self.clock(), media_t))
                k += 1
        except Exception as e:       # reported to the consumer, never lost on this thread
            self.error = e
        finally:
            self._put(self._END)

    def get(self, timeout=0.1):
        """The next Captured; None on timeout; StopIteration when the media has ended."""
        try:
            item = self.q.get(timeout=timeout)
        except queue.Empty:
            return None
        if item is self._END:
            raise StopIteration
        return item

    def close(self):
        self._stop.set()
        self._thread.join(2.0)
        self.media.close()
