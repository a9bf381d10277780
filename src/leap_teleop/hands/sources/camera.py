"""Camera hand sources: `webcam` (a V4L2 device) and `video` (a video file, an image, a
folder or a glob of images). Each captured image goes through MediaPipe Hands
(mediapipe_hands) and the landmark conversion (landmarks) into a Frame, in Leap axes
and millimetres, so everything downstream works as with a Leap.

Frame stamps: live and paced sources stamp the capture time on the caller's clock;
video read as fast as possible is stamped start + media time (the recording's own
timing, as the recording source does), so gesture timing matches the video.
"""
import logging
import os
import time

import numpy as np

from leap_teleop.hands.frame import Frame
from leap_teleop.hands.sources import capture
from leap_teleop.hands.sources.hand_tracks import HandTracks
from leap_teleop.hands.sources.landmarks import (
    DEFAULT_CAMERA_POSITION_MM,
    DEFAULT_HFOV_DEG,
    DEFAULT_PALM_LENGTH_MM,
    CameraModel,
    hand_from_landmarks,
)
from leap_teleop.hands.sources.mediapipe_hands import HandDetector
from leap_teleop.hands.sources.source import HandSource, SourceError

log = logging.getLogger(__name__)
# A frame the detector fails on is skipped (no hands: downstream holds, as for a lost
# hand) with a warning; this many failures in a row end the source.
MAX_DETECTOR_FAILURES = 30
class CameraSource(HandSource):
    """Frames from a capture.* media object through the hand detector.

    width, height: images of another size are letterboxed to it; both 0: as they come
    (one of them 0 alone is refused). camera: CameraModel of the processed image, or None
    to use hfov_deg at whatever size the images come. mirror: flip images left-right
    before processing (a selfie view); input_mirrored: the images already are mirror
    images. Either way the hands come out with the person's side and the person's right
    as +x.
    on_image(frame, bgr, landmarks): optional, called after each processed image (for the
    annotated view), on the source's thread.
    """

    still = False
    live = False                       # a device: running out of frames is a failure

    def __init__(self, open_media, realtime=True, latest_only=False, pace_hz=0.0, loop=False,
                 width=0, height=0, mirror=False, input_mirrored=False, camera=None,
                 hfov_deg=DEFAULT_HFOV_DEG, palm_length_mm=DEFAULT_PALM_LENGTH_MM,
                 camera_position_mm=DEFAULT_CAMERA_POSITION_MM, max_hands=2, model='full',
                 strategy='paired', detect_every=8, search_thread=True,
                 min_detection_confidence=0.5, clock=time.time, on_image=None):
        if not 0.0 < float(palm_length_mm) < 300.0:
            raise SourceError('palm length must be in (0, 300) mm, got %r' % (palm_length_mm,))
        self._open_media = open_media
        self.realtime = bool(realtime)
        self.latest_only = bool(latest_only)
        self.pace_hz = float(pace_hz or 0.0)
        self.loop = bool(loop)
        size = (int(width or 0), int(height or 0))
        if size != (0, 0) and min(size) <= 0:      # one alone was silently unused
            raise SourceError('image size %d x %d: both more than 0 (the size images are '
                              'letterboxed to) or both 0 (images as they come)' % size)
        self.size = size if size != (0, 0) else None
        self.mirrored = bool(mirror) != bool(input_mirrored)
        self.flip = bool(mirror)
        self.camera = camera
        self.hfov_deg = float(hfov_deg)
        CameraModel.from_hfov(640, 480, self.hfov_deg)      # validates the angle
        self.palm_length_mm = float(palm_length_mm)
        self.camera_position_mm = tuple(float(v) for v in camera_position_mm)
        self._clock = clock
        self.on_image = on_image
        self.cv2 = capture.import_cv2()
        self.detector = HandDetector(max_hands=max_hands, model=model, strategy=strategy,
                                     detect_every=detect_every, static=self.still,
                                     # offline: in the call, so results do not
                                     # depend on timing
                                     search_thread=search_thread and self.realtime,
                                     min_detection_confidence=min_detection_confidence)
        media = open_media()             # fails now, not later, on a bad device or file
        self.rate_hz = media.fps
        self._first_media = media
        self._cameras = {}
        self._tracks = HandTracks()      # ids and sides that follow the hands
        self.frames_processed = 0
        self.dropped = 0

    # -- conversion -------------------------------------------------------------------
    def camera_for(self, width, height, fit=None):
        """CameraModel of the processed image of a width x height capture: after `fit` =
        (scale, pad_x, pad_y, out_width, out_height) when it was letterboxed, and
        mirrored when flipped."""
        key = (width, height, fit)
        cam = self._cameras.get(key)
        if cam is None:
            cam = (self.camera.scaled_to(width, height) if self.camera is not None
                   else CameraModel.from_hfov(width, height, self.hfov_deg))
            if fit is not None:
                cam = cam.letterboxed(*fit)
            if self.flip:
                cam = CameraModel(cam.width, cam.height, cam.fx, cam.fy,
                                  cam.width - cam.cx, cam.cy)
            self._cameras[key] = cam
        return cam

    def letterbox(self, bgr):
        """bgr fitted into self.size keeping its aspect ratio (a distorted hand is read
        wrongly), centred on black; (image, fit) with fit as camera_for takes it."""
        h, w = bgr.shape[:2]
        out_w, out_h = self.size
        scale = min(out_w / w, out_h / h)
        new_w, new_h = max(1, round(w * scale)), max(1, round(h * scale))
        resized = self.cv2.resize(bgr, (new_w, new_h), interpolation=self.cv2.INTER_AREA)
        if (new_w, new_h) == (out_w, out_h):
            return resized, (scale, 0, 0, out_w, out_h)
        pad_x, pad_y = (out_w - new_w) // 2, (out_h - new_h) // 2
        canvas = np.zeros((out_h, out_w, 3), dtype=bgr.dtype)
        canvas[pad_y:pad_y + new_h, pad_x:pad_x + new_w] = resized
        return canvas, (scale, pad_x, pad_y, out_w, out_h)

    def hands_of(self, landmarks, cam, t):
        """Hands (one per side) from detector landmarks at time t, found in an image seen
        by CameraModel cam: each followed from image to image (HandTracks), keeping its
        id and its side through a few images whose side reads otherwise."""
        hands, lm_of = [], {}
        for lm in landmarks:
            hand = self._hand(lm, cam)
            if hand is not None:
                hands.append(hand)
                lm_of[id(hand)] = lm
        return self._tracks.update(hands, t, lambda hand, side: self._hand(lm_of[id(hand)], cam, side))

    def _hand(self, lm, cam, side=None):
        return hand_from_landmarks(lm, cam, self.mirrored, self.palm_length_mm,
                                   self.camera_position_mm, side=side)

    def forget_hands(self):
        """Treat the next image as unrelated to the last: new hand ids, no velocity (a
        cut in a video)."""
        self._tracks.forget()

    def forget_motion(self):
        """No velocity from the last image to the next (separate photos), the same hand
        ids for each side: a new id would read as the hand lost and found again, every
        other photo."""
        self._tracks.forget_motion()

    def prepare(self, bgr):
        """A captured image as the detector sees it: (processed BGR, RGB, its CameraModel)
        after the letterbox and the flip."""
        cv2 = self.cv2
        h, w = bgr.shape[:2]
        fit = None
        if self.size is not None and (w, h) != self.size:
            bgr, fit = self.letterbox(bgr)
        if self.flip:
            bgr = cv2.flip(bgr, 1)
        return bgr, cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB), self.camera_for(w, h, fit)

    def process(self, bgr, stamp, frame_id):
        """One image -> (Frame, landmarks, processed BGR image)."""
        bgr, rgb, cam = self.prepare(bgr)
        try:
            landmarks = self.detector.detect(rgb)
            self._failures = 0
        except (RuntimeError, ValueError) as e:
            self._failures = getattr(self, '_failures', 0) + 1
            if self._failures >= MAX_DETECTOR_FAILURES:
                raise SourceError('hand detection failed on %d frames in a row: %s'
                                  % (self._failures, e))
            if self._failures == 1:
                log.warning('camera source: hand detection failed on frame %d (skipped): %s',
                            frame_id, e)
            landmarks = []
        frame = Frame(id=frame_id, timestamp=stamp,
                      hands=self.hands_of(landmarks, cam, stamp))
        self.frames_processed += 1
        return frame, landmarks, bgr

    # -- the source ---------------------------------------------------------------------
    def frames(self):
        media = self._first_media
        self._first_media = None
        start_stamp = self._clock()
        offset = 0.0                    # media seconds of the passes already played
        frame_id = 0
        next_first_id = 1               # a pass of footage numbers from here (its place + this)
        try:
            while not self.stopped:
                if media is None:
                    media = self._open_media()
                # A pass starts over: the hand at its start is not the one at the last
                # pass's end (a new id, no velocity from the jump back).
                self.forget_hands()
                pace = (self.pace_hz if self.realtime else None)
                reader = capture.CaptureThread(media, clock=self._clock,
                                               latest_only=self.latest_only, pace_hz=pace)
                # footage numbers its frames by their place in it (an unreadable image or
                # a dropped frame leaves its number unused); a live camera counts them
                fps = getattr(media, 'fps', None)
                first_id = max(next_first_id, frame_id + 1)
                next_first_id = first_id + (getattr(media, 'frame_count', 0) or 0)
                last_media = 0.0
                try:
                    while not self.stopped:
                        try:
                            item = reader.get(0.1)
                        except StopIteration:
                            break
                        if item is None:
                            continue
                        if item.media_time is not None and fps:
                            frame_id = first_id + int(round(item.media_time * fps))
                        else:
                            frame_id += 1
                        if self.realtime or item.media_time is None:
                            stamp = item.stamp
                        else:
                            last_media = item.media_time
                            stamp = start_stamp + offset + item.media_time
                        if self.still:          # unrelated pictures: no velocity between them
                            self.forget_motion()
                        frame, landmarks, bgr = self.process(item.bgr, stamp, frame_id)
                        if self.on_image is not None:
                            self.on_image(frame, bgr, landmarks)
                        yield frame
                finally:
                    reader.close()
                    self.dropped += reader.dropped
                if reader.error is not None:
                    raise SourceError('camera source: reading failed: %s' % reader.error)
                if self.live and not self.stopped:
                    raise SourceError('camera %s stopped delivering frames (unplugged?)'
                                      % getattr(self, 'device', ''))
                media = None
                if not self.loop:
                    return
                offset += last_media + 1.0 / (self.rate_hz or 30.0)
        finally:
            if media is not None:
                media.close()
            self.detector.close()


