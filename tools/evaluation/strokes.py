"""Circles drawn in the air by real people: which strokes fire a circle (the drone's flip).

usage: python -m tools.evaluation.strokes [--strokes DIR] [--leap-people DIR]
           [--leapjs DIR] [--loso] [--json FILE]

The strokes folder holds index-fingertip paths of 7 people drawing 26 symbols (one
`circle`, loop-free strokes, strokes that hold loops, closed angular shapes). A person
drawing moves the whole hand with the finger, so a real hand of another person (from
leap_people/gti_dev.jsonl.gz) is translated so that its index tip follows each path,
stamped with the path's times, and fed to a fresh GestureRecognizer (stream mode): once
as a pointing hand (label `index`: the index tip draws) and once as an open hand (label
`five`: the whole hand draws). Stroke person k (in name order) moves the hands of GTI
person k + 1, so every person's strokes are drawn with a different real hand.

Reported per symbol and per person, for each hand: circles recognized (a circle event
while drawing the `circle`), loop-free strokes that fire one (the goal: none), closed
angular shapes and looped strokes that fire one (reported). Beside them: circle events
on the Guinevere dynamic takes (leap_people/guinevere) and on the shared LeapJS takes,
none of which draws a circle.

--loso: the circle rules refitted leave-one-person-out (CircleFit): for each person,
the rules are chosen on the other six and scored on that person.
"""
import argparse
import dataclasses
import functools
import gc
import glob
import gzip
import hashlib
import json
import math
import os
import sys
from bisect import bisect_left, bisect_right

import numpy as np

from leap_teleop.hands.frame import Finger
from leap_teleop.hands.gestures import CircleDetector, GestureRecognizer, datasets
from leap_teleop.hands.gestures.circles import (
    CIRCLE_MIN_POINTS,
    CIRCLE_R_MIN,
    CIRCLE_REFRACTORY_S,
    CIRCLE_RETRY_POINTS,
    DRAWN,
    PALM_SMOOTHING,
    PALM_SPACING,
    SPAN_FRACTIONS,
    TIP_RULES,
    TIP_SPACING,
    CircleFits,
    CircleRules,
    index_circle_cw,
    index_draws,
    track_circle,
)
from leap_teleop.hands.gestures.datasets import SHARED_DATA, DataError
from leap_teleop.hands.gestures.temporal import HandEvent
from leap_teleop.hands.sources import leapjs
from tools.evaluation.results_file import write_json
from tools.evaluation.take_stream import EVERY_TAKE, recognize_take

STROKES_DATA = os.environ.get('STROKES_DATA') or os.path.join(SHARED_DATA, 'strokes')
LEAP_PEOPLE_DATA = os.environ.get('LEAP_PEOPLE_DATA') or os.path.join(SHARED_DATA, 'leap_people')

CIRCLE = 'circle'
LOOP_FREE = ('left-swipe', 'right-swipe', 'v', 'check', 'caret', 'zig-zag',
             'square-braket-left', 'square-braket-right', 'curly-braket-left',
             'curly-braket-right', 'arc3Dleft', 'arc3Dright')
LOOPED = ('spiral', 'pigtail')          # hold loops: a circle event there is no error
CLOSED = ('rectangle', 'triangle', 'star', 'x', 'delete', 'poly3Dxyz', 'poly3Dxzy',
          'poly3Dyxz', 'poly3Dyzx', 'poly3Dzxy', 'poly3Dzyx')
KINDS = (('circle', (CIRCLE,)), ('loop_free', LOOP_FREE), ('looped', LOOPED),
         ('closed', CLOSED))
# The hands moved along the strokes: GTI label, and which fingers the SDK flags extended
# (thumb .. pinky; None: either) on the frame chosen.
HANDS = {'pointing': ('index', (None, True, False, False, False)),
         'open': ('five', (True, True, True, True, True))}


def _kind(symbol):
    for kind, symbols in KINDS:
        if symbol in symbols:
            return kind
    return None


def load_strokes(folder=STROKES_DATA):
    """{person: {symbol: (t (n,) s from the stroke's first sample, xyz (n, 3) mm)}}."""
    if not os.path.isdir(folder):
        raise DataError('no strokes folder at %s (set $STROKES_DATA)' % folder)
    out = {}
    for person in sorted(os.listdir(folder)):
        files = sorted(glob.glob(os.path.join(folder, person, '*.csv')))
        if not files:
            continue
        out[person] = {}
        for path in files:
            a = np.loadtxt(path, ndmin=2)
            if a.shape[1] != 4 or len(a) < 2 or not np.isfinite(a).all():
                raise DataError('%s: expected rows of 4 finite numbers (x y z ms)' % path)
            out[person][os.path.basename(path)[:-4]] = ((a[:, 3] - a[0, 3]) * 1e-3, a[:, :3])
    if not out:
        raise DataError('no strokes under %s' % folder)
    return out


def _parsed(text):
    """json.loads through orjson when installed (leapjs.parse_json: a third of the time);
    what it refuses (NaN...) as json.loads reads it."""
    try:
        return leapjs.parse_json(text)
    except ValueError:
        return json.loads(text)


def _flags_match(d, want):
    by_type = {p.get('type'): p.get('extended') for p in d.get('pointables') or []}
    return all(w is None or by_type.get(i) is w for i, w in enumerate(want))


