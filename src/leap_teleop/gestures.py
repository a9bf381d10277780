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
from collections import deque
from dataclasses import dataclass, field
from typing import List, Tuple

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
# Paths are resampled at a minimum spacing (drops jitter while still), then the turning
# of successive segments is summed as a rotation vector; a circle is one full turn about
# a consistent axis within the time window. (track name, spacing mm, min radius mm,
# max radius mm, window s)
CIRCLE_TRACKS = (('palm', 6.0, 25.0, 300.0, 2.0), ('finger', 4.0, 3.0, 60.0, 1.0))
CIRCLE_TURN = 2 * math.pi * 0.9    # rad of consistent turning that makes a circle
CIRCLE_MAX_STEP_TURN = math.radians(100.0)   # a sharper corner is a reversal, not a circle
CIRCLE_CONSISTENCY = 0.6           # |sum of turn vectors| / sum of |turns|
PALM_SMOOTHING = 0.35             # exponential smoothing factor of the palm path
_UP = np.array([0.0, 1.0, 0.0])
CIRCLE_REFRACTORY_S = 0.25         # one event per circle even when several fingers trace it


@dataclass
class GestureEvent:
    gesture: str
    active: bool = True
    value: float = 0.0


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
@dataclass
class HandGeometry:
    """What the rules look at, in the hand frame. NaN where the frame lacks the data."""
    bend: np.ndarray            # (5,) degrees; [0] is the thumb's (unused by the rules)
    thumb_out: float            # mm, thumb tip's thumbward offset from the palm centre
    pinch_gap: float            # mm, thumb tip to index tip
    tips_local: np.ndarray      # (5, 3) mm, fingertips in the hand frame
    tips_world: np.ndarray      # (5, 3) mm, fingertips in Leap axes
    basis: np.ndarray           # (3, 3) rows: thumbward, normal, direction (Leap axes)


def _unit_rows(a):
    n = np.sqrt(np.einsum('ij,ij->i', a, a))
    with np.errstate(invalid='ignore', divide='ignore'):
        return a / n[:, None]


def hand_geometry(hand):
    """HandGeometry of a Hand, or None when its palm frame is unusable (non-finite or
    degenerate normal / direction, missing fingers)."""
    fingers = hand.fingers
    if len(fingers) != 5:
        return None
    try:
        pts = np.array([[f.tip, f.direction,
                         f.dip if f.dip is not None else f.tip,
                         f.pip if f.pip is not None else _NAN3,
                         f.mcp if f.mcp is not None else _NAN3] for f in fingers], dtype=float)
        head = np.array([hand.palm_position, hand.palm_normal, hand.direction], dtype=float)
    except (TypeError, ValueError):
        return None
    if pts.shape != (5, 5, 3) or head.shape != (3, 3) or not np.all(np.isfinite(head)):
        return None
    palm, n, d = head
    nn = math.sqrt(n @ n)
    if nn < 1e-6:
        return None
    n = n / nn
    d = d - n * (d @ n)
    dn = math.sqrt(d @ d)
    if dn < 1e-6:
        return None
    d = d / dn
    x = np.array([d[1] * n[2] - d[2] * n[1], d[2] * n[0] - d[0] * n[2], d[0] * n[1] - d[1] * n[0]])
    if hand.side == 'left':
        x = -x
    basis = np.stack([x, n, d])
    with np.errstate(invalid='ignore', divide='ignore', over='ignore'):
        tips_local = (pts[:, 0] - palm) @ basis.T
        # The distal bone (dip -> tip); the SDK's finger direction when joints are absent
        # (it follows the middle bone on real captures, so it is the second choice).
        distal = pts[:, 0] - pts[:, 2]
        bad = ~np.all(np.isfinite(distal), axis=1) | (np.einsum('ij,ij->i', distal, distal) < 1e-6)
        if bad.any():
            distal[bad] = pts[bad, 1]
        distal = _unit_rows(distal)
        proximal = _unit_rows(pts[:, 3] - pts[:, 4])
        flex = np.degrees(np.arccos(np.clip(distal @ d, -1.0, 1.0)))
        curl = np.degrees(np.arccos(np.clip(np.einsum('ij,ij->i', proximal, distal), -1.0, 1.0)))
        bend = np.where(np.isfinite(curl), np.fmax(flex, curl), flex)
        gap_v = pts[0, 0] - pts[1, 0]
        gap = math.sqrt(gap_v @ gap_v)
    return HandGeometry(bend=bend, thumb_out=float(tips_local[0, 0]), pinch_gap=gap,
                        tips_local=tips_local, tips_world=pts[:, 0], basis=basis)


