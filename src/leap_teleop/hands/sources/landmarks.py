"""Camera hand landmarks (MediaPipe's 21 per hand) -> the project's TrackedHand, in Leap axes.

Pure numpy: no MediaPipe, no ROS. Input per hand: the image landmarks (normalized x, y in
[0, 1] of the image width / height, z relative depth), the metric world landmarks
(metres, hand-centred, in the camera's axes: x right in the image, y down, z away from
the camera), the handedness label and its score.

Axes. The camera faces the user; the Leap's axes are the user's: x to the user's right,
y up, z toward the user (= away from the camera). In an image that is not mirrored the
user's right is the image's left, so a camera vector (x, y, z) is (-x, -y, z) in Leap
axes; in a mirrored (selfie) image it is (x, -y, z).

Handedness. MediaPipe labels hands as if the image were mirrored: on a mirrored image
its label is the person's hand, on a plain one the other. The label is a separate
classifier's guess; the world landmarks carry the hand's chirality themselves: fingers
bend toward the palm, and a right hand's palm faces (index knuckle - pinky knuckle) x
(wrist -> middle knuckle). Where the fingertips sit clearly on one side of the palm
(`CHIRALITY_MIN` palm lengths, on average) that decides the side; on the shared photos
it agrees with the label on 28 of 30 hands and, on the other two (labels scored 0.69),
with the label of a third photo of the same hand.

Shape comes from the world landmarks, rescaled so the palm (wrist to middle-finger
knuckle) has the user's length (`palm_length_mm`). Position: the translation that puts
that rescaled hand where the camera sees it, by least squares over all 21 image
landmarks with the camera's intrinsics (a pinhole PnP whose rotation is known, so
linear in the translation). Depth is then exact up to the ratio of the true palm length
to the configured one (10 % off -> 10 % farther or nearer) plus landmark noise.

Touching fingertips. The world landmarks are weakest in depth: on photos of OK signs they
put thumb and index tips 5-6 cm apart in depth while the image shows them touching. Where
the thumb tip and fingertips touch in the image (their image gap, back-projected to the
tips' depth, within a fingertip's width) the depth between them is the only thing parting
them, and it is the least certain number: those fingers are turned about their base
joints, along the camera's rays (so the image is unchanged), until the tips meet in depth.
"""
import math
from dataclasses import dataclass

import numpy as np

from leap_teleop.hands.frame import Finger, TrackedHand
from leap_teleop.vectors import unit

N_LANDMARKS = 21
WRIST = 0
# MediaPipe landmark indices per finger, in FINGER_NAMES order: the Leap's mcp, pip, dip,
# tip joints. The Leap's thumb has a zero-length metacarpal, so its "mcp" is the
# anatomical CMC joint and its "pip" the anatomical MCP.
FINGER_JOINTS = ((1, 2, 3, 4), (5, 6, 7, 8), (9, 10, 11, 12), (13, 14, 15, 16),
                 (17, 18, 19, 20))
KNUCKLES = (5, 9, 13, 17)
MIDDLE_MCP = 9
# A palm length (wrist to middle-finger knuckle) between the measured median of
# MediaPipe's world landmarks on the shared photos (94 mm) and adult hand tables.
DEFAULT_PALM_LENGTH_MM = 95.0
# The virtual Leap device in camera terms: where the camera sits in Leap axes (mm). A hand
# 500 mm in front of the camera, on its axis, is reported at (0, 200, 0): the middle of
# the Leap's interaction box.
DEFAULT_CAMERA_POSITION_MM = (0.0, 200.0, -500.0)
DEFAULT_HFOV_DEG = 60.0            # a typical laptop webcam
MAX_IMAGE_SIDE = 16384             # pixels: beyond any camera's frames