def template_hands(folder=LEAP_PEOPLE_DATA):
    """{'pointing': [Hand per GTI person], 'open': [...]}: per person (in name order) the
    most confident frame of the label whose SDK flags match (first of equals)."""
    path = os.path.join(folder, 'gti_dev.jsonl.gz')
    if not os.path.exists(path):
        raise DataError('no %s (set $LEAP_PEOPLE_DATA)' % path)
    stat = os.stat(path)
    return {kind: list(hands) for kind, hands in _template_hands(path, stat.st_mtime_ns, stat.st_size).items()}


@functools.lru_cache(maxsize=2)
def _template_hands(path, mtime_ns, size):
    # (read once per process and file version: the tests and run() both want them)
    best = {}
    labels = {label: kind for kind, (label, _) in HANDS.items()}
    with gzip.open(path, 'rt') as f:
        for line in f:
            d = _parsed(line)
            kind = labels.get(d.get('label'))
            if kind is None or not _flags_match(d['frame'], HANDS[kind][1]):
                continue
            hands = d['frame'].get('hands') or []
            conf = float(hands[0].get('confidence', 0.0)) if hands else 0.0
            key = (kind, d['person'])
            if key not in best or conf > best[key][0]:
                best[key] = (conf, d['frame'])
    out = {kind: [] for kind in HANDS}
    for (kind, person) in sorted(best):
        frame = leapjs.frame_from_dict(best[(kind, person)][1], timestamp=0.0)
        out[kind].append(frame.hands[0])
    if not all(out.values()):
        raise DataError('%s holds no usable frame for %s'
                        % (path, [k for k, v in out.items() if not v]))
    return out


def _shifted(v, d):
    return None if v is None else v + d


def hand_at(hand, tip):
    """`hand` translated so that its index tip is at `tip` (mm)."""
    d = np.asarray(tip, dtype=float) - hand.fingers[1].tip
    fingers = tuple(Finger(f.tip + d, f.direction, f.extended, _shifted(f.mcp, d),
                           _shifted(f.pip, d), _shifted(f.dip, d)) for f in hand.fingers)
    return dataclasses.replace(hand, palm_position=hand.palm_position + d, fingers=fingers)


def circle_events(events):
    return [e for e in events if e.active and e.gesture.startswith('circle')]


def _mover(hand):
    """point -> hand_at(hand, point) (the same sums), at a third of its cost: the hand's
    joints moved in one addition, the moved Hand built directly."""
    fingers = hand.fingers
    names = ('tip', 'mcp', 'pip', 'dip')
    joints = [hand.palm_position] + [getattr(f, a) for f in fingers for a in names
                                     if getattr(f, a) is not None]
    if not all(j.__class__ is np.ndarray and j.dtype == float and j.shape == (3,) for j in joints):
        return lambda point: hand_at(hand, point)
    base, index_tip, fields, make = np.array(joints), fingers[1].tip, vars(hand), type(hand)
    rows, k = [], 1                         # per finger, the row of each joint in base (-1: none)
    for f in fingers:
        rows.append([])
        for a in names:
            present = getattr(f, a) is not None
            rows[-1].append(k if present else -1)
            k += present

    def at(point):
        moved = list(base + (np.asarray(point, dtype=float) - index_tip))
        moved.append(None)
        return make(**dict(fields, palm_position=moved[0], fingers=tuple(
            Finger(moved[t], f.direction, f.extended, moved[m], moved[p], moved[d])
            for f, (t, m, p, d) in zip(fingers, rows))))
    return at


def draw(hand, t, xyz, recognizer=None):
    """Circle events [(time s, HandEvent)] of `hand` moved along the path."""
    rec = recognizer or GestureRecognizer()
    at = _mover(hand)
    out = []
    for k in range(len(t)):
        state = rec.update(at(xyz[k]), t[k])
        out += [(float(t[k]), e) for e in circle_events(state.events)]
    return out


def load_guinevere(folder=LEAP_PEOPLE_DATA):
    """{'NN/name': [frame dicts]} of the Guinevere takes."""
    paths = sorted(glob.glob(os.path.join(folder, 'guinevere', '*', '*.json.gz')))
    if not paths:
        raise DataError('no Guinevere takes under %s/guinevere' % folder)
    out = {}
    for path in paths:
        with gzip.open(path, 'rt') as f:
            data = _parsed(f.read())
        frames = data.get('data') if isinstance(data, dict) else None
        if not isinstance(frames, list):
            raise DataError('%s: expected {"frames": N, "data": [frames]}' % path)
        out[os.path.relpath(path, os.path.join(folder, 'guinevere'))[:-len('.json.gz')]] = frames
    return out


def take_circles(dicts, make_recognizer=GestureRecognizer):
    """Circle events [(time s, side, HandEvent)] of a take's frame dicts, one
    recognizer per hand side (as classify_frames)."""
    return [(frame.timestamp, hand.side, e)
            for _, frame, judged in recognize_take(dicts, make_recognizer)
            for hand, state in judged for e in circle_events(state.events)]


def leapjs_takes(folder=None):
    folder = folder or datasets.data_dir()
    out = {}
    for take in EVERY_TAKE:
        path = datasets.find_take(folder, take)
        if path is None:
            raise DataError('LeapJS take %s not found in %s (set $LEAPJS_DATA)' % (take, folder))
        out[take] = leapjs.load(path)[1]
    return out