class WebcamSource(CameraSource):
    """A V4L2 webcam, live: every frame stamped at capture; a frame that arrives while
    the previous one is still being processed replaces the older one (lowest latency)."""

    live = True

    def __init__(self, device='0', width=640, height=480, fps=30.0, mirror=False, **kwargs):
        kwargs.setdefault('input_mirrored', False)

        def open_media():
            return capture.Webcam(device, width, height, fps)
        self.device = str(device)
        super().__init__(open_media, realtime=True, latest_only=True, pace_hz=None,
                         loop=False, width=width, height=height, mirror=mirror, **kwargs)


class VideoSource(CameraSource):
    """A video file or still images, paced at the file's timing (realtime, or at
    `rate_hz` frames/s when > 0) or as fast as they are processed; optional loop. Every
    frame is processed (a recording is not live: when processing cannot keep up, paced
    playback slows down rather than skip frames), unless drop_late: then paced playback
    behaves like a live camera (a frame that arrives while the previous one is being
    processed replaces it). Still images (an image, a folder, a glob) are unrelated
    pictures: each is detected on its own, with no palm velocity between them (a side's
    hand keeps its id, so it stays present from photo to photo)."""

    def __init__(self, path, realtime=True, loop=False, rate_hz=0.0, mirror=False,
                 width=0, height=0, drop_late=False, **kwargs):
        self.path = str(path)
        stills = capture.resolve_stills(self.path)
        if (not stills and (any(c in self.path for c in '*?[') or not os.path.isfile(self.path))
                or stills == [self.path] and not os.path.isfile(self.path)):
            raise SourceError('video source: %s names no video file, image, folder of '
                              'images or glob that matches images' % self.path)
        self.still = bool(stills)
        still_rate = rate_hz or capture.DEFAULT_STILL_RATE_HZ

        def open_media():
            if stills:
                return capture.StillImages(stills, still_rate)
            return capture.VideoFile(self.path)
        super().__init__(open_media, realtime=realtime,
                         latest_only=bool(drop_late and realtime),
                         pace_hz=rate_hz if not stills else 0.0, loop=loop, width=width,
                         height=height, mirror=mirror, **kwargs)
