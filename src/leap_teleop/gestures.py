"""Per-hand gesture recognition from hand geometry.

GestureRecognizer decides from where the fingertips and finger bones are relative to the
palm (not from the SDK's per-finger `extended` flags or its pinch strength, which real
captures show to be unreliable: see shared/data/leapjs/README.md), filters each held
gesture in time (on after `on_frames` consistent frames, off after `off_frames`, with
looser thresholds to stay on than to turn on), gates low-confidence frames, and emits
events: start / stop of held gestures, unfold (fist -> open), fold (open -> fist) and
circles ('circle_cw' / 'circle_ccw', value = radius in m) traced by the palm or a
fingertip. GestureRecognizer(stateless=True) classifies every frame on its own.

OriginalRules reproduces the mirrored design's per-frame rules (DESIGN.md section 4): the
evaluation baseline.

Hand frame used throughout (from palm normal n and hand direction d): x = thumbward
(cross(d, n) for a right hand, its negative for a left one), y = n (out of the palm),
z = d (toward the fingers). One code path serves both hands.
"""
import math
from bisect import bisect_left
from collections import deque
from dataclasses import dataclass, field
from typing import List, Optional, Tuple

import numpy as np

from .frame import FINGER_NAMES

PINCH_THRESHOLD = 0.2   # original: pinch when strength > 0.2; pinch_value = strength - 0.2
HELD_GESTURES = ('fist', 'thumb_up', 'pinch', 'rock', 'open')

# -- geometry thresholds (mm, degrees); (to turn on, to stay on) -------------------------
# A finger's bend is the larger of: the angle between the hand direction and its distal
# bone, and the angle between its proximal and distal bones. On the recordings open
# fingers bend < ~65 deg (a relaxed pinky the most), fingers in a fist > ~100 deg.
CURLED_BEND = (95.0, 85.0)         # curled when bend > 95 (stays curled while > 85)
EXTENDED_BEND = (70.0, 80.0)       # extended when bend < 70 (stays while < 80)
# Thumbs-up needs the fingers deeper in the fist to start: every unfold passes through a
# fist with the thumb already out while the fingers are still half-bent.
THUMB_UP_CURLED_BEND = (110.0, 85.0)
# Thumb tip's thumbward distance from the palm centre: out (thumbs-up, open, gun) is
# 55..120 mm on the recordings, tucked over a fist 10..35 mm.
THUMB_OUT_MM = (50.0, 42.0)
# Thumb-index tip gap: touching ~15..30 mm, apart > 55 mm.
PINCH_GAP_MM = (35.0, 45.0)
PINCH_GAP_OPEN_MM = 60.0           # geometric pinch strength 0 at this gap, 1 at 20 mm
PINCH_GAP_CLOSED_MM = 20.0
# In a pinch the other fingers are less bent than the index; in a closing fist they all
# bend together. Required margin (deg) of index bend over the least bent of the rest.
PINCH_BEND_MARGIN = 15.0
MIN_CONFIDENCE = 0.1               # below: the frame does not count (SDK fists go to ~0.15)
HOLD_LOW_CONFIDENCE_S = 0.25       # held gestures survive this long on low-confidence frames
# Minimum time a gesture must be seen before it turns on (besides on_frames).
ON_TIME_S = {}
# Thumbs-up arms a robot, and every fist -> open unfold passes ~0.1 s through a fist with
# the thumb out: no thumbs-up starts while the mean finger bend has dropped by more than
# OPENING_DEG within the last OPENING_WINDOW_S (the hand is unfolding).
OPENING_DEG = 25.0
OPENING_WINDOW_S = 0.15

