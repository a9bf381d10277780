"""The annotated camera view: what the camera source sees, with each hand's landmarks,
its side, the gestures the recognizer holds for it, the processed frame rate and, when
given, the pipeline's latency lines (capture -> published, capture -> command) drawn on
the image (ros.sensor_conversions.bgr_image_msg makes it a message).
"""
import logging
import time

import numpy as np

from leap_teleop.hands.sources.landmarks import hand_side
from leap_teleop.hands.tracker import held_names

# MediaPipe's hand skeleton: landmark index pairs.
HAND_CONNECTIONS = ((0, 1), (1, 2), (2, 3), (3, 4), (0, 5), (5, 6), (6, 7), (7, 8),
                    (5, 9), (9, 10), (10, 11), (11, 12), (9, 13), (13, 14), (14, 15),
                    (15, 16), (13, 17), (17, 18), (18, 19), (19, 20), (0, 17))
log = logging.getLogger(__name__)
SIDE_COLOURS = {'right': (60, 180, 255), 'left': (255, 160, 60)}      # BGR
FPS_SMOOTHING = 0.1


def held_gestures(state):
    """Names of the gestures the recognizer holds for a hand, built-in and the user's own:
    a HandState's `held` (its fist, thumb_up, ... flags are the bound actions, not the
    gestures), or those of a GestureState."""
    if state is None:
        return []
    held = getattr(state, 'held', None)
    return list(held) if held is not None else list(held_names(state))


def published_sides(landmarks, hands, width, height):
    """The side each detected hand (HandLandmarks) is published as: that of the frame's
    hand drawn from the same landmarks (the camera source may hold a side the image reads
    otherwise for a few images), else as the landmarks read (hand_side)."""
    sides = []
    for lm in landmarks:
        centre = np.asarray(lm.image, dtype=float)[:, :2].mean(axis=0) * (width, height)
        best, side = 2.0, None          # px: the same landmarks, not a neighbour
        for hand in hands:
            px = getattr(hand, 'image_landmarks', None)
            if px is not None and len(px):
                d = float(np.linalg.norm(np.asarray(px, dtype=float)[:, :2].mean(axis=0) - centre))
                if d < best:
                    best, side = d, hand.side
        sides.append(side)
    return sides


def draw(bgr, landmarks, mirrored, states=None, fps=None, notes=(), sides=None):
    """A copy of bgr with every hand drawn. landmarks: HandLandmarks list as detected in
    this image; states: {side: HandState} (gestures), optional; fps: shown top left;
    notes: lines of text shown bottom left (the latency); sides: the side each hand is
    published as (published_sides; None, or a None in it: as its landmarks read)."""
    import cv2
    out = bgr.copy()
    h, w = out.shape[:2]
    thick = max(1, round(min(w, h) / 240))
    for k, lm in enumerate(landmarks):
        # the side its hand is published as; else as the camera source reads it (chirality first)
        side = (sides[k] if sides is not None and k < len(sides) else None) or hand_side(lm, mirrored)
        colour = SIDE_COLOURS[side]
        pts = np.round(lm.image[:, :2] * (w, h)).astype(int)
        for a, b in HAND_CONNECTIONS:
            cv2.line(out, tuple(pts[a]), tuple(pts[b]), colour, thick, cv2.LINE_AA)
        for p in pts:
            cv2.circle(out, tuple(p), thick + 2, (255, 255, 255), -1, cv2.LINE_AA)
            cv2.circle(out, tuple(p), thick + 2, colour, 1, cv2.LINE_AA)
        state = (states or {}).get(side)
        gestures = held_gestures(state)
        label = '%s %.2f%s' % (side, lm.score, (': ' + ' '.join(gestures)) if gestures else '')
        pose = getattr(state, 'pose_class', '')
        if pose:        # what the pose model sees this frame, held or not
            label += ' [%s %.2f]' % (pose, getattr(state, 'pose_probability', 0.0))
        x, y = int(pts[:, 0].min()), int(pts[:, 1].min()) - 8
        _text(out, label, (max(2, x), max(16, y)), colour, thick)
    if fps is not None:
        _text(out, '%.1f fps' % fps, (6, 20), (255, 255, 255), thick)
    small = max(1, thick - 1)           # smaller than the labels: several lines, kept out of the way
    for k, line in enumerate(reversed(list(notes))):
        _text(out, line, (6, h - 6 - k * 14 * thick), (255, 255, 255), small, 0.35 * thick)
    return out


def _text(img, text, org, colour, thick, scale=None):
    import cv2
    scale = scale or 0.5 * thick
    cv2.putText(img, text, org, cv2.FONT_HERSHEY_SIMPLEX, scale, (0, 0, 0), thick + 2,
                cv2.LINE_AA)
    cv2.putText(img, text, org, cv2.FONT_HERSHEY_SIMPLEX, scale, colour, thick, cv2.LINE_AA)


class CameraView:
    """Joins a camera source's images with the recognizer's states: give on_image to the
    source (source.on_image) and on_frame to LeapInterface.add_listener; publish(frame,
    image) receives each annotated image. wanted() -> False skips the drawing (no one
    is looking). notes() gives the lines drawn bottom left (called per drawn image)."""

    def __init__(self, mirrored, publish, wanted=lambda: True, clock=time.monotonic,
                 notes=tuple):
        self.mirrored = mirrored
        self.notes = notes
        self.publish = publish
        self.wanted = wanted
        self.clock = clock
        self.fps = None
        self._last_t = None
        self._pending = None

    def on_image(self, frame, bgr, landmarks):
        t = self.clock()
        if self._last_t is not None and t > self._last_t:
            rate = 1.0 / (t - self._last_t)
            self.fps = rate if self.fps is None else (
                (1 - FPS_SMOOTHING) * self.fps + FPS_SMOOTHING * rate)
        self._last_t = t
        self._pending = (frame.id, bgr, landmarks)

    def on_frame(self, frame, states):
        pending, self._pending = self._pending, None
        if pending is None or pending[0] != frame.id or not self.wanted():
            return
        try:
            notes = self.notes()
        except Exception as e:  # noqa: BLE001 - the overlay's text must not end the hand source
            log.warning('camera view: no latency lines: %s', e)
            notes = ()
        h, w = pending[1].shape[:2]
        sides = published_sides(pending[2], getattr(frame, 'hands', ()), w, h)
        self.publish(frame, draw(pending[1], pending[2], self.mirrored, states, self.fps, notes,
                                 sides))