# Extended: a finger whose tip points along the hand (angle between the hand direction
# and knuckle -> tip) under this and whose joints are nearly straight.
EXTENDED_MAX_DEG = 60.0
EXTENDED_MAX_BEND_DEG = 70.0       # sum of the pip and dip bends (fists: > 140)
# Thumb extended: its tip beyond the index knuckle, thumbward, by this fraction of the palm
# length, and the thumb pointing thumbward rather than across the palm or along the index
# (on the shared photos: open palms and thumbs-up 0.34..0.83 and 44..69 deg, fists with
# the thumb over or beside the fingers -0.44..0.28 and 85..141 deg).
THUMB_OUT_FRACTION = 0.3
THUMB_MAX_ANGLE_DEG = 75.0
# Mean fingertip offset (palm lengths) along the right-hand palm normal beyond which the
# landmarks' own chirality decides the side (shared photos: 0.12..0.67 either way).
CHIRALITY_MIN = 0.08
# Grab strength: mean over the four fingers of (flex - lo) / (hi - lo), clipped to 0..1,
# flex = angle (deg) between the hand direction and the distal bone.
GRAB_FLEX_DEG = (40.0, 150.0)
# Pinch strength: thumb tip to the nearest fingertip, 1 at or below the first distance,
# 0 at or beyond the second (fractions of the palm length).
PINCH_GAP_FRACTION = (0.2, 0.65)
THUMB_TIP = 4
FINGERTIPS = (8, 12, 16, 20)
# Thumb tip to fingertip gap in the image (mm at the tips' depth, over the palm length) at
# or below which the tips touch (two fingertip pads side by side: ~0.2 palm lengths) and
# their depth gap is removed; beyond the second it is left alone, between in proportion.
# Shared photos: OK signs and the "O" 0.06..0.21; a fist's thumb over the index 0.13; other
# poses (fists, pinky-only, hooked index) 0.26 and up. A relaxed hand seen edge-on (the
# palm clip's first frames) also has its thumb tip on the index in the image (0.09..0.13):
# joined too, it reads as before once filtered (a fist, then open).
TIP_TOUCH_GAP = (0.2, 0.3)


@dataclass
class CameraModel:
    """Pinhole intrinsics in pixels of the image the landmarks were found in."""
    width: int
    height: int
    fx: float
    fy: float
    cx: float
    cy: float

    @classmethod
    def from_hfov(cls, width, height, hfov_deg=DEFAULT_HFOV_DEG):
        if not 1.0 <= hfov_deg <= 179.0:
            raise ValueError('horizontal field of view must be in [1, 179] deg, got %r'
                             % hfov_deg)
        f = 0.5 * width / math.tan(math.radians(hfov_deg) / 2.0)
        return cls(int(width), int(height), f, f, 0.5 * width, 0.5 * height)

    @classmethod
    def from_matrix(cls, width, height, k):
        """From a 3x3 camera matrix (row-major, 9 numbers: sensor_msgs/CameraInfo K)."""
        k = np.asarray(k, dtype=float).reshape(9)
        if not (np.all(np.isfinite(k)) and k[0] > 0 and k[4] > 0):
            raise ValueError('camera matrix needs positive finite fx, fy, got %r' % (list(k),))
        if not (0 < width <= MAX_IMAGE_SIDE and 0 < height <= MAX_IMAGE_SIDE):
            # the lens is rescaled to each frame's size by these
            raise ValueError('image size needs 1..%d pixels a side, got %r x %r'
                             % (MAX_IMAGE_SIDE, width, height))
        return cls(int(width), int(height), float(k[0]), float(k[4]), float(k[2]), float(k[5]))

    def scaled_to(self, width, height):
        """The same lens for the image resized to width x height."""
        sx, sy = width / self.width, height / self.height
        return CameraModel(int(width), int(height), self.fx * sx, self.fy * sy,
                           self.cx * sx, self.cy * sy)

    def letterboxed(self, scale, pad_x, pad_y, width, height):
        """The same lens for the image scaled by `scale` and placed at (pad_x, pad_y) in a
        width x height canvas."""
        return CameraModel(int(width), int(height), self.fx * scale, self.fy * scale,
                           self.cx * scale + pad_x, self.cy * scale + pad_y)