# -- circles -------------------------------------------------------------------------------
# Each track (the smoothed palm, every fingertip) keeps its recent path, resampled at a
# small spacing (drops jitter while still). Cheap gate, per new point, for a few recent
# stretches of the path: how round the stretch is, closed by its chord (isoperimetric
# quotient 4 pi area / length^2: 1 for a circle, ~0.96 for a 270 deg arc, ~0.75 for a
# half circle, ~0 for straight or back-and-forth moves; prefix sums make it O(1)). The
# roundest stretch past the gate is fitted with a circle (plane + least squares), which
# decides: an arc of >= CIRCLE_ARC about the fitted centre, swept one way, close to it.
# (track name, spacing mm, min radius mm, max radius mm, stretches looked at (s), top
# speed mm/s); the SDK's minimum radius is 5 mm, the algebraic fit reads small noisy arcs
# ~10% small.
# Top speed: a fingertip that moved faster than the SDK's default swipe velocity
# (Gesture.Swipe.MinVelocity, 1000 mm/s) within the stretch holding the loop was swiping:
# the SDK gives a pointable's motion to one gesture, and the loop a fast stroke closes on
# its way back is no circle. (Palm circles are ours, not the SDK's: no limit.)
CIRCLE_TRACKS = (('palm', 2.0, 25.0, 300.0, (0.5, 0.8, 1.1, 1.6), math.inf),
                 ('finger', 1.0, 4.0, 60.0, (0.2, 0.3, 0.4, 0.55), 1000.0))
# Arc that makes a circle: 270 deg, the Leap SDK's (Gesture.Circle.MinArc 1.5 pi): its
# circles start there (progress 0.76..0.95 turns on the recordings).
CIRCLE_ARC = 1.5 * math.pi
CIRCLE_MIN_ROUNDNESS = 0.6         # isoperimetric quotient that triggers a fit
CIRCLE_MIN_POINTS = 8
# |circle normal . finger direction| of a fingertip circle; the SDK's own circles on the
# recordings: 0.71..0.98 in 18 of 20 (cos 45 deg = 0.71)
CIRCLE_MIN_ACROSS = 0.7
CIRCLE_MAX_TRAVEL = 1.3            # angular travel / net sweep: more is back and forth
CIRCLE_MAX_RESIDUAL = 0.35         # rms radial residual / radius
CIRCLE_MAX_DEVIATION = 0.6         # largest radial deviation / radius
CIRCLE_RETRY_POINTS = 1            # after a failed fit, new points before the next one
PALM_SMOOTHING = 0.35              # exponential smoothing factor of the palm path
CIRCLE_REFRACTORY_S = 0.25         # one event per circle even when several fingers trace it


@dataclass
class GestureEvent:
    gesture: str
    active: bool = True
    value: float = 0.0
    # Circles only: what traced it ('palm' or a finger name, as the SDK's circles belong
    # to one pointable) and its centre [x, y, z] in mm, Leap axes.
    source: str = ''
    center: Optional[Tuple[float, float, float]] = None


@dataclass
class GestureState:
    fist: bool = False
    thumb_up: bool = False
    pinch: bool = False
    pinch_value: float = 0.0           # 0..0.8
    rock: bool = False
    open: bool = False
    finger_extended: Tuple[bool, ...] = (False,) * 5
    events: List[GestureEvent] = field(default_factory=list)


def _flags(hand):
    return tuple(bool(f.extended) for f in hand.fingers) if len(hand.fingers) == 5 else (False,) * 5


def _num(x, default=0.0):
    try:
        x = float(x)
    except (TypeError, ValueError):
        return default
    return x if math.isfinite(x) else default


class OriginalRules:
    """The original system's rules, frame by frame (the baseline to beat)."""

    def classify(self, hand):
        ext = _flags(hand)
        grab = _num(hand.grab_strength)
        pinch = _num(hand.pinch_strength)
        state = GestureState(finger_extended=ext)
        if grab > 0.5:
            state.thumb_up = ext[0]
            state.fist = not ext[0]
        state.pinch = pinch > PINCH_THRESHOLD
        state.pinch_value = min(pinch - PINCH_THRESHOLD, 0.8) if state.pinch else 0.0
        state.rock = ext[0] and ext[1] and not ext[2] and not ext[3] and ext[4]
        state.open = all(ext) and grab < 0.5
        return state


# -- geometry -----------------------------------------------------------------------------
# Plain Python floats throughout: on 3-vectors numpy's per-call overhead costs more than
# the arithmetic (this path runs for every hand of every frame).
_NAN = math.nan
_isfinite = math.isfinite


