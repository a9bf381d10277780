"""Circles traced by the palm or the index tip: per-track path buffers, a cheap roundness
gate, a least-squares circle fit that decides, and the per-hand detector (one event per
circle, with its sense, radius, centre and what traced it)."""
import math
from bisect import bisect_left
from collections import deque
from dataclasses import dataclass

import numpy as np

from leap_teleop.hands.gestures.geometry import f3 as _f3
from leap_teleop.hands.gestures.temporal import HandEvent

_isfinite = math.isfinite
_sum = np.add.reduce

# Each track (the smoothed palm, the index tip) keeps its recent path, resampled at a
# small spacing (drops jitter while still). Cheap gate, per new point, for a few recent
# stretches of the path: how round the stretch is, closed by its chord (isoperimetric
# quotient 4 pi area / length^2: 1 for a circle, ~0.96 for a 270 deg arc, ~0.75 for a
# half circle, ~0 for straight or back-and-forth moves; prefix sums make it O(1)). The
# roundest stretch past the gate is fitted with a circle (plane + least squares), which
# decides: an arc of >= rules.arc about the fitted centre, swept one way, close to it.
# Which tracks: the palm, and the index tip while pointing (middle and ring folded).
# Thumb, pinky and ring tips loop by themselves while hands clap, flap, tap or
# turn a knob (4-20 mm loops; the SDK called some of them circles); so do the fingertips
# of an open hand that moves or turns.


@dataclass(frozen=True)
class CircleRules:
    """The few numbers fitted on people's drawn circles (tools/evaluation/strokes.py);
    the defaults are the rules before that fit (its starting point), DRAWN the fit."""
    r_max: float = 300.0         # mm, largest circle radius (both tracks)
    max_s: float = 1.6           # s, the longest stretch of path looked at for a circle
    arc: float = 1.5 * math.pi   # rad swept about the fitted centre
    min_roundness: float = 0.6   # isoperimetric quotient that triggers a fit
    tip_v_max: float = 1000.0    # mm/s, index tip: faster within the loop is a swipe
    # |circle normal . finger direction| of an index circle, at least: a loop in the
    # plane the finger bends in is a tap or a fold (default: cos 45 deg, the SDK's own
    # circles on the recordings, 0.71..0.98 in 18 of 20)
    min_across: float = 0.7


# The rules read only on the index tip's path (while index_draws): a replay without
# pointing frames does not depend on them.
TIP_RULES = ('tip_v_max', 'min_across')


# Fitted (tools.evaluation.strokes.CircleFit, `python -m tools.evaluation.strokes
# --loso` prints them) on the 7 development people's strokes (GestureMidAir: circles
# 120-260 mm across, one loop in 1.7-2.5 s), drawn by translated real pointing and open
# hands (GTI-UPM), with no circle event allowed on the Guinevere and LeapJS takes; each
# value the middle of its grid range that recognizes the most circles and fires on no
# loop-free stroke (ties: fewest closed angular shapes). A translated hand's palm draws
# the same circle as its index, so the index's own two rules (tip_v_max, min_across)
# sit mid-grid: these people's strokes do not bound them.
DRAWN = CircleRules(
    r_max=200.0,            # mm; the people's circles fit 64..119 mm
    max_s=2.5,              # s; 1.6 misses the slowest (~2 s to 290 deg)
    arc=1.625 * math.pi,    # 292.5 deg; 342 deg misses a loop closed short
    min_roundness=0.6,      # the gate only: the fit and the corner test decide
    tip_v_max=2000.0,       # mm/s; drawn circles peak at 0.5..1.9 m/s
    min_across=0.6)         # within 53 deg of across the finger (a tap loops along it)
