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
VELOCITY_SMOOTHING = 0.5            # weight of the newest finite difference
# A frame the detector fails on is skipped (no hands: downstream holds, as for a lost
# hand) with a warning; this many failures in a row end the source.
MAX_DETECTOR_FAILURES = 30
# A hand is the last image's hand only within this many hand sizes (the diagonal of its
# landmarks' box in the image) of where that one was predicted to be (last place + image
# velocity x dt); else it is a new hand (new id, new session), so a side's palm never
# jumps further with its session kept. On the shared clips a followed hand is at most 0.18
# sizes off its prediction; a hand setting off at 1.8 m/s 0.5 m away, 0.31.
MATCH_MAX_SIZES = 0.5
# A hand read as the other side keeps its followed hand's side (a misread) only within
# this many sizes of the prediction: a misread hand on the shared clips is within 0.05 of
# it; the other hand in view 6 cm from where one left, 0.34. Further, it is a new hand on
# the side it is read as.
HOLD_MAX_SIZES = 0.25
# ... and only when its shape in the image (landmarks about their centre, in hand sizes)
# is within this of the followed hand's: from one image to the next a hand's changes by
# 0.04 at most when misread, 0.12 when closing into a fist, on the shared clips; the
# mirror-image hand (the other one) in its place is 0.24 off.
HOLD_SHAPE_MAX = 0.15
# Cost, in hand sizes off the prediction, of matching a hand to a followed hand of the
# other side: two hands near each other (crossing, one passing in front of the other) go
# by their reading unless their places tell them apart by more.
SIDE_DISAGREE_COST = 0.25
# Images in a row whose reading disagrees with a followed hand's side before it changes
# side: a single hand's side read wrongly for 6 images in a row on the shared palm clip.
SIDE_SWITCH_FRAMES = 8
# More hands than this in one image are matched greedily (the exact search grows fast).
EXACT_MATCH_MAX_HANDS = 4
# A hand matched to none, read as the side of the one followed hand of that side matched to
# none, is still that hand within this many sizes of its last place, when no other followed
# hand was that near: a hand faster than its prediction (a track starts with no velocity, and
# one that stops is overshot), which got a new session every image from 1.35 m/s at 15
# images/s. Another hand near where one vanished is still new.
LONE_MATCH_MAX_SIZES = 1.5
# A followed hand keeps its side against the reading only once its side was read this many
# images: a track started by one misread image held the wrong side against 7 right ones.
HOLD_AFTER_IMAGES = 3


class _Track:
    __slots__ = ('id', 'side', 't', 'palm', 'velocity', 'centre', 'size', 'shape',
                 'image_velocity', 'against', 'published', 'agreed')


def image_place(hand):
    """(centre, size) of a hand in the image: its landmarks' mean and box diagonal, in
    pixels; from the palm position (mm) when it has no image landmarks."""
    px = getattr(hand, 'image_landmarks', None)
    if px is not None:
        px = np.asarray(px, dtype=float)[:, :2]
        if px.size and np.all(np.isfinite(px)):
            size = float(np.linalg.norm(px.max(axis=0) - px.min(axis=0)))
            return px.mean(axis=0), max(size, 1.0)
    return np.asarray(hand.palm_position, dtype=float)[:2], 200.0


def image_shape(hand, centre, size):
    """The hand's landmarks about their centre, in hand sizes; None without landmarks."""
    px = getattr(hand, 'image_landmarks', None)
    if px is None:
        return None
    px = np.asarray(px, dtype=float)[:, :2]
    return (px - centre) / size if px.size and np.all(np.isfinite(px)) else None


def _same_shape(a, b):
    """Much the same shape in the image (or not known)."""
    return a is None or b is None or a.shape != b.shape or \
        float(np.mean(np.linalg.norm(a - b, axis=1))) <= HOLD_SHAPE_MAX