@dataclass
class HandLandmarks:
    """One detected hand as the detector gives it."""
    image: np.ndarray          # (21, 3) normalized x, y, relative z
    world: np.ndarray          # (21, 3) metres, camera axes, hand-centred
    label: str                 # 'Left' | 'Right' as the detector says (mirrored convention)
    score: float               # handedness score, 0..1

    @classmethod
    def from_dict(cls, d):
        """From a hands.json-style dict: handedness, score, landmarks, world_landmarks."""
        return cls(np.asarray(d['landmarks'], dtype=float).reshape(N_LANDMARKS, 3),
                   np.asarray(d['world_landmarks'], dtype=float).reshape(N_LANDMARKS, 3),
                   str(d['handedness']), float(d['score']))

    def to_dict(self, decimals=5):
        return {'handedness': self.label, 'score': round(float(self.score), decimals),
                'landmarks': np.round(self.image, decimals).tolist(),
                'world_landmarks': np.round(self.world, decimals).tolist()}


def person_side(label, mirrored):
    """The person's hand ('right' | 'left') from the detector's label."""
    detected = 'right' if label.lower().startswith('r') else 'left'
    if mirrored:
        return detected
    return 'left' if detected == 'right' else 'right'


def chirality(world):
    """Mean fingertip offset from the knuckles along the right-hand palm normal, in palm
    lengths, of (21, 3) landmarks in a right-handed frame: > 0 a right hand's shape, < 0 a
    left hand's (fingers bend toward the palm)."""
    w = np.asarray(world, dtype=float)
    palm = np.linalg.norm(w[MIDDLE_MCP] - w[WRIST])
    normal = unit(np.cross(w[5] - w[17], w[MIDDLE_MCP] - w[WRIST]))
    tips, knuckles = w[[8, 12, 16, 20]], w[list(KNUCKLES)]
    return float(np.mean((tips - knuckles) @ normal)) / palm if palm > 0 else 0.0


def hand_side(lm, mirrored):
    """The person's hand: from the landmarks' chirality when clear, else the label."""
    c = chirality(lm.world)
    if not abs(c) >= CHIRALITY_MIN:
        return person_side(lm.label, mirrored)
    seen = 'right' if c > 0 else 'left'         # the hand as the (processed) image shows it
    if mirrored:
        return 'left' if seen == 'right' else 'right'
    return seen


def camera_to_leap(mirrored):
    """3x3 matrix taking camera-axes vectors (of the image as processed) to Leap axes."""
    return np.diag((1.0 if mirrored else -1.0, -1.0, 1.0))


def solve_translation(points_mm, pixels, camera):
    """Camera-frame translation t (mm) minimising, in the linearised (algebraic) sense,
    the reprojection error of points_mm + t onto pixels: pinhole u = fx X / Z + cx.

    points_mm (N, 3) in camera axes, pixels (N, 2). Rows: fx tx - (u - cx) tz =
    (u - cx) Z_i - fx X_i, and the same for v. NaN when degenerate or behind the camera.
    """
    p = np.asarray(points_mm, dtype=float)
    uv = np.asarray(pixels, dtype=float)
    du = uv[:, 0] - camera.cx
    dv = uv[:, 1] - camera.cy
    n = len(p)
    a = np.zeros((2 * n, 3))
    b = np.empty(2 * n)
    a[:n, 0] = camera.fx
    a[:n, 2] = -du
    b[:n] = du * p[:, 2] - camera.fx * p[:, 0]
    a[n:, 1] = camera.fy
    a[n:, 2] = -dv
    b[n:] = dv * p[:, 2] - camera.fy * p[:, 1]
    t, _, rank, _ = np.linalg.lstsq(a, b, rcond=None)
    if rank < 3 or not np.all(np.isfinite(t)) or t[2] <= 0:
        return np.full(3, np.nan)
    return t


def project(points_mm, camera):
    """Pixels (N, 2) of camera-frame points (N, 3), mm."""
    p = np.asarray(points_mm, dtype=float)
    return np.stack((camera.fx * p[:, 0] / p[:, 2] + camera.cx,
                     camera.fy * p[:, 1] / p[:, 2] + camera.cy), axis=1)