# Smallest radius, mm, both tracks; not fitted (people's circles are all far larger):
# the drone's flip_min_radius, the smallest circle anything acts on. Smaller loops are
# what fingertips make by themselves, and what the cusp of a curly bracket drawn 1.5x
# its size made (12 mm; the scripted demo's palm circle is 35 mm).
CIRCLE_R_MIN = 25.0
PALM_SPACING = 2.0                 # mm, path resampling (the palm is noisier)
TIP_SPACING = 1.0
# Stretches looked at, as fractions of rules.max_s. Steps of a tenth: with fifths, a loop
# that just closes within one stretch was lost to a 20-100 ms pause of the input.
SPAN_FRACTIONS = (0.25, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0)
# A hand that rolls or pitches swings its fingertips round loops with the fingers still:
# a drawn fingertip circle keeps the palm facing one way (largest angle between palm
# normals over the track's longest stretch).
CIRCLE_MAX_PALM_TURN_DEG = 30.0
CIRCLE_MIN_POINTS = 8
CIRCLE_MAX_TRAVEL = 1.3            # angular travel / net sweep: more is back and forth
CIRCLE_MAX_RESIDUAL = 0.35         # rms radial residual / radius
CIRCLE_MAX_DEVIATION = 0.6         # largest radial deviation / radius
CIRCLE_MAX_CORNER = 2.5            # most turning in an eighth of the path / an even share
CIRCLE_RETRY_POINTS = 1            # after a failed fit, new points before the next one
PALM_SMOOTHING = 0.35              # exponential smoothing factor of the palm path
CIRCLE_REFRACTORY_S = 0.25         # one event per circle even when the hand changes track


def index_draws(extended):
    """Whether the index tip's path is followed, from the 5 extended flags: index out,
    middle and ring folded (an open hand that moves or turns carries every fingertip
    round loops nobody drew)."""
    return extended[1] and not (extended[2] or extended[3])


def fit_circle(pts):
    """Least-squares circle through 3-D points: the plane from their covariance, then an
    algebraic (Kasa) fit in it. (centre (3,), unit normal (3,), radius, rms radial
    residual, unwrapped angle of each point about the centre, right-handed about the
    normal) or None when degenerate."""
    fit = _plane_circle(pts)
    if fit is None:
        return None
    c, normal, u, v, cx, cy, radius, dx, dy = fit
    off = np.sqrt(dx * dx + dy * dy) - radius
    residual = math.sqrt(float(_sum(off * off)) / len(dx))
    return c + cx * u + cy * v, normal, radius, residual, _unwrapped_angles(dx, dy)


def _plane_circle(pts):
    """fit_circle's plane and circle in it: (mean point, normal, in-plane axes u, v, the
    centre's u and v coordinates from the mean point, radius, each point's u and v
    offsets from the centre), or None when degenerate."""
    # (np.add.reduce(.) / n: what mean() computes, without its wrapper's cost)
    p = np.asarray(pts, dtype=float)
    n = len(p)
    c = _sum(p, 0) / n
    q = p - c
    _, vecs = np.linalg.eigh(q.T @ q)
    normal, u = vecs[:, 0], vecs[:, 2]
    v = vecs[:, 1]
    (n0, v0, u0), (n1, v1, u1), (n2, v2, u2) = vecs.tolist()
    if (u1 * v2 - u2 * v1) * n0 + (u2 * v0 - u0 * v2) * n1 + (u0 * v1 - u1 * v0) * n2 < 0:
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
    r2 = float(_sum(zz)) / n + cx * cx + cy * cy
    return c, normal, u, v, cx, cy, math.sqrt(r2), x - cx, y - cy


def _unwrapped_angles(dx, dy):
    """The angle of each offset (dx, dy), unwrapped along the path."""
    angles = np.arctan2(dy, dx)
    step = angles[1:] - angles[:-1]
    step -= 2 * math.pi * np.round(step / (2 * math.pi))
    return np.concatenate(([angles[0]], angles[0] + np.cumsum(step)))