_NAN3 = np.full(3, math.nan)


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
    bend = g.bend[1:]
    known = np.isfinite(bend)
    # Each of fist / thumbs-up keeps its own hysteresis: leaving a fist through a brief
    # thumb-out phase must not count as a thumbs-up that is already on.
    all_curled = {name: bool(known.all() and np.all(bend > th[1 if name in active else 0]))
                  for name, th in (('fist', CURLED_BEND), ('thumb_up', THUMB_UP_CURLED_BEND))}
    k_open = 1 if ('open' in active or 'rock' in active) else 0
    extended = known & (bend < EXTENDED_BEND[k_open])
    thumb_out = g.thumb_out
    thumb_known = math.isfinite(thumb_out)
    k_thumb = 1 if ('thumb_up' in active or 'open' in active) else 0
    out = thumb_known and thumb_out > THUMB_OUT_MM[k_thumb]
    r = {}
    r['fist'] = all_curled['fist'] and not out
    r['thumb_up'] = all_curled['thumb_up'] and out and ('thumb_up' in active or not opening)
    # Rock: index and pinky out, middle and ring curled (looser bar for the curl: a
    # horns hand rarely folds middle and ring as deep as a fist).
    r['rock'] = bool(extended[0] and extended[3] and known[1] and known[2]
                     and bend[1] > CURLED_BEND[1] and bend[2] > CURLED_BEND[1])
    gap = g.pinch_gap
    others = bend[1:]
    pinch = (math.isfinite(gap) and gap < PINCH_GAP_MM[1 if 'pinch' in active else 0]
             and not r['fist'] and not r['thumb_up']
             and bool(np.all(np.isfinite(others)))
             and (not math.isfinite(bend[0]) or bend[0] > float(np.min(others)) + PINCH_BEND_MARGIN
                  or not bool(np.all(others > CURLED_BEND[1]))))
    r['pinch'] = bool(pinch)
    # Open: four fingers straight, thumb either way (a flat hand tucks it), not pinching.
    r['open'] = bool(extended.all()) and not pinch
    strength = _num(hand.pinch_strength, -1.0)
    if not 0.0 <= strength <= 1.0:
        strength = geometric_pinch_strength(gap)
    r['pinch_value'] = min(max(strength - PINCH_THRESHOLD, 0.0), 0.8) if pinch else 0.0
    r['extended'] = (bool(out),) + tuple(bool(e) for e in extended)
    return r


# -- circles ------------------------------------------------------------------------------
class _CircleTrack:
    """One point's path (the palm or a fingertip): resampled, turning accumulated."""
    __slots__ = ('spacing', 'r_min', 'r_max', 'window', 'last', 'seg', 'steps', 'turn',
                 'abs_turn', 'length')

    def __init__(self, spacing, r_min, r_max, window):
        self.spacing, self.r_min, self.r_max, self.window = spacing, r_min, r_max, window
        self.reset()

    def reset(self):
        self.last = None          # last accepted point (x, y, z)
        self.seg = None           # last segment vector
        self.steps = deque()      # (t, turn vector, |turn|, segment length)
        self.turn = [0.0, 0.0, 0.0]
        self.abs_turn = 0.0
        self.length = 0.0

    def _clear(self):
        self.steps.clear()
        self.turn = [0.0, 0.0, 0.0]
        self.abs_turn = self.length = 0.0

    def add(self, t, p):
        """Feed a point (3 floats); (axis unit vector, radius mm) when a circle closed.
        Plain floats: numpy's per-call overhead dominates on 3-vectors."""
        if self.last is None:
            self.last = p
            return None
        lx, ly, lz = self.last
        sx, sy, sz = p[0] - lx, p[1] - ly, p[2] - lz
        length = math.sqrt(sx * sx + sy * sy + sz * sz)
        if length < self.spacing:
            return None
        if length > 25 * self.spacing + 2 * self.r_max:   # a jump: tracking glitch
            self.reset()
            self.last = p
            return None
        self.last = p
        prev, self.seg = self.seg, (sx, sy, sz)
        if prev is None:
            return None
        px, py, pz = prev
        cx, cy, cz = py * sz - pz * sy, pz * sx - px * sz, px * sy - py * sx
        cn = math.sqrt(cx * cx + cy * cy + cz * cz)
        angle = math.atan2(cn, px * sx + py * sy + pz * sz)
        if angle > CIRCLE_MAX_STEP_TURN:
            self._clear()
            return None
        k = angle / cn if cn > 0 else 0.0
        v = (cx * k, cy * k, cz * k)
        steps = self.steps
        steps.append((t, v, angle, length))
        turn = self.turn
        turn[0] += v[0]
        turn[1] += v[1]
        turn[2] += v[2]
        self.abs_turn += angle
        self.length += length
        while steps and (t - steps[0][0] > self.window or t < steps[0][0]):
            _, ov, oa, ol = steps.popleft()
            turn[0] -= ov[0]
            turn[1] -= ov[1]
            turn[2] -= ov[2]
            self.abs_turn -= oa
            self.length -= ol
        total = math.sqrt(turn[0] ** 2 + turn[1] ** 2 + turn[2] ** 2)
        if total < CIRCLE_TURN or total < CIRCLE_CONSISTENCY * self.abs_turn:
            return None
        radius = self.length / total
        axis = np.array(turn) / total
        self._clear()
        if not self.r_min <= radius <= self.r_max:
            return None
        return axis, radius