@dataclass
class HandGeometry:
    """What the rules look at. NaN where the frame lacks the data."""
    bend: Tuple[float, ...]     # 5 bends, degrees; [0] is the thumb's (unused by the rules)
    thumb_out: float            # mm, thumb tip's thumbward offset from the palm centre
    pinch_gap: float            # mm, thumb tip to index tip
    tips_world: list            # 5 [x, y, z] fingertips, mm, Leap axes
    basis: tuple                # rows: thumbward, normal, direction (Leap axes), unit
    palm: list                  # [x, y, z] palm centre, mm


def _f3(v):
    """[x, y, z] (numbers) of a 3-vector, or None when absent / malformed."""
    if v.__class__ is np.ndarray:
        return v.tolist() if v.shape == (3,) else None
    if v is None or len(v) != 3:
        return None
    return [float(v[0]), float(v[1]), float(v[2])]


def _unit(x, y, z):
    n = math.sqrt(x * x + y * y + z * z)
    if n > 0.0 and n != math.inf:
        return x / n, y / n, z / n
    return _NAN, _NAN, _NAN


def _angle_deg(c):
    """acos in degrees of a cosine; NaN stays NaN."""
    if c != c:
        return _NAN
    return math.degrees(math.acos(1.0 if c > 1.0 else -1.0 if c < -1.0 else c))


def hand_geometry(hand):
    """HandGeometry of a Hand, or None when its palm frame is unusable (non-finite or
    degenerate normal / direction, missing fingers)."""
    fingers = hand.fingers
    if len(fingers) != 5:
        return None
    try:
        palm = _f3(hand.palm_position)
        n = _f3(hand.palm_normal)
        d = _f3(hand.direction)
        if palm is None or n is None or d is None:
            return None
        px, py, pz = palm
        nx, ny, nz = n
        dx, dy, dz = d
        if not (_isfinite(px + py + pz) and _isfinite(nx + ny + nz) and _isfinite(dx + dy + dz)):
            return None
        nn = math.sqrt(nx * nx + ny * ny + nz * nz)
        if nn < 1e-6:
            return None
        nx, ny, nz = nx / nn, ny / nn, nz / nn
        k = dx * nx + dy * ny + dz * nz
        dx, dy, dz = dx - nx * k, dy - ny * k, dz - nz * k
        dn = math.sqrt(dx * dx + dy * dy + dz * dz)
        if dn < 1e-6:
            return None
        dx, dy, dz = dx / dn, dy / dn, dz / dn
        # thumbward = d x n for a right hand, its negative for a left one
        s = -1.0 if hand.side == 'left' else 1.0
        tx, ty, tz = s * (dy * nz - dz * ny), s * (dz * nx - dx * nz), s * (dx * ny - dy * nx)
        tips = []
        bend = []
        for f in fingers:
            tip = _f3(f.tip)
            if tip is None:
                return None
            tips.append(tip)
            ax, ay, az = tip
            dip = f.dip
            dip = _f3(dip) if dip is not None else tip
            if dip is None:
                return None
            # The distal bone (dip -> tip); the SDK's finger direction when joints are
            # absent (it follows the middle bone on real captures: the second choice).
            ux, uy, uz = ax - dip[0], ay - dip[1], az - dip[2]
            l2 = ux * ux + uy * uy + uz * uz
            if not (l2 >= 1e-6 and l2 != math.inf):
                fd = _f3(f.direction)
                if fd is None:
                    return None
                ux, uy, uz = fd
            ux, uy, uz = _unit(ux, uy, uz)
            flex = _angle_deg(ux * dx + uy * dy + uz * dz)
            pip, mcp = f.pip, f.mcp
            curl = _NAN
            if pip is not None and mcp is not None:
                pip, mcp = _f3(pip), _f3(mcp)
                if pip is None or mcp is None:
                    return None
                vx, vy, vz = _unit(pip[0] - mcp[0], pip[1] - mcp[1], pip[2] - mcp[2])
                curl = _angle_deg(vx * ux + vy * uy + vz * uz)
            # the larger of the two (like np.fmax: a NaN loses)
            bend.append(flex if curl != curl else curl if flex != flex or curl > flex else flex)
        th, ix = tips[0], tips[1]
        gx, gy, gz = th[0] - ix[0], th[1] - ix[1], th[2] - ix[2]
        gap = math.sqrt(gx * gx + gy * gy + gz * gz)
        thumb_out = (th[0] - px) * tx + (th[1] - py) * ty + (th[2] - pz) * tz
    except (TypeError, ValueError, AttributeError, IndexError, OverflowError):
        return None
    return HandGeometry(bend=tuple(bend), thumb_out=thumb_out, pinch_gap=gap, tips_world=tips,
                        basis=((tx, ty, tz), (nx, ny, nz), (dx, dy, dz)), palm=palm)