class _CircleTrack:
    """One point's path (the palm or a fingertip); see the circles section above."""
    __slots__ = ('spacing2', 'r_min', 'r_max', 'spans', 'jump2', 'min_len', 'ts', 'pts',
                 'cross', 'length', 'speed', 'head', 'wait', 'v_max', 'arc', 'min_roundness',
                 'fits')

    def __init__(self, spacing, r_min, rules, v_max=math.inf, fits=None):
        self.spacing2 = spacing * spacing
        self.r_min, self.r_max = r_min, rules.r_max
        self.spans = tuple(f * rules.max_s for f in SPAN_FRACTIONS)
        self.arc, self.min_roundness = rules.arc, rules.min_roundness
        self.v_max = v_max
        self.jump2 = (25 * spacing + 2 * self.r_max) ** 2
        self.min_len = self.arc * r_min         # path length of the smallest circle
        self.fits = _FITS if fits is None else fits
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
        best, best_j = self.min_roundness, -1
        last_j = -1
        for span in spans:
            if last_j == head:
                break                           # the longer stretches start there too
            j = bisect_left(ts, t - span, head, n)
            if j == last_j or n - j < CIRCLE_MIN_POINTS:
                if j == head:
                    break
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
        hit = track_circle(np.array(pts[best_j:], dtype=float), self.arc, self.r_min, self.r_max,
                           self.fits)
        if hit is None:
            self.wait = CIRCLE_RETRY_POINTS
        return hit


def track_circle(p, arc, r_min, r_max, fits):
    """(axis, radius mm, centre) of the circle a track's roundest stretch ((n, 3) array)
    closes, or None: trimmed to the shortest tail that sweeps `arc` about the fitted
    centre, refitted (`fits`: a CircleFits)."""
    start = fits.arc_start(p, arc)
    if start is None:
        return None
    hit = fits.tail_circle(p[start:])
    if hit is None:
        return None
    axis, radius, centre, sweep = hit
    # (the refit on the trimmed tail may read the arc a little shorter: 10% slack)
    if abs(sweep) < 0.9 * arc or not r_min <= radius <= r_max:
        return None
    return axis, radius, centre


class CircleFits:
    """The two fits that decide a track's circle, on its roundest stretch ((n, 3) array):
    where the shortest tail sweeping the arc starts, and that tail's circle. They read
    the points and the arc only, not the rules' other numbers or the track's state, so
    a caller replaying many rules over the same paths may cache them (a subclass: the
    fits are `sweeps` and `tail_circle`)."""

    def arc_start(self, p, arc):
        """Index of the shortest tail of `p` (at least CIRCLE_MIN_POINTS) that sweeps
        `arc` about the circle fitted to all of `p`; None without one."""
        sweeps = self.sweeps(p)
        if sweeps is None:
            return None
        tail = np.flatnonzero(sweeps >= arc)
        if not len(tail) or len(p) - int(tail[-1]) < CIRCLE_MIN_POINTS:
            return None
        return int(tail[-1])

    def sweeps(self, p):
        """The angle (rad, >= 0) the path sweeps from each point of `p` to its last one,
        about the circle fitted to all of `p`; None when degenerate."""
        fit = _plane_circle(p)                 # (its angles only)
        if fit is None:
            return None
        angles = _unwrapped_angles(fit[7], fit[8])
        return np.abs(angles[-1] - angles)

    def tail_circle(self, p):
        """(axis: the unit normal the path turns right-handed about, radius, centre, signed
        sweep rad) of the circle fitted to `p` when the path goes round it one way and
        stays close to it all along; else None."""
        fit = fit_circle(p)
        if fit is None:
            return None
        centre, normal, radius, residual, angles = fit
        sweep = float(angles[-1] - angles[0])
        travel = float(np.sum(np.abs(np.diff(angles))))
        if travel > CIRCLE_MAX_TRAVEL * abs(sweep) or residual > CIRCLE_MAX_RESIDUAL * radius:
            return None
        # Every point near the circle, not just most: a half circle plus the straight way
        # out to it sweeps 270 deg about a centre between them with a modest rms residual.
        q = p - centre
        q -= np.outer(q @ normal, normal)                   # in the circle's plane
        deviation = np.abs(np.sqrt(np.einsum('ij,ij->i', q, q)) - radius)
        if deviation.max() > CIRCLE_MAX_DEVIATION * radius:
            return None
        # Turning spread along the path, not gathered at corners: straight moves joined
        # by turns (a hand moved between places; a rectangle, star or x drawn with the
        # index) also close a round-enough loop.
        if _cornered(q, normal):
            return None
        return (normal if sweep > 0 else -normal), radius, centre, sweep