def _angle_deg(u, v):
    c = float(np.dot(unit(u), unit(v)))
    return math.degrees(math.acos(min(1.0, max(-1.0, c)))) if math.isfinite(c) else math.nan


def image_gap(points_mm, pixels, camera, i, j):
    """The image distance between landmarks i and j, in mm at their mean depth."""
    du = (pixels[i, 0] - pixels[j, 0]) / camera.fx
    dv = (pixels[i, 1] - pixels[j, 1]) / camera.fy
    return math.hypot(du, dv) * 0.5 * (points_mm[i, 2] + points_mm[j, 2])


def join_touching_tips(points_mm, pixels, camera, palm_length_mm):
    """The placed hand (21, 3) (camera axes, mm) with the thumb tip and the fingertips it
    touches in the image brought to one depth: each touching fingertip gets a weight w
    from its image gap (1 touching, 0 apart: TIP_TOUCH_GAP), the tips meet at the
    w-weighted mean depth of the thumb tip and those tips (the thumb tip with the largest
    w), a pair with weight w keeping (1 - w) of its depth gap. Each finger is turned about
    its base joint along the camera's rays, its inner joints in proportion to their place
    on the finger, so every landmark keeps its pixel."""
    p = np.array(points_mm, dtype=float)
    g0, g1 = TIP_TOUCH_GAP
    weights = [min(max((g1 - image_gap(p, pixels, camera, THUMB_TIP, j) / palm_length_mm)
                       / (g1 - g0), 0.0), 1.0) for j in FINGERTIPS]
    if not max(weights) > 0.0:
        return p
    z = p[:, 2]
    meet = (z[THUMB_TIP] + sum(w * z[j] for w, j in zip(weights, FINGERTIPS))) \
        / (1.0 + sum(weights))
    moves = [(FINGER_JOINTS[0], max(weights) * (meet - z[THUMB_TIP]))]
    moves += [(FINGER_JOINTS[k + 1], w * (meet - z[j]))
              for k, (w, j) in enumerate(zip(weights, FINGERTIPS)) if w > 0.0]
    for chain, dz in moves:
        for n, i in enumerate(chain):
            depth = p[i, 2]
            moved = depth + dz * n / (len(chain) - 1)
            if depth > 0.0 and moved > 0.0:
                p[i] *= moved / depth
    return p


def hand_basis(joints, side):
    """(palm normal, hand direction) unit vectors from (21, 3) joints in a right-handed
    frame: direction wrist -> middle knuckle, normal out of the palm (orthogonalised)."""
    wrist = joints[WRIST]
    across = joints[5] - joints[17]              # index knuckle <- pinky knuckle
    direction = unit(joints[MIDDLE_MCP] - wrist)
    # Right hand: thumb side x fingers points out of the palm; a left hand's mirror image.
    normal = np.cross(across, direction) if side == 'right' else np.cross(direction, across)
    normal = unit(normal)
    direction = unit(direction - normal * np.dot(direction, normal))
    return normal, direction


def palm_centre(joints):
    """The Leap's palm position: halfway between the wrist and the knuckles' centroid."""
    return 0.5 * (joints[WRIST] + joints[list(KNUCKLES)].mean(axis=0))