def geometric_pinch_strength(gap):
    """0..1 from the thumb-index gap (1 = touching), like the SDK's pinch strength."""
    if not math.isfinite(gap):
        return 0.0
    s = (PINCH_GAP_OPEN_MM - gap) / (PINCH_GAP_OPEN_MM - PINCH_GAP_CLOSED_MM)
    return min(max(s, 0.0), 1.0)


def classify_geometry(g, hand, active=None, opening=False):
    """Per-frame decisions {gesture: bool}, 'pinch_value' and 'extended' (5 bools) from a
    HandGeometry. `active` = gestures currently on: they are judged on the looser
    stay-on thresholds (hysteresis). `opening`: the fingers are unfolding fast (a
    stateful caller knows); a thumbs-up does not start then."""
    active = active or ()
    b1, b2, b3, b4 = g.bend[1:]                  # index, middle, ring, pinky
    known = _isfinite(b1 + b2 + b3 + b4)
    least = min(b1, b2, b3, b4) if known else _NAN
    # Each of fist / thumbs-up keeps its own hysteresis: leaving a fist through a brief
    # thumb-out phase must not count as a thumbs-up that is already on.
    fist_curled = known and least > CURLED_BEND[1 if 'fist' in active else 0]
    thumb_curled = known and least > THUMB_UP_CURLED_BEND[1 if 'thumb_up' in active else 0]
    ext_th = EXTENDED_BEND[1 if ('open' in active or 'rock' in active) else 0]
    e1, e2, e3, e4 = b1 < ext_th, b2 < ext_th, b3 < ext_th, b4 < ext_th   # NaN -> False
    thumb_out = g.thumb_out
    out = thumb_out > THUMB_OUT_MM[1 if ('thumb_up' in active or 'open' in active) else 0]
    fist = fist_curled and not out
    thumb_up = thumb_curled and out and ('thumb_up' in active or not opening)
    # Rock: index and pinky out, middle and ring curled (looser bar for the curl: a
    # horns hand rarely folds middle and ring as deep as a fist).
    rock = e1 and e4 and b2 > CURLED_BEND[1] and b3 > CURLED_BEND[1]
    gap = g.pinch_gap
    pinch = False
    if gap < PINCH_GAP_MM[1 if 'pinch' in active else 0] and not fist and not thumb_up:
        rest = min(b2, b3, b4)
        if _isfinite(b2 + b3 + b4):
            pinch = (not _isfinite(b1) or b1 > rest + PINCH_BEND_MARGIN
                     or not rest > CURLED_BEND[1])
    # Open: four fingers straight, thumb either way (a flat hand tucks it), not pinching.
    opn = e1 and e2 and e3 and e4 and not pinch
    value = 0.0
    if pinch:
        strength = _num(hand.pinch_strength, -1.0)
        if not 0.0 <= strength <= 1.0:
            strength = geometric_pinch_strength(gap)
        value = min(max(strength - PINCH_THRESHOLD, 0.0), 0.8)
    return {'fist': fist, 'thumb_up': thumb_up, 'rock': rock, 'pinch': pinch, 'open': opn,
            'pinch_value': value, 'extended': (out, e1, e2, e3, e4)}