def _cornered(q, normal):
    """Whether a path (points in the circle's plane, about its centre) turns at corners:
    the most its heading turns within an eighth of the path exceeds CIRCLE_MAX_CORNER
    times an even turning's share."""
    if len(q) < 24:
        return False
    # Averaged over a twelfth of the path, 24 points round: headings above the jitter.
    w = len(q) // 12
    c = np.cumsum(np.vstack([np.zeros((1, 3)), q]), axis=0)
    q = (c[w:] - c[:-w]) / w
    q = q[np.linspace(0, len(q) - 1, 25).astype(int)]
    step = np.diff(q, axis=0)
    head = np.arctan2(np.cross(step[:-1], step[1:]) @ normal,
                      np.einsum('ij,ij->i', step[:-1], step[1:]))
    total = abs(float(head.sum()))
    m = max(2, len(head) // 8)
    window = np.abs(np.convolve(head, np.ones(m), 'valid'))
    return float(window.max()) > CIRCLE_MAX_CORNER * total * m / len(head)


def index_circle_cw(axis, hand, geometry, normals, min_across):
    """Whether the index tip's circle about `axis` turns clockwise (True / False), or None
    when it is no circle: drawn along the finger, or the palm turned meanwhile (`normals`:
    (time, palm normal) over the stretch)."""
    # Like the SDK's: a circle drawn roughly across the finger's axis (a loop in the
    # plane the finger bends in is a tap or a fold, not a circle). The sense is then
    # the SDK's: clockwise when the normal points along the finger.
    ref = _f3(hand.fingers[1].direction)
    if ref is None or not _isfinite(ref[0] + ref[1] + ref[2]):
        ref = geometry.basis[2]
    along = float(axis[0] * ref[0] + axis[1] * ref[1] + axis[2] * ref[2])
    if abs(along) < min_across or _palm_turned(normals):
        return None
    return along > 0


def _palm_turned(normals):
    """Whether the palm normal turned more than CIRCLE_MAX_PALM_TURN_DEG over the
    (time, normal) pairs (compared with their mean direction, half the pairwise angle)."""
    ns = np.array([n for _, n in normals])
    if len(ns) < 2:
        return False
    mean = ns.sum(axis=0)
    norm = float(np.linalg.norm(mean))
    if norm == 0.0:
        return True
    half = math.cos(math.radians(CIRCLE_MAX_PALM_TURN_DEG / 2.0))
    return float((ns @ (mean / norm)).min()) < half


_ZERO3 = (0.0, 0.0, 0.0)
_FITS = CircleFits()


class CircleDetector:
    """Circles of one hand: traced by the palm, or by the index tip while pointing; one
    event per circle (both paths are forgotten when one fires), at most one per
    CIRCLE_REFRACTORY_S. `rules`: a CircleRules (default DRAWN); `fits`: the CircleFits
    that fit the circles (default: one that computes each).

    Direction: a fingertip circle is clockwise when it turns clockwise seen along the
    finger (the Leap SDK's convention: normal . pointable direction > 0); a palm circle
    is clockwise as the device sees it, looking up +y (the scripted source's `cw`)."""

    def __init__(self, rules=None, fits=None):
        rules = DRAWN if rules is None else rules
        self.rules = rules
        self.palm_track = _CircleTrack(PALM_SPACING, CIRCLE_R_MIN, rules, fits=fits)
        self.tip_track = _CircleTrack(TIP_SPACING, CIRCLE_R_MIN, rules, rules.tip_v_max, fits)
        self._normals = deque()                 # (t, palm normal) over the tip's stretch
        self._normal_span = rules.max_s
        self._tip_v_max = rules.tip_v_max
        self._min_across = rules.min_across
        self.reset()

    def reset(self):
        self._last_event = -math.inf
        self._t = None                          # the last frame's stamp
        self._forget_palm()
        self._forget_tip()

    def _forget_palm(self):
        self._palm_smooth = None
        if len(self.palm_track.pts) > self.palm_track.head:
            self.palm_track.reset()

    def _forget_tip(self):
        self._tip_smooth = None
        self._tip_prev = None
        self._tip_fast_at = -math.inf
        self._normals.clear()
        if len(self.tip_track.pts) > self.tip_track.head:
            self.tip_track.reset()

    def _palm(self, timestamp, geometry):
        # Light smoothing: palm noise would otherwise scramble the turning at the palm
        # track's coarse spacing.
        x, y, z = geometry.palm
        sm = self._palm_smooth
        if sm is not None:
            a = PALM_SMOOTHING
            x, y, z = sm[0] + a * (x - sm[0]), sm[1] + a * (y - sm[1]), sm[2] + a * (z - sm[2])
        self._palm_smooth = sm = [x, y, z]
        hit = self.palm_track.add(timestamp, sm)
        if hit is None:
            return None
        return hit[0][1] > 0, hit[1], 'palm', hit[2]

    def _tip(self, hand, timestamp, geometry):
        normals = self._normals
        normals.append((timestamp, geometry.basis[1]))
        while normals[0][0] < timestamp - self._normal_span:
            normals.popleft()
        tip = geometry.tips_world[1]
        if not _isfinite(tip[0] + tip[1] + tip[2]):
            return None
        # Swipe speed is judged on the raw tip (smoothing rounds a fast stroke off).
        prev = self._tip_prev
        self._tip_prev = (timestamp, tip)
        if prev is not None and timestamp > prev[0]:
            pt = prev[1]
            d2 = (tip[0] - pt[0]) ** 2 + (tip[1] - pt[1]) ** 2 + (tip[2] - pt[2]) ** 2
            reach = self._tip_v_max * (timestamp - prev[0])      # (`**` raises on overflow)
            if d2 > reach * reach:
                self._tip_fast_at = timestamp
        # Smoothed like the palm: frame-to-frame jitter of a few mm zig-zags a small
        # circle's path and reads it as not round.
        sm = self._tip_smooth
        if sm is not None:
            a = PALM_SMOOTHING
            tip = [sm[0] + a * (tip[0] - sm[0]), sm[1] + a * (tip[1] - sm[1]),
                   sm[2] + a * (tip[2] - sm[2])]
        self._tip_smooth = tip
        hit = self.tip_track.add(timestamp, tip)
        if hit is None or timestamp - self._tip_fast_at < self._normal_span:
            return None                         # (or swiped within the stretch)
        cw = index_circle_cw(hit[0], hand, geometry, normals, self._min_across)
        if cw is None:
            return None
        return cw, hit[1], 'index', hit[2]

    def update(self, hand, timestamp, geometry, extended):
        """HandEvent or None, from the hand's HandGeometry (palm and tips) and the
        pose rules' extended verdict per finger."""
        # The palm always (a whole hand going round; a pointing hand's palm follows its
        # finger, and keeps its circle when the pose reads a frame or two as not
        # pointing: 3 % of such frames lost 6 of the 7 people's circles without it);
        # the index tip while pointing (index_draws).
        if self._t is not None and not 0.0 <= timestamp - self._t <= self._normal_span:
            # A pause longer than any circle, or a stamp going back: start again (no path,
            # smoothing or speed spans it).
            self.reset()
        self._t = timestamp
        found = self._palm(timestamp, geometry)
        if index_draws(extended):
            tip = self._tip(hand, timestamp, geometry)
            if found is None:
                found = tip
        else:
            self._forget_tip()
        if found is None:
            return None
        self.palm_track.clear()
        self.tip_track.clear()
        if timestamp - self._last_event < CIRCLE_REFRACTORY_S:
            return None
        self._last_event = timestamp
        cw, radius, source, centre = found
        return HandEvent('circle_cw' if cw else 'circle_ccw', True, radius * 1e-3, source,
                            tuple(float(c) for c in centre))