# -- fitting the circle rules: the recognizer's calls to its CircleDetector, recorded once
# and replayed through detectors with other rules (the poses do not depend on them).
class _Recorder:
    """Stands in for a recognizer's CircleDetector: keeps its calls, fires nothing."""

    def __init__(self, calls):
        self.calls = calls

    def update(self, hand, timestamp, geometry, extended):
        self.calls.append((hand, timestamp, geometry, tuple(extended)))

    def reset(self):
        self.calls.append(None)


def _recording_recognizer(calls):
    rec = GestureRecognizer()
    rec.circles = _Recorder(calls)
    return rec


class CachedFits(CircleFits):
    """CircleFits that fits each stretch of path once: the rules replayed over the same
    calls differ in a number or two, and their detectors fit the same stretches over
    and over. A stretch is known by a 128-bit digest of its points (not its few kB)."""

    def __init__(self):
        self._sweeps, self._tails = {}, {}

    def sweeps(self, p):
        key = _digest(p)
        if key not in self._sweeps:
            self._sweeps[key] = super().sweeps(p)
        return self._sweeps[key]

    def tail_circle(self, p):
        key = _digest(p)
        if key not in self._tails:
            self._tails[key] = super().tail_circle(p)
        return self._tails[key]


def _digest(p):
    return hashlib.blake2b(np.ascontiguousarray(p).data, digest_size=16).digest()


def replay(calls, rules, fits=None):
    """Circle events [(time s, HandEvent)] of a CircleDetector with `rules` fed the
    recorded calls (None: the hand left); `fits`: its CircleFits (e.g. a CachedFits
    shared by the replays of many rules)."""
    det = CircleDetector(rules, fits)
    out = []
    for c in calls:
        if c is None:
            det.reset()
            continue
        e = det.update(*c)
        if e is not None:
            out.append((c[1], e))
    return out