# -- circles ------------------------------------------------------------------------------
def fit_circle(pts):
    """Least-squares circle through 3-D points: the plane from their covariance, then an
    algebraic (Kasa) fit in it. (centre (3,), unit normal (3,), radius, rms radial
    residual, unwrapped angle of each point about the centre, right-handed about the
    normal) or None when degenerate."""
    p = np.array(pts, dtype=float)
    c = p.mean(axis=0)
    q = p - c
    _, vecs = np.linalg.eigh(q.T @ q)
    normal, u = vecs[:, 0], vecs[:, 2]
    v = vecs[:, 1]
    if (u[1] * v[2] - u[2] * v[1]) * normal[0] + (u[2] * v[0] - u[0] * v[2]) * normal[1] \
            + (u[0] * v[1] - u[1] * v[0]) * normal[2] < 0:
        v = -v                                  # u x v = normal
    x, y = q @ u, q @ v
    # x^2 + y^2 = 2 a x + 2 b y + k, normal equations (x, y are centred: sums are 0)
    zz = x * x + y * y
    sxx, sxy, syy = float(x @ x), float(x @ y), float(y @ y)
    det = sxx * syy - sxy * sxy
    if not det > 1e-12 * (sxx + syy) ** 2:
        return None
    bx, by = float(x @ zz), float(y @ zz)
    cx = 0.5 * (syy * bx - sxy * by) / det
    cy = 0.5 * (sxx * by - sxy * bx) / det
    r2 = float(zz.mean()) + cx * cx + cy * cy
    dx, dy = x - cx, y - cy
    radius = math.sqrt(r2)
    residual = float(np.sqrt(np.mean((np.sqrt(dx * dx + dy * dy) - radius) ** 2)))
    angles = np.arctan2(dy, dx)
    step = np.diff(angles)
    step -= 2 * math.pi * np.round(step / (2 * math.pi))
    angles = np.concatenate(([angles[0]], angles[0] + np.cumsum(step)))
    return c + cx * u + cy * v, normal, radius, residual, angles