class CircleDetector:
    """Circles traced by the palm or any fingertip of one hand.

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

    def update(self, hand, timestamp, geometry=None):
        """GestureEvent or None."""
        found = None
        palm = np.asarray(hand.palm_position, dtype=float)
        if palm.shape == (3,) and np.all(np.isfinite(palm)):
            # Light smoothing: palm noise would otherwise scramble the turning at the
            # palm track's coarse spacing.
            sm = self._palm_smooth
            sm = palm if sm is None else sm + PALM_SMOOTHING * (palm - sm)
            self._palm_smooth = sm
            hit = self.tracks[0].add(timestamp, sm.tolist())
            if hit is not None:
                found = (hit[0] @ _UP > 0, hit[1])
        if geometry is not None:
            tips = geometry.tips_world
            ok = np.isfinite(tips).all(axis=1).tolist()
            tips = tips.tolist()
            for i, f in enumerate(hand.fingers[:5]):
                if not ok[i]:
                    continue
                hit = self.tracks[1 + i].add(timestamp, tips[i])
                if hit is not None and found is None:
                    ref = np.asarray(f.direction, dtype=float)
                    if ref.shape != (3,) or not np.all(np.isfinite(ref)):
                        ref = geometry.basis[2]
                    along = float(hit[0] @ ref)
                    # A circle drawn across the finger's axis has no SDK sense: fall back
                    # on the palm convention.
                    found = ((along > 0) if abs(along) >= 0.5 else (hit[0] @ _UP > 0), hit[1])
        if found is None or timestamp - self._last_event < CIRCLE_REFRACTORY_S:
            return None
        self._last_event = timestamp
        cw, radius = found
        return GestureEvent('circle_cw' if cw else 'circle_ccw', True, radius * 1e-3)


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
        if not math.isfinite(timestamp):
            timestamp = self._prev_time() + 0.01
        g = hand_geometry(hand)
        confidence = _num(hand.confidence, 1.0)
        usable = g is not None and confidence >= self.min_confidence
        events = []
        prev = self._prev
        if usable:
            self._last_confident = timestamp
            opening = False
            if not self.stateless:
                bends = g.bend[1:]
                if np.all(np.isfinite(bends)):
                    mean_bend = float(bends.mean())
                    hist = self._bend_hist
                    while hist and not 0.0 <= timestamp - hist[0][0] <= OPENING_WINDOW_S:
                        hist.popleft()
                    hist.append((timestamp, mean_bend))
                    opening = max(b for _, b in hist) - mean_bend > OPENING_DEG
            raw = classify_geometry(g, hand, () if self.stateless else self._active, opening)
            for name in HELD_GESTURES:
                if raw[name] == (name in self._active):
                    self._count[name] = 0
                    continue
                if self._count[name] == 0:
                    self._since[name] = timestamp
                self._count[name] += 1
                if name in self._active:
                    done = self._count[name] >= self.off_frames
                else:
                    done = (self._count[name] >= self.on_frames and
                            timestamp - self._since[name] >= self.on_time.get(name, 0.0) - 1e-9)
                if done:
                    self._count[name] = 0
                    if raw[name]:
                        self._active.add(name)
                    else:
                        self._active.discard(name)
            extended = raw['extended']
            pinch_value = raw['pinch_value']
            if 'pinch' in self._active and pinch_value == 0.0 and not raw['pinch']:
                pinch_value = prev.pinch_value      # held through the off-filter
        else:
            # Unusable frame: hold what we had for a moment, then let go.
            if timestamp - self._last_confident > HOLD_LOW_CONFIDENCE_S:
                self._active.clear()
            for name in HELD_GESTURES:
                self._count[name] = 0
            extended = prev.finger_extended
            pinch_value = prev.pinch_value
        if self.stateless:
            self._active = {n for n in HELD_GESTURES if usable and raw[n]}
        state = GestureState(finger_extended=tuple(extended), events=events,
                             **{n: n in self._active for n in HELD_GESTURES})
        state.pinch_value = min(max(float(pinch_value), 0.0), 0.8) if state.pinch else 0.0
        if not self.stateless:
            for name in HELD_GESTURES:
                now = getattr(state, name)
                if now != getattr(prev, name):
                    events.append(GestureEvent(name, now,
                                               state.pinch_value if name == 'pinch' else 0.0))
        shape = 'fist' if state.fist else 'open' if state.open else None
        if shape and shape != self._last_shape and not self.stateless:
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