# -- replaying many rules over one recording: a CircleDetector's work that does not
# depend on its rules, done once per recording. Which points a track keeps does not: the
# smoothing and the resampling at the track's spacing read no rule, and a jump or an
# event restarts the path at a point the track keeps either way. What the rules change
# is where the path restarts, and the gate and fits along it; those are worked out per
# stretch from a restart (one numpy pass per restart point and max_s, whatever the other
# numbers), in the detector's own arithmetic, so the events are the detector's own.
class _TrackPoints:
    """The points a CircleDetector's track (palm or index tip) keeps over a recording,
    with what its gate reads of each: the step's squared length (a jump restarts the
    path there when longer than the rules allow), length, speed and its terms of the
    area's prefix sums. `restart[frame]`: where the path restarts when an event clears
    it at that frame (its last point, or the next one when it is empty)."""

    def __init__(self, spacing, is_tip):
        self.spacing, self.is_tip = spacing, is_tip     # the tip's swipes: rules.tip_v_max
        self.spacing2 = spacing * spacing
        self.frame, self.t, self.p, self.l2, self.step, self.speed = [], [], [], [], [], []
        self.ab, self.hard = [], []             # [qy z, qz x, qx y, qz y, qx z, qy x]; a restart whatever the rules
        self.restart = []
        self.empty = True

    def feed(self, frame, t, p):
        """Whether the track keeps the point [x, y, z] (as _CircleTrack.add)."""
        if not self.empty:
            x, y, z = p
            qx, qy, qz = self.p[-1]
            sx, sy, sz = x - qx, y - qy, z - qz
            l2 = sx * sx + sy * sy + sz * sz
            if l2 < self.spacing2:
                return False
            if t >= self.t[-1]:
                step = math.sqrt(l2)
                dt = t - self.t[-1]
                self._keep(frame, t, p, False, l2, step, step / dt if dt > 0.0 else math.inf,
                           (qy * z, qz * x, qx * y, qz * y, qx * z, qy * x))
                return True
        self.empty = False
        self._keep(frame, t, p, True, math.inf, 0.0, 0.0, (0.0,) * 6)
        return True

    def _keep(self, frame, t, p, hard, l2, step, speed, ab):
        self.frame.append(frame)
        self.t.append(t)
        self.p.append(p)
        self.hard.append(hard)
        self.l2.append(l2)
        self.step.append(step)
        self.speed.append(speed)
        self.ab.append(ab)

    def end_frame(self):
        n = len(self.t)
        self.restart.append(n if self.empty else n - 1)

    def finish(self, fits):
        self.n = len(self.t)
        self.ts = np.array(self.t, dtype=float)
        self.pts = np.array(self.p, dtype=float).reshape(-1, 3)
        self.l2 = np.array(self.l2, dtype=float)
        self.steps = np.array(self.step, dtype=float)
        self.ab = np.array(self.ab, dtype=float).reshape(-1, 6)
        self.hard = np.array(self.hard, dtype=bool)
        starts = np.flatnonzero(self.hard).tolist() + [self.n]
        self.run_end = np.repeat(starts[1:], np.diff(starts)).tolist() if self.n else []
        self.fits = fits
        self._breaks, self._blocks, self._roundest, self._candidates = {}, {}, {}, {}
        self._circles, self._first = {}, {}

    def segment_end(self, s, r_max):
        """Where the path from `s` restarts next (a restart whatever the rules, or a jump
        longer than r_max allows; the track's jump2)."""
        breaks = self._breaks.get(r_max)
        if breaks is None:
            jump2 = (25 * self.spacing + 2 * r_max) ** 2
            breaks = self._breaks[r_max] = np.flatnonzero(self.hard | (self.l2 > jump2)).tolist()
        k = bisect_right(breaks, s)
        return breaks[k] if k < len(breaks) else self.n

    def candidates(self, s, rules):
        """([frame], [n], [j]) of the points from `s` on (to the end of its run) where
        the gate of a path restarted at `s` passes: the stretch from point j to point n
        is the roundest past min_roundness (as _CircleTrack.add)."""
        key = (s, rules.max_s, rules.arc, rules.min_roundness)
        out = self._candidates.get(key)
        if out is None:
            out = self._candidates[key] = self._gate(s, rules)
        return out

    def _gate(self, s, rules):
        # The roundest stretch wins when it beats min_roundness (add's loop keeps the first
        # of equals): per min_roundness only that comparison differs.
        roundest = self._roundest.get((s, rules.max_s, rules.arc))
        if roundest is None:
            roundest = self._roundest[s, rules.max_s, rules.arc] = self._roundest_stretches(s, rules)
        n, j, r = roundest
        ok = r > rules.min_roundness
        ns = n[ok].tolist()
        return [self.frame[k] for k in ns], ns, j[ok].tolist()

    def _roundest_stretches(self, s, rules):
        """(points n, their roundest stretch's start j, its roundness) from `s` on where
        the path since the head is long enough and a stretch is long enough."""
        hi = self.run_end[s]
        if hi - s <= CIRCLE_MIN_POINTS:
            return np.empty(0, int), np.empty(0, int), np.empty(0)
        block = self._blocks.get((s, rules.max_s))
        if block is None:
            block = self._blocks[s, rules.max_s] = self._block(s, hi, rules.max_s)
        js, perimeter, roundness, since_head = block
        min_len = rules.arc * CIRCLE_R_MIN
        n = np.arange(s, hi)
        r = np.where((n - js >= CIRCLE_MIN_POINTS) & ~(perimeter < min_len) & ~np.isnan(roundness),
                     roundness, -np.inf)
        best = r.argmax(axis=0)
        cols = np.arange(len(n))
        r = r[best, cols]
        ok = (r > -np.inf) & ~(since_head < min_len)
        return n[ok], js[best, cols][ok], r[ok]

    def _block(self, s, hi, max_s):
        """Per point n of [s, hi) and per stretch (the track's spans): its start j, the
        closed perimeter and the roundness of the stretch, and the path length since the
        track's head; all as _CircleTrack.add computes them, the path restarted at s."""
        ts, p = self.ts[s:hi], self.pts[s:hi]
        # prefix sums from s, in add's order: length + step; cross + a - b per axis
        length = np.concatenate(([0.0], np.cumsum(self.steps[s + 1:hi])))
        ab = self.ab[s + 1:hi]
        cross = np.zeros((hi - s, 3))
        for axis in range(3):
            terms = np.empty(2 * (hi - s - 1))
            terms[0::2], terms[1::2] = ab[:, axis], -ab[:, axis + 3]
            cross[1:, axis] = np.cumsum(terms)[1::2]
        spans = np.array([f * max_s for f in SPAN_FRACTIONS])
        n = np.arange(hi - s)
        head = np.searchsorted(ts, ts - spans[-1])
        js = np.minimum(np.searchsorted(ts, (ts[None, :] - spans[:, None]).ravel())
                        .reshape(len(spans), -1), n)
        x, y, z = p[:, 0], p[:, 1], p[:, 2]
        a = p[js]
        ex, ey, ez = x - a[..., 0], y - a[..., 1], z - a[..., 2]
        perimeter = length - length[js] + np.sqrt(ex * ex + ey * ey + ez * ez)
        cn, cj = cross, cross[js]
        ax = cn[:, 0] - cj[..., 0] + y * a[..., 2] - z * a[..., 1]
        ay = cn[:, 1] - cj[..., 1] + z * a[..., 0] - x * a[..., 2]
        az = cn[:, 2] - cj[..., 2] + x * a[..., 1] - y * a[..., 0]
        with np.errstate(divide='ignore', invalid='ignore'):
            roundness = _TWO_PI * np.sqrt(ax * ax + ay * ay + az * az) / (perimeter * perimeter)
        return js + s, perimeter, roundness, length - length[head]

    def first_circle(self, s, rules, reads, verdict):
        """(frame, *verdict) of the first circle the track closes from point s on (its
        path restarted there, and again wherever the rules restart it) that `verdict`
        (j, n, frame, hit, rules) -> (cw, radius, source, centre) or None keeps; None
        without one. `reads`: the rules this track's circles depend on (a key)."""
        key = (s, reads)
        if key in self._first:
            return self._first[key]
        found = None
        while s < self.n and found is None:
            e = self.segment_end(s, rules.r_max)
            frames, ns, js = self.candidates(s, rules)
            failed = -math.inf                  # the last point whose fit failed
            for k in range(bisect_left(ns, e)):
                n, j = ns[k], js[k]
                if n - failed <= CIRCLE_RETRY_POINTS:
                    continue                    # the track's wait after a failed fit
                if self.is_tip and max(self.speed[j + 1:n + 1]) > rules.tip_v_max:
                    failed = n
                    continue
                hit = self.circle(j, n, rules)
                if hit is None:
                    failed = n
                    continue
                found = verdict(j, n, frames[k], hit, rules)
                if found is not None:
                    found = (frames[k],) + found
                    break
            s = e
        self._first[key] = found
        return found

    def circle(self, j, n, rules):
        """The track's circle on the stretch j..n, or None (as _CircleTrack.add)."""
        key = (j, n, rules.arc)
        hit = self._circles.get(key, False)
        if hit is False:
            # whatever the largest radius, checked below (its one use)
            hit = self._circles[key] = track_circle(self.pts[j:n + 1].copy(), rules.arc,
                                                    CIRCLE_R_MIN, math.inf, self.fits)
        return hit if hit is None or hit[1] <= rules.r_max else None