class _CircleTrack:
    """One point's path (the palm or a fingertip); see the circles section above."""
    __slots__ = ('spacing2', 'r_min', 'r_max', 'spans', 'jump2', 'min_len', 'ts', 'pts',
                 'cross', 'length', 'speed', 'head', 'wait', 'v_max')

    def __init__(self, spacing, r_min, r_max, spans, v_max=math.inf):
        self.spacing2 = spacing * spacing
        self.r_min, self.r_max, self.spans = r_min, r_max, spans
        self.v_max = v_max
        self.jump2 = (25 * spacing + 2 * r_max) ** 2
        self.min_len = CIRCLE_ARC * r_min       # path length of the smallest circle
        self.reset()

    def reset(self):
        # Parallel lists from index `head` on: time, point, prefix sums of p[i-1] x p[i]
        # (twice the vector area swept about the origin) and of the path length.
        self.ts, self.pts, self.cross, self.length = [], [], [], []
        self.speed = []                         # mm/s of the step that reached each point
        self.head = 0
        self.wait = 0

    def clear(self):
        """Forget the path so far but keep the current point (after an event)."""
        last = self.pts[-1] if len(self.pts) > self.head else None
        t = self.ts[-1] if last is not None else 0.0
        self.reset()
        if last is not None:
            self._start(t, last)

    def _start(self, t, p):
        self.ts.append(t)
        self.pts.append(p)
        self.cross.append(_ZERO3)
        self.speed.append(0.0)
        self.length.append(0.0)

    def add(self, t, p):
        """Feed a point [x, y, z]; (axis unit vector, radius mm, centre) when a circle
        closed."""
        pts = self.pts
        if len(pts) <= self.head:
            self._start(t, p)
            return None
        ts = self.ts
        q = pts[-1]
        x, y, z = p
        qx, qy, qz = q
        sx, sy, sz = x - qx, y - qy, z - qz
        l2 = sx * sx + sy * sy + sz * sz
        if l2 < self.spacing2:
            return None
        if l2 > self.jump2 or not t >= ts[-1]:      # a jump: tracking glitch
            self.reset()
            self._start(t, p)
            return None
        cross, length = self.cross, self.length
        c = cross[-1]
        cn = (c[0] + qy * z - qz * y, c[1] + qz * x - qx * z, c[2] + qx * y - qy * x)
        step = math.sqrt(l2)
        ln = length[-1] + step
        cross.append(cn)
        length.append(ln)
        dt = t - ts[-1]
        self.speed.append(step / dt if dt > 0.0 else math.inf)
        ts.append(t)
        pts.append(p)
        spans = self.spans
        # drop what is older than the longest stretch; compact now and then
        head = self.head
        oldest = t - spans[-1]
        while ts[head] < oldest:
            head += 1
        if head > 256:
            del ts[:head], pts[:head], cross[:head], length[:head], self.speed[:head]
            head = 0
        self.head = head
        if self.wait > 0:
            self.wait -= 1
            return None
        n = len(ts) - 1
        min_len = self.min_len
        if ln - length[head] < min_len:
            return None
        best, best_j = CIRCLE_MIN_ROUNDNESS, -1
        last_j = -1
        for span in spans:
            j = bisect_left(ts, t - span, head, n)
            if j == last_j or n - j < CIRCLE_MIN_POINTS:
                continue
            last_j = j
            a = pts[j]
            ex, ey, ez = x - a[0], y - a[1], z - a[2]
            perimeter = ln - length[j] + math.sqrt(ex * ex + ey * ey + ez * ez)
            if perimeter < min_len:
                continue
            # twice the area closed by the chord p[n] -> p[j], which adds p[n] x p[j]
            cj = cross[j]
            ax = cn[0] - cj[0] + y * a[2] - z * a[1]
            ay = cn[1] - cj[1] + z * a[0] - x * a[2]
            az = cn[2] - cj[2] + x * a[1] - y * a[0]
            # 4 pi area / perimeter^2
            r = 2.0 * math.pi * math.sqrt(ax * ax + ay * ay + az * az) / (perimeter * perimeter)
            if r > best:
                best, best_j = r, j
        if best_j < 0:
            return None
        # (max() only here, past both gates: a few times per loop)
        if max(self.speed[best_j + 1:]) > self.v_max:
            self.wait = CIRCLE_RETRY_POINTS
            return None
        hit = self._fit(pts[best_j:])
        if hit is None:
            self.wait = CIRCLE_RETRY_POINTS
        return hit

    def _fit(self, pts):
        fit = fit_circle(pts)
        if fit is None:
            return None
        # Trim to the shortest tail that sweeps the arc about the fitted centre, refit.
        tail = np.flatnonzero(np.abs(fit[4][-1] - fit[4]) >= CIRCLE_ARC)
        if not len(tail) or len(pts) - int(tail[-1]) < CIRCLE_MIN_POINTS:
            return None
        fit = fit_circle(pts[int(tail[-1]):])
        if fit is None:
            return None
        centre, normal, radius, residual, angles = fit
        sweep = float(angles[-1] - angles[0])
        travel = float(np.sum(np.abs(np.diff(angles))))
        # (the refit on the trimmed tail may read the arc a little shorter: 10% slack)
        if (abs(sweep) < 0.9 * CIRCLE_ARC or travel > CIRCLE_MAX_TRAVEL * abs(sweep)
                or not self.r_min <= radius <= self.r_max
                or residual > CIRCLE_MAX_RESIDUAL * radius):
            return None
        # Every point near the circle, not just most: a half circle plus the straight way
        # out to it sweeps 270 deg about a centre between them with a modest rms residual.
        q = np.asarray(pts[int(tail[-1]):]) - centre
        q -= np.outer(q @ normal, normal)                   # in the circle's plane
        deviation = np.abs(np.sqrt(np.einsum('ij,ij->i', q, q)) - radius)
        if deviation.max() > CIRCLE_MAX_DEVIATION * radius:
            return None
        return (normal if sweep > 0 else -normal), radius, centre