def _best_assignment(costs, n_hands, n_tracks):
    """{hand: track} of the most pairs, then the lowest total cost, among the allowed
    pairs costs[(track, hand)]."""
    if n_hands > EXACT_MATCH_MAX_HANDS:
        track_of, used = {}, set()
        for (i, j), _ in sorted(costs.items(), key=lambda kv: kv[1]):
            if i not in used and j not in track_of:
                used.add(i)
                track_of[j] = i
        return track_of
    best = []                            # [(rank, {hand: track})]

    def search(j, used, chosen, total):
        if j == n_hands:
            rank = (-len(chosen), total)
            if not best or rank < best[0][0]:
                best[:] = [(rank, dict(chosen))]
            return
        for i in range(n_tracks):
            if i not in used and (i, j) in costs:
                chosen[j] = i
                search(j + 1, used | {i}, chosen, total + costs[(i, j)])
                del chosen[j]
        search(j + 1, used, chosen, total)
    search(0, frozenset(), {}, 0.0)
    return best[0][1]


class HandTracks:
    """Camera hands from image to image: each physical hand keeps its id, and its side.

    The detector reads each image afresh, the side of each hand too, and a side can be
    misread for a few images (a right hand's shape read as a left one's). Ids given by side
    handed one hand's id to the other when both were misread. Here a hand is followed by
    where it is in the image: each image's hands are matched to the last image's at the
    lowest total cost, the distance from where each was predicted to be (last place + image
    velocity x dt, in hand sizes) plus SIDE_DISAGREE_COST for a hand read as the other side:
    crossing hands keep their own, and near each other the reading decides. A hand further
    than MATCH_MAX_SIZES from every prediction is new (new id, new session), so a side's
    palm never jumps with its session kept, unless it is the lone hand of its side near
    where that side's hand was (LONE_MATCH_MAX_SIZES): a hand faster than predicted. A
    followed hand keeps its id, and, once its side was read HOLD_AFTER_IMAGES images, its
    side against the reading when it is the same hand misread (within HOLD_MAX_SIZES, much
    the same shape), until SIDE_SWITCH_FRAMES images in a row read the other side; it then
    changes side with a new id."""

    def __init__(self):
        self._tracks = []
        self._next_id = 1
        self._unrelated = False

    def forget(self):
        """The next image is unrelated to the last (a cut): new ids, no velocity."""
        self._tracks = []
        self._unrelated = False

    def forget_motion(self):
        """The next image is a separate photo: no velocity, and its hands are matched by
        side (their place says nothing), so each side's hand keeps its id."""
        for tr in self._tracks:
            tr.t, tr.palm, tr.velocity = None, None, np.zeros(3)
            tr.image_velocity = np.zeros(2)
        self._unrelated = True

    def _new_id(self):
        self._next_id += 1
        return self._next_id - 1

    def _pairs(self, hands, t):
        """[(track or None, hand, place)]: the last image's tracks matched to these hands."""
        places = [image_place(h) for h in hands]
        costs = {}
        for i, tr in enumerate(self._tracks):
            for j, hand in enumerate(hands):
                agree = hand.side == tr.side
                if self._unrelated:
                    if agree:                    # the most confident first
                        costs[(i, j)] = -float(hand.confidence or 0.0)
                    continue
                centre, size = places[j]
                predicted = tr.centre
                if tr.t is not None and t - tr.t > 0:
                    predicted = tr.centre + tr.image_velocity * (t - tr.t)
                d = float(np.linalg.norm(centre - predicted)) / max(size, tr.size)
                if agree and d <= MATCH_MAX_SIZES or not agree and d <= HOLD_MAX_SIZES \
                        and _same_shape(image_shape(hand, centre, size), tr.shape):
                    costs[(i, j)] = d + (0.0 if agree else SIDE_DISAGREE_COST)
        track_of = _best_assignment(costs, len(hands), len(self._tracks))
        if not self._unrelated:
            self._lone_matches(hands, places, track_of)
        return [(self._tracks[track_of[j]] if j in track_of else None, hand, places[j])
                for j, hand in enumerate(hands)]

    def _lone_matches(self, hands, places, track_of):
        """Add to track_of each hand matched to none that is the one unmatched followed hand
        of its side, within LONE_MATCH_MAX_SIZES of that hand's last place, with no other
        followed hand as near (LONE_MATCH_MAX_SIZES)."""
        free = [i for i in range(len(self._tracks)) if i not in track_of.values()]
        for j, hand in enumerate(hands):
            same = [i for i in free if self._tracks[i].side == hand.side]
            if j in track_of or len(same) != 1:
                continue
            centre, size = places[j]
            near = [i for i, tr in enumerate(self._tracks)
                    if np.linalg.norm(centre - tr.centre) / max(size, tr.size) <= LONE_MATCH_MAX_SIZES]
            if near == same:
                track_of[j] = same[0]
                free.remove(same[0])

    def update(self, hands, t, as_side=None):
        """Hands of one image (their side as read in it), at time t -> the hands to
        publish: at most one per side, with ids, sides and palm velocities that follow
        the hands. as_side(hand, side) gives a hand read as the other side (its normal
        and thumb depend on it), or None when unusable; by default the side is changed
        on the hand itself."""
        pairs = self._pairs(hands, t)
        # Sides held by a hand published on them in the last image.
        taken = {tr.side for tr, hand, _ in pairs
                 if tr is not None and tr.published and (hand.side == tr.side or (
                     tr.against + 1 < SIDE_SWITCH_FRAMES and tr.agreed >= HOLD_AFTER_IMAGES))}
        tracks, out = [], []
        for tr, hand, (centre, size) in pairs:
            if tr is None:
                tr = self._start(hand)
            elif hand.side == tr.side or self._unrelated:
                tr.against = 0
                tr.agreed += 1
            else:
                tr.against += 1
                # Read so for long enough; or a hand not published (another one holds
                # its side) read as a side no other hand holds: two hands in view are
                # mostly a left and a right one.
                if tr.against >= SIDE_SWITCH_FRAMES or tr.agreed < HOLD_AFTER_IMAGES or (
                        not tr.published and hand.side not in taken):
                    tr = self._start(hand)
                else:
                    hand = as_side(hand, tr.side) if as_side else _with_side(hand, tr.side)
                    if hand is None:
                        continue                            # lost with its side
            velocity, image_velocity = tr.velocity, tr.image_velocity
            if tr.t is not None and t - tr.t > 0:
                velocity = ((1 - VELOCITY_SMOOTHING) * tr.velocity
                            + VELOCITY_SMOOTHING * (hand.palm_position - tr.palm) / (t - tr.t))
                image_velocity = ((1 - VELOCITY_SMOOTHING) * tr.image_velocity
                                  + VELOCITY_SMOOTHING * (centre - tr.centre) / (t - tr.t))
            hand.palm_velocity = velocity
            hand.id = tr.id
            tr.t, tr.palm, tr.velocity, tr.centre, tr.size = t, hand.palm_position, velocity, centre, size
            tr.image_velocity, tr.shape = image_velocity, image_shape(hand, centre, size)
            tracks.append(tr)
            out.append((tr, hand))
        self._tracks = tracks
        self._unrelated = False
        # One per side: the hand published on it in the last image, else the most confident.
        chosen = {}
        for tr, hand in out:
            rank = (tr.published, float(hand.confidence or 0.0))
            if hand.side not in chosen or rank > chosen[hand.side][0]:
                chosen[hand.side] = (rank, tr, hand)
        for tr in tracks:
            tr.published = any(c[1] is tr for c in chosen.values())
        return [chosen[s][2] for s in ('right', 'left') if s in chosen]

    def _start(self, hand):
        """A new track for a hand seen first now (or on a new side): new id, no velocity."""
        tr = _Track()
        tr.id, tr.side, tr.published, tr.against, tr.agreed = self._new_id(), hand.side, False, 0, 1
        tr.t, tr.palm, tr.velocity, tr.image_velocity = None, None, np.zeros(3), np.zeros(2)
        return tr


def _with_side(hand, side):
    hand.side = side
    return hand


class CameraSource(HandSource):
    """Frames from a capture.* media object through the hand detector.

    camera: CameraModel of the processed image, or None to use hfov_deg at whatever size
    the images come. mirror: flip images left-right before processing (a selfie view);
    input_mirrored: the images already are mirror images. Either way the hands come out
    with the person's side and the person's right as +x.
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
        self.size = (int(width), int(height)) if width and height else None
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