_TWO_PI = 2.0 * math.pi


class RecordedCircles:
    """One recording's calls to a CircleDetector (None: the hand left), for replays:
    events(rules) is replay(calls, rules) at a fraction of its cost once the work that
    does not depend on the rules is done (here, once). A recording whose time goes back
    is replayed by a detector."""

    def __init__(self, calls, fits):
        self.calls, self.fits = calls, fits
        times = [c[1] for c in calls if c is not None]
        self.monotonic = all(b >= a for a, b in zip(times, times[1:]))
        if self.monotonic:
            self._walk(calls)
        self._fast = {}

    def _walk(self, calls):
        """The detector's rule-free work, frame by frame (as CircleDetector.update)."""
        self.palm, self.tip = palm, tip = _TrackPoints(PALM_SPACING, False), _TrackPoints(TIP_SPACING, True)
        self.resets = []
        # the index tip's stretches: palm normals (time, normal) and raw tip steps (time,
        # squared length, duration) of each, and per tip point its stretch's extent
        self.normals, self.steps = [], []
        self.tip_stretch = []                   # per tip point: (first normal, its normal, first step, steps)
        palm_smooth = tip_smooth = tip_prev = None
        normals_from = steps_from = None
        a = PALM_SMOOTHING
        for frame, c in enumerate(calls):
            if c is None:
                self.resets.append(frame)
                palm_smooth = None
                palm.empty = True
            else:
                _, t, g, extended = c
                x, y, z = g.palm
                if palm_smooth is not None:
                    sm = palm_smooth
                    x, y, z = sm[0] + a * (x - sm[0]), sm[1] + a * (y - sm[1]), sm[2] + a * (z - sm[2])
                palm_smooth = [x, y, z]
                palm.feed(frame, t, palm_smooth)
            if c is not None and index_draws(extended):
                if normals_from is None:
                    normals_from, steps_from = len(self.normals), len(self.steps)
                self.normals.append((t, g.basis[1]))
                tp = g.tips_world[1]
                if math.isfinite(tp[0] + tp[1] + tp[2]):
                    if tip_prev is not None and t > tip_prev[0]:
                        pt = tip_prev[1]
                        self.steps.append((t, (tp[0] - pt[0]) ** 2 + (tp[1] - pt[1]) ** 2
                                           + (tp[2] - pt[2]) ** 2, t - tip_prev[0]))
                    tip_prev = (t, tp)
                    sm = tip_smooth
                    if sm is not None:
                        tp = [sm[0] + a * (tp[0] - sm[0]), sm[1] + a * (tp[1] - sm[1]),
                              sm[2] + a * (tp[2] - sm[2])]
                    tip_smooth = tp
                    if tip.feed(frame, t, tp):
                        self.tip_stretch.append((normals_from, len(self.normals) - 1,
                                                 steps_from, len(self.steps)))
            else:
                tip_smooth = tip_prev = normals_from = steps_from = None
                tip.empty = True
            palm.end_frame()
            tip.end_frame()
        palm.finish(self.fits)
        tip.finish(self.fits)
        self.normal_t = [t for t, _ in self.normals]

    def events(self, rules, most=math.inf):
        """Circle events [(time s, HandEvent)] of a CircleDetector with `rules` fed the
        calls (as replay), the first `most` of them."""
        if not self.monotonic:
            out = replay(self.calls, rules, self.fits)
            return out[:most] if len(out) > most else out
        palm, tip = self.palm, self.tip
        palm_rules = (rules.max_s, rules.arc, rules.min_roundness, rules.r_max)
        out = []
        last_event, last_frame = -math.inf, -1
        palm_from = tip_from = 0
        while True:
            # Each track goes its own way until one closes a circle (the palm first within
            # a frame, as the detector): the event clears both paths.
            found = palm.first_circle(palm_from, rules, palm_rules, _palm_circle)
            by_tip = tip.first_circle(tip_from, rules, rules, self._index_circle)
            if by_tip is not None and (found is None or by_tip[0] < found[0]):
                found = by_tip
            if found is None:
                return out
            frame, cw, radius, source, centre = found
            palm_from, tip_from = palm.restart[frame], tip.restart[frame]
            if bisect_right(self.resets, frame) > bisect_right(self.resets, last_frame):
                last_event = -math.inf          # the hand left since
            t = self.calls[frame][1]
            if t - last_event < CIRCLE_REFRACTORY_S:
                continue
            last_event, last_frame = t, frame
            out.append((t, HandEvent('circle_cw' if cw else 'circle_ccw', True, radius * 1e-3,
                                     source, tuple(float(c) for c in centre))))
            if len(out) >= most:
                return out

    def _index_circle(self, j, n, frame, hit, rules):
        """CircleDetector._tip's verdict on the index tip's circle on the stretch j..n:
        (cw, radius, 'index', centre) or None."""
        t = self.calls[frame][1]
        normals_from, normal, steps_from, steps_to = self.tip_stretch[n]
        fast = self._last_fast(rules.tip_v_max)
        k = fast[steps_to - 1] if steps_to > steps_from else -1
        if k >= steps_from and t - self.steps[k][0] < rules.max_s:
            return None                         # swiped within the stretch
        first = bisect_left(self.normal_t, t - rules.max_s, normals_from, normal + 1)
        hand, _, g, _ = self.calls[frame]
        cw = index_circle_cw(hit[0], hand, g, self.normals[first:normal + 1], rules.min_across)
        return None if cw is None else (cw, hit[1], 'index', hit[2])

    def _last_fast(self, v_max):
        """Per raw tip step, the last one so far faster than v_max (-1: none)."""
        out = self._fast.get(v_max)
        if out is None:
            out, last = [], -1
            for k, (_, d2, dt) in enumerate(self.steps):
                if d2 > (v_max * dt) ** 2:
                    last = k
                out.append(last)
            self._fast[v_max] = out
        return out