_ZERO3 = (0.0, 0.0, 0.0)


class CircleDetector:
    """Circles traced by the palm or any fingertip of one hand: one event per circle (all
    tracks forget their path when one fires), at most one per CIRCLE_REFRACTORY_S.

    Direction: a fingertip circle is clockwise when it turns clockwise seen along the
    finger (the Leap SDK's convention: normal . pointable direction > 0); a palm circle
    is clockwise as the device sees it, looking up +y (the scripted source's `cw`)."""

    def __init__(self):
        palm, finger = CIRCLE_TRACKS
        self.tracks = [_CircleTrack(*palm[1:])] + [_CircleTrack(*finger[1:]) for _ in range(5)]
        self._last_event = -math.inf
        self._palm_smooth = None

    def reset(self):
        for tr in self.tracks:
            tr.reset()
        self._last_event = -math.inf
        self._palm_smooth = None

    def update(self, hand, timestamp, geometry):
        """GestureEvent or None, from the hand's HandGeometry (palm and tips)."""
        found = None
        tracks = self.tracks
        # Light smoothing: palm noise would otherwise scramble the turning at the palm
        # track's coarse spacing.
        x, y, z = geometry.palm
        sm = self._palm_smooth
        if sm is not None:
            a = PALM_SMOOTHING
            x, y, z = sm[0] + a * (x - sm[0]), sm[1] + a * (y - sm[1]), sm[2] + a * (z - sm[2])
        self._palm_smooth = sm = [x, y, z]
        hit = tracks[0].add(timestamp, sm)
        if hit is not None:
            found = (hit[0][1] > 0, hit[1], 'palm', hit[2])
        bend = geometry.bend
        for i, tip in enumerate(geometry.tips_world):
            if not _isfinite(tip[0] + tip[1] + tip[2]):
                continue
            hit = tracks[1 + i].add(timestamp, tip)
            if hit is None or found is not None:
                continue
            # Like the SDK's: a circle drawn with an extended finger (a curled one only
            # loops while folding), roughly across the finger's axis (a loop in the
            # plane the finger bends in is a tap or a fold, not a circle). The sense is
            # then the SDK's: clockwise when the normal points along the finger.
            if i > 0 and not bend[i] < EXTENDED_BEND[1]:
                continue
            axis = hit[0]
            ref = _f3(hand.fingers[i].direction)
            if ref is None or not _isfinite(ref[0] + ref[1] + ref[2]):
                ref = geometry.basis[2]
            along = float(axis[0] * ref[0] + axis[1] * ref[1] + axis[2] * ref[2])
            if abs(along) >= CIRCLE_MIN_ACROSS:
                found = (along > 0, hit[1], FINGER_NAMES[i], hit[2])
        if found is None:
            return None
        for tr in tracks:
            tr.clear()
        if timestamp - self._last_event < CIRCLE_REFRACTORY_S:
            return None
        self._last_event = timestamp
        cw, radius, source, centre = found
        return GestureEvent('circle_cw' if cw else 'circle_ccw', True, radius * 1e-3, source,
                            tuple(float(c) for c in centre))