def hand_from_landmarks(lm, camera, mirrored=False, palm_length_mm=DEFAULT_PALM_LENGTH_MM,
                        camera_position_mm=DEFAULT_CAMERA_POSITION_MM, hand_id=0,
                        velocity=None, side=None):
    """A TrackedHand (mm, Leap axes) from HandLandmarks seen by `camera`; None when unusable.
    side: the person's hand to read it as (a followed hand's), else hand_side's."""
    world = np.asarray(lm.world, dtype=float)
    image = np.asarray(lm.image, dtype=float)
    if world.shape != (N_LANDMARKS, 3) or image.shape != (N_LANDMARKS, 3) \
            or not (np.all(np.isfinite(world)) and np.all(np.isfinite(image))):
        return None
    model_palm = float(np.linalg.norm(world[MIDDLE_MCP] - world[WRIST]))
    if not model_palm > 1e-4:
        return None
    scale = palm_length_mm / model_palm          # metres of the model -> the user's mm
    shape_cam = world * scale
    pixels = image[:, :2] * (camera.width, camera.height)
    t = solve_translation(shape_cam, pixels, camera)
    if not np.all(np.isfinite(t)):
        return None
    rot = camera_to_leap(mirrored)
    side = side if side in ('right', 'left') else hand_side(lm, mirrored)
    placed = join_touching_tips(shape_cam + t, pixels, camera, palm_length_mm)
    joints = placed @ rot.T + np.asarray(camera_position_mm, dtype=float)
    normal, direction = hand_basis(joints, side)
    if not (np.all(np.isfinite(normal)) and np.all(np.isfinite(direction))):
        return None
    thumbward = np.cross(direction, normal) * (1.0 if side == 'right' else -1.0)
    fingers, flex = [], []
    for i, (a, b, c, d) in enumerate(FINGER_JOINTS):
        mcp, pip, dip, tip = joints[a], joints[b], joints[c], joints[d]
        if i == 0:
            out = float(np.dot(tip - joints[5], thumbward)) / palm_length_mm
            extended = (out > THUMB_OUT_FRACTION
                        and _angle_deg(tip - pip, thumbward) < THUMB_MAX_ANGLE_DEG)
        else:
            bend = _angle_deg(pip - mcp, dip - pip) + _angle_deg(dip - pip, tip - dip)
            extended = (_angle_deg(direction, tip - mcp) < EXTENDED_MAX_DEG
                        and bend < EXTENDED_MAX_BEND_DEG)
            flex.append(_angle_deg(direction, tip - dip))
        fdir = unit(tip - pip)
        fingers.append(Finger(tip=tip, direction=fdir, extended=bool(extended),
                              mcp=mcp, pip=pip, dip=dip))
    lo, hi = GRAB_FLEX_DEG
    grab = float(np.mean(np.clip((np.array(flex) - lo) / (hi - lo), 0.0, 1.0)))
    pinch = gap_pinch_strength(joints, palm_length_mm)
    return TrackedHand(side=side, palm_position=palm_centre(joints),
                palm_velocity=np.zeros(3) if velocity is None else np.asarray(velocity, float),
                palm_normal=normal, direction=direction, grab_strength=grab,
                pinch_strength=pinch, confidence=float(min(max(lm.score, 0.0), 1.0)),
                fingers=tuple(fingers), id=int(hand_id), image_landmarks=pixels)


def gap_pinch_strength(points, palm):
    """Pinch strength 0..1 of 21 landmarks (3-D in the world, or 2-D in the picture): the
    thumb tip's gap to the nearest fingertip over `palm` (a length in the same units), 1 at
    PINCH_GAP_FRACTION[0] or less, 0 at [1] or more."""
    gap = min(np.linalg.norm(points[THUMB_TIP] - points[j]) for j in FINGERTIPS) / palm
    g0, g1 = PINCH_GAP_FRACTION
    return float(min(max((g1 - gap) / (g1 - g0), 0.0), 1.0))


def reprojection_rms_px(lm, camera, palm_length_mm=DEFAULT_PALM_LENGTH_MM):
    """RMS pixel distance between the image landmarks and the placed world landmarks:
    how well the world shape and the image agree (a check of the axes and the solver)."""
    world = np.asarray(lm.world, dtype=float)
    scale = palm_length_mm / float(np.linalg.norm(world[MIDDLE_MCP] - world[WRIST]))
    shape = world * scale
    pixels = np.asarray(lm.image, dtype=float)[:, :2] * (camera.width, camera.height)
    t = solve_translation(shape, pixels, camera)
    return float(np.sqrt(np.mean(np.sum((project(shape + t, camera) - pixels) ** 2, axis=1))))