def _palm_circle(j, n, frame, hit, rules):
    return hit[0][1] > 0, hit[1], 'palm', hit[2]


def record_strokes(strokes, hands):
    """{(hand kind, person, symbol): recorded calls} of every stroke drawn with each hand."""
    out = {}
    for kind in HANDS:
        for k, person in enumerate(sorted(strokes)):
            hand = hands[kind][k % len(hands[kind])]
            for symbol, (t, xyz) in sorted(strokes[person].items()):
                calls = []
                draw(hand, t, xyz, _recording_recognizer(calls))
                # the detector reads only the finger's direction off the Hand, which the
                # translation keeps: one Hand for the stroke holds less memory
                out[(kind, person, symbol)] = [c and (hand,) + c[1:] for c in calls]
    return out


def record_takes(takes):
    """{take: [recorded calls per hand side]} of frame-dict takes."""
    out = {}
    for name, dicts in sorted(takes.items()):
        per_side = {}

        def make(per_side=per_side):
            calls = []
            per_side[len(per_side)] = calls
            return _recording_recognizer(calls)
        take_circles(dicts, make)
        out[name] = list(per_side.values())
    return out


# The circle rules' search: each rule over its grid, one at a time (the others held),
# two passes in FIT_ORDER from the rules before this refit (CircleRules()). A value
# scores by the training people's circles recognized (both hands) minus twice their
# loop-free strokes firing one; any circle event on a shared take rules it out; ties go
# to fewer closed angular shapes firing; of what is still tied, the middle value (the
# widest margin on both sides).
GRID = {'tip_v_max': (1000.0, 1500.0, 2000.0, 3000.0, 4000.0),
        'max_s': (1.6, 2.0, 2.5, 3.0),
        'r_max': (100.0, 125.0, 150.0, 200.0, 250.0, 300.0),
        'arc': tuple(math.pi * k for k in (1.5, 1.625, 1.75, 1.875)),
        'min_roundness': (0.5, 0.6, 0.7, 0.8),
        'min_across': (0.4, 0.5, 0.6, 0.7, 0.8, 0.9)}
FIT_ORDER = ('tip_v_max', 'max_s', 'r_max', 'arc', 'min_roundness', 'min_across')
FIT_PASSES = 2
LOOP_FREE_WEIGHT = 2