# -- the recognizer -----------------------------------------------------------------------
class GestureRecognizer:
    """Stream recognizer for one hand (either side): geometry rules, temporal filter,
    events. update(hand, timestamp) -> GestureState; reset() when the hand leaves."""

    def __init__(self, stateless=False, on_frames=3, off_frames=3,
                 min_confidence=MIN_CONFIDENCE, circles=True, on_time=None):
        self.stateless = stateless
        self.on_time = {} if stateless else dict(ON_TIME_S if on_time is None else on_time)
        self.on_frames = 1 if stateless else max(1, int(on_frames))
        self.off_frames = 1 if stateless else max(1, int(off_frames))
        self.min_confidence = float(min_confidence)
        self.circles = CircleDetector() if circles and not stateless else None
        self.reset()

    def reset(self):
        self._active = set()
        self._count = {name: 0 for name in HELD_GESTURES}
        self._since = {name: 0.0 for name in HELD_GESTURES}
        self._bend_hist = deque(maxlen=64)
        self._last_shape = None
        self._prev = GestureState()
        self._last_confident = -math.inf
        if self.circles is not None:
            self.circles.reset()

    def update(self, hand, timestamp):
        try:
            timestamp = float(timestamp)
        except (TypeError, ValueError):
            timestamp = math.nan
        if not _isfinite(timestamp):
            timestamp = self._prev_time() + 0.01
        g = hand_geometry(hand)
        confidence = _num(hand.confidence, 1.0)
        usable = g is not None and confidence >= self.min_confidence
        stateless = self.stateless
        active = self._active
        events = []
        prev = self._prev
        if usable:
            self._last_confident = timestamp
            opening = False
            if not stateless:
                b = g.bend
                mean_bend = (b[1] + b[2] + b[3] + b[4]) * 0.25
                if _isfinite(mean_bend):
                    hist = self._bend_hist
                    while hist and not 0.0 <= timestamp - hist[0][0] <= OPENING_WINDOW_S:
                        hist.popleft()
                    hist.append((timestamp, mean_bend))
                    opening = max(b for _, b in hist) - mean_bend > OPENING_DEG
            raw = classify_geometry(g, hand, () if stateless else active, opening)
            if stateless:
                active = {n for n in HELD_GESTURES if raw[n]}
            else:
                count = self._count
                for name in HELD_GESTURES:
                    want = raw[name]
                    if want == (name in active):
                        count[name] = 0
                        continue
                    if count[name] == 0:
                        self._since[name] = timestamp
                    count[name] += 1
                    if want:
                        done = (count[name] >= self.on_frames and
                                timestamp - self._since[name] >= self.on_time.get(name, 0.0) - 1e-9)
                    else:
                        done = count[name] >= self.off_frames
                    if done:
                        count[name] = 0
                        if want:
                            active.add(name)
                        else:
                            active.discard(name)
            extended = raw['extended']
            pinch_value = raw['pinch_value']
            if 'pinch' in active and pinch_value == 0.0 and not raw['pinch']:
                pinch_value = prev.pinch_value      # held through the off-filter
        else:
            # Unusable frame: hold what we had for a moment, then let go.
            if stateless or timestamp - self._last_confident > HOLD_LOW_CONFIDENCE_S:
                active.clear()
            for name in HELD_GESTURES:
                self._count[name] = 0
            extended = prev.finger_extended
            pinch_value = prev.pinch_value
        self._active = active
        pinch = 'pinch' in active
        state = GestureState('fist' in active, 'thumb_up' in active, pinch,
                             min(max(float(pinch_value), 0.0), 0.8) if pinch else 0.0,
                             'rock' in active, 'open' in active, extended, events)
        if not stateless:
            if (state.fist != prev.fist or state.thumb_up != prev.thumb_up or pinch != prev.pinch
                    or state.rock != prev.rock or state.open != prev.open):
                for name in HELD_GESTURES:
                    now = getattr(state, name)
                    if now != getattr(prev, name):
                        events.append(GestureEvent(name, now,
                                                   state.pinch_value if name == 'pinch' else 0.0))
            shape = 'fist' if state.fist else 'open' if state.open else None
            if shape and shape != self._last_shape:
                if self._last_shape == 'fist' and shape == 'open':
                    events.append(GestureEvent('unfold'))
                elif self._last_shape == 'open' and shape == 'fist':
                    events.append(GestureEvent('fold'))
                self._last_shape = shape
            if self.circles is not None and usable:
                circle = self.circles.update(hand, timestamp, g)
                if circle is not None:
                    events.append(circle)
        self._prev = state
        self._prev_t = timestamp
        return state

    def _prev_time(self):
        return getattr(self, '_prev_t', 0.0)


__all__ = ['FINGER_NAMES', 'CircleDetector', 'GestureEvent', 'GestureRecognizer',
           'GestureState', 'HandGeometry', 'OriginalRules', 'PINCH_THRESHOLD',
           'classify_geometry', 'hand_geometry']