class CircleFit:
    """Leave-one-person-out choice of CircleRules from recorded calls (record_strokes,
    record_takes), replayed through RecordedCircles; each rules' outcome is computed
    once, each circle fit once (`fits`, default a new CachedFits), and a recording without
    pointing frames is replayed once for rules that differ only in TIP_RULES."""

    def __init__(self, stroke_calls, take_calls, fits=None):
        self.stroke_calls = stroke_calls
        self.take_calls = take_calls
        self.fits = CachedFits() if fits is None else fits
        self._cache = {}
        self._events = {}                   # (recording, rules read) -> circle events
        self._recordings = {}               # recording -> its RecordedCircles
        self._tip_free = {key for key, calls in (*stroke_calls.items(), *self._take_sides())
                          if not any(c is not None and index_draws(c[3]) for c in calls)}
        self._tip_default = {name: getattr(CircleRules, name) for name in TIP_RULES}

    def _take_sides(self):
        """((take, side), recorded calls) of every take."""
        for name, sides in self.take_calls.items():
            for k, calls in enumerate(sides):
                yield (name, k), calls

    def _n_events(self, key, calls, rules, most=math.inf):
        read = rules
        if key in self._tip_free:
            read = dataclasses.replace(rules, **self._tip_default)
        if (key, read) not in self._events:
            recording = self._recordings.get(key)
            if recording is None:
                recording = self._recordings[key] = RecordedCircles(calls, self.fits)
            self._events[key, read] = len(recording.events(rules, most))
        return self._events[key, read]

    def outcome(self, rules):
        """({(hand kind, person, symbol): circle events, as many as are read (_events_read)},
        circle events on the takes)."""
        if rules not in self._cache:
            strokes = {key: self._n_events(key, calls, rules, _events_read(key[2]))
                       for key, calls in self.stroke_calls.items()}
            takes = sum(self._n_events(key, calls, rules) for key, calls in self._take_sides())
            self._cache[rules] = strokes, takes
        return self._cache[rules]

    def score(self, rules, people):
        strokes, takes = self.outcome(rules)
        if takes:
            return (-math.inf, -math.inf)
        good = bad = closed = 0
        for (_, person, symbol), n in strokes.items():
            if person not in people or not n:
                continue
            kind = _kind(symbol)
            good += kind == 'circle'
            bad += kind == 'loop_free'
            closed += kind == 'closed'
        return (good - LOOP_FREE_WEIGHT * bad, -closed)

    def fit(self, people, start=None):
        rules = start or CircleRules()
        people = set(people)
        for _ in range(FIT_PASSES):
            for name in FIT_ORDER:
                values = GRID[name]
                scores = [self.score(dataclasses.replace(rules, **{name: v}), people)
                          for v in values]
                best = [i for i, s in enumerate(scores) if s == max(scores)]
                rules = dataclasses.replace(rules, **{name: values[best[(len(best) - 1) // 2]]})
        return rules

    def loso(self, people):
        """{'folds': {person: {'rules', 'held_out'}}, 'pooled', 'worst_person', 'all'}."""
        folds = {}
        for person in people:
            rules = self.fit([p for p in people if p != person])
            folds[person] = {'rules': _rules_dict(rules),
                             'held_out': self._counts(rules, [person])}
        pooled = _sum_counts([f['held_out'] for f in folds.values()])
        worst = min(people, key=lambda p: (_recall(folds[p]['held_out']),
                                           -folds[p]['held_out']['loop_free_fired']))
        return {'folds': folds, 'pooled': pooled, 'worst_person': worst,
                'all_people_rules': _rules_dict(self.fit(people))}

    def _counts(self, rules, people):
        strokes, takes = self.outcome(rules)
        out = _zero_counts()
        for (hand, person, symbol), n in strokes.items():
            if person in people:
                _count(out, hand, _kind(symbol), n)
        out['take_events'] = takes
        return out


def _events_read(symbol):
    """How many of a stroke's circle events the scores and counts read (a replay stops
    there): whether the circle fired and fired twice, whether any other stroke fired."""
    return 2 if _kind(symbol) == 'circle' else 1


def _rules_dict(rules):
    d = dataclasses.asdict(rules)
    d['arc_deg'] = round(math.degrees(d.pop('arc')), 1)
    return d


def _zero_counts():
    return {'circles': 0, 'circles_recognized': 0, 'circles_fired_twice': 0,
            'loop_free': 0, 'loop_free_fired': 0, 'closed': 0, 'closed_fired': 0,
            'looped': 0, 'looped_fired': 0,
            'per_hand': {h: {'circles': 0, 'circles_recognized': 0, 'loop_free': 0,
                             'loop_free_fired': 0} for h in HANDS}}


def _count(out, hand, kind, n):
    if kind is None:
        return
    if kind == 'circle':
        out['circles'] += 1
        out['circles_recognized'] += n > 0
        out['circles_fired_twice'] += n > 1
        out['per_hand'][hand]['circles'] += 1
        out['per_hand'][hand]['circles_recognized'] += n > 0
    else:
        out[kind] += 1
        out[kind + '_fired'] += n > 0
        if kind == 'loop_free':
            out['per_hand'][hand]['loop_free'] += 1
            out['per_hand'][hand]['loop_free_fired'] += n > 0


def _sum_counts(counts):
    out = _zero_counts()
    for c in counts:
        for k, v in c.items():
            if k == 'per_hand':
                for h, d in v.items():
                    for kk, vv in d.items():
                        out['per_hand'][h][kk] += vv
            elif k != 'take_events':
                out[k] += v
    return out


def _recall(c):
    return c['circles_recognized'] / c['circles'] if c['circles'] else 1.0


# -- the evaluation with the shipped rules ----------------------------------------------
def run(strokes_dir=STROKES_DATA, leap_people_dir=LEAP_PEOPLE_DATA, leapjs_dir=None,
        rules=None, loso=False):
    """The figures as a JSON-able dict: per person and per symbol (each hand), circles
    recognized, loop-free / closed / looped strokes firing one, circle events on the
    Guinevere and LeapJS takes; with `loso`, the leave-one-person-out refit too. `rules`:
    CircleRules for the detector (default: the shipped ones). DataError without data."""
    # The cyclic garbage collector paused: the recordings and takes are millions of
    # containers, none in a cycle, that its collections would walk again and again (a
    # third of the CPU).
    paused = gc.isenabled()
    gc.disable()
    try:
        return _run(strokes_dir, leap_people_dir, leapjs_dir, rules, loso)
    finally:
        if paused:
            gc.enable()


def _run(strokes_dir, leap_people_dir, leapjs_dir, rules, loso):
    strokes = load_strokes(strokes_dir)
    hands = template_hands(leap_people_dir)
    people = sorted(strokes)
    rules = rules or DRAWN
    # The recognizer runs once over every stroke and take; its circle detector's calls
    # are replayed through the rules here and, with loso, through every candidate.
    stroke_calls = record_strokes(strokes, hands)
    fits = CachedFits()
    per_person, per_symbol, fired, replayed = {}, {}, [], {}
    total = _zero_counts()
    for kind in HANDS:
        for person in people:
            for symbol in sorted(strokes[person]):
                events = replay(stroke_calls[kind, person, symbol], rules, fits)
                replayed[kind, person, symbol] = len(events)
                sym_kind = _kind(symbol)
                for c in (per_person.setdefault(person, _zero_counts()),
                          per_symbol.setdefault(symbol, _zero_counts()), total):
                    _count(c, kind, sym_kind, len(events))
                if events:
                    fired.append({'hand': kind, 'person': person, 'symbol': symbol,
                                  'kind': sym_kind, 'events': [
                                      {'t': round(t_, 3), 'gesture': e.gesture,
                                       'source': e.source, 'radius_mm': round(e.value * 1e3, 1)}
                                      for t_, e in events]})
    frames = {'guinevere/' + k: v for k, v in load_guinevere(leap_people_dir).items()}
    frames.update(('leapjs/' + k, v) for k, v in leapjs_takes(leapjs_dir).items())
    take_calls = record_takes(frames)
    takes = {name: sum(len(replay(calls, rules, fits)) for calls in sides)
             for name, sides in sorted(take_calls.items())}
    # total, per person and per symbol: the shipped rules (DRAWN) were chosen on all these
    # people, so those are in-sample; 'loso' holds the figures on people left out.
    out = {'rules': _rules_dict(rules), 'people': people, 'total': total,
           'in_sample': rules is DRAWN,
           'per_person': per_person, 'per_symbol': per_symbol, 'fired': fired,
           'worst_person': min(people, key=lambda p: (_recall(per_person[p]),
                                                      -per_person[p]['loop_free_fired'])),
           'take_events': {k: v for k, v in takes.items() if v},
           'takes': {'guinevere': sum(k.startswith('guinevere/') for k in takes),
                     'leapjs': sum(k.startswith('leapjs/') for k in takes)},
           'takes_with_circles': sum(1 for v in takes.values() if v)}
    if loso:
        fit = CircleFit(stroke_calls, take_calls, fits)
        out['loso'] = fit.loso(people)
        # the refit's replays (RecordedCircles) against the detector's own on these rules
        capped = {key: min(n, _events_read(key[2])) for key, n in replayed.items()}
        if fit.outcome(rules) != (capped, sum(takes.values())):
            raise RuntimeError('the refit replays the circle detector wrongly (rules %s)' % (rules,))
    return out


def _rate(n, d):
    return '%d/%d (%.1f %%)' % (n, d, 100.0 * n / d) if d else '-'


def _line(name, c):
    hands = ' '.join('%s %d/%d' % (h, v['circles_recognized'], v['circles'])
                     for h, v in c['per_hand'].items())
    return ('%-20s circles %s (%s; twice %d) | loop-free firing %s | closed %s | looped %s'
            % (name, '%d/%d' % (c['circles_recognized'], c['circles']), hands,
               c['circles_fired_twice'], _rate(c['loop_free_fired'], c['loop_free']),
               _rate(c['closed_fired'], c['closed']), _rate(c['looped_fired'], c['looped'])))


def print_table(results, out=None):
    w = (out or sys.stdout).write
    w('circle rules: %s\n' % ', '.join('%s %s' % kv for kv in results['rules'].items()))
    w('strokes drawn with a pointing and an open hand (each person: one stroke a symbol)%s\n'
      % (results.get('in_sample') and '; in-sample: these rules were chosen on these people '
         '(leave one person out below, with --loso)' or ''))
    for person in results['people']:
        w(_line(person, results['per_person'][person]) + '\n')
    w(_line('all people', results['total']) + '\n')
    w('worst person: %s\n' % results['worst_person'])
    w('per symbol (strokes firing a circle / strokes, both hands):\n')
    for symbol, c in sorted(results['per_symbol'].items()):
        n = sum(c[k] for k in ('circles', 'loop_free', 'closed', 'looped'))
        k = sum(c[k] for k in ('circles_recognized', 'loop_free_fired', 'closed_fired',
                               'looped_fired'))
        w('  %-20s %d/%d\n' % (symbol, k, n))
    w('circle events on takes that draw none: %d of %d Guinevere and %d LeapJS takes %s\n'
      % (results['takes_with_circles'], results['takes']['guinevere'],
         results['takes']['leapjs'], results['take_events'] or ''))
    lo = results.get('loso')
    if lo:
        w('leave-one-person-out (rules fitted on the other people, scored on this one):\n')
        for person, f in lo['folds'].items():
            w(_line(person, f['held_out']) + '\n')
        w(_line('pooled', lo['pooled']) + '\n')
        w('worst person: %s; rules fitted on all people: %s\n' % (
            lo['worst_person'], ', '.join('%s %s' % kv for kv in lo['all_people_rules'].items())))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    ap.add_argument('--strokes', default=STROKES_DATA, help='strokes folder')
    ap.add_argument('--leap-people', default=LEAP_PEOPLE_DATA,
                    help='leap_people folder (gti_dev.jsonl.gz, guinevere/)')
    ap.add_argument('--leapjs', default=None, help='LeapJS takes folder')
    ap.add_argument('--loso', action='store_true',
                    help='also refit the circle rules leave-one-person-out (about 30 s)')
    ap.add_argument('--json', help='write the results here as JSON')
    args = ap.parse_args(argv)
    try:
        results = run(args.strokes, args.leap_people, args.leapjs, loso=args.loso)
    except (DataError, leapjs.SourceError, OSError, ValueError) as e:
        sys.stderr.write('evaluate_strokes: %s\n' % e)
        return 2
    print_table(results)
    if args.json:
        write_json(args.json, results, announce=False)
    return 0


if __name__ == '__main__':
    sys.exit(main())
