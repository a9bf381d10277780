"""Scripted gestures: a YAML script of poses and palm waypoints rendered into frames.

Script format (all keys but `hands` optional; a key not shown here is refused by name)::

    rate_hz: 120            # frames per second
    noise_mm: 0.0           # std. dev. of Gaussian palm noise
    seed: 0                 # noise seed
    hands:
      right:                # a list of segments, played in order
        - {pose: absent, duration: 0.5}
        - {pose: thumbs_up, palm: [0, 200, 0], duration: 1.0}
        - {pose: open, palm: [80, 220, -40], duration: 2.0}   # palm moves linearly
        - {pose: pinch, value: 0.6, duration: 1.0}
        - {pose: open, rpy: [0, 20, 0], duration: 1.0}       # roll, pitch, yaw in deg
        - {pose: open, circle: {radius: 60, turns: 1, direction: cw}, duration: 1.5}
      left: [...]

A segment holds `pose` for `duration` seconds while the palm moves from where the
previous segment ended to `palm` (mm, Leap axes) and the orientation to `rpy`; a hand
that appears (first segment, or after `absent`) appears at its `palm` and `rpy`.
`circle` moves the palm once round a horizontal circle of `radius` mm instead.
A hand whose segments are over is absent. Poses: absent and rendered_hand.POSES.

Looped (loop=True), a script whose hand jumps from its end to its start (its palm by over
SEAM_MAX_MM, or its palm normal or direction by over SEAM_MAX_DEG) plays one frame without
hands between passes, so that each pass is a new session for the trackers. A script that
ends where it starts loops with its hands kept.
"""
import logging
import math
import time

import numpy as np

from leap_teleop.hands.frame import SIDES, Frame
from leap_teleop.hands.rendered_hand import POSES, render_hand, rpy_to_basis
from leap_teleop.hands.sources.source import HandSource, SourceError
from leap_teleop.yaml_file import YamlFileError, load_yaml_file

log = logging.getLogger(__name__)

DEFAULT_PALM = (0.0, 200.0, 0.0)
# Frames a second a script may ask for: the sender's ~rate bound, and a rate the renderer
# keeps in real time on 2 cores (10 kHz ran at a third of it).
MAX_RATE_HZ = 1000.0
_TOP_KEYS = {'rate_hz', 'noise_mm', 'seed', 'hands'}
_SEGMENT_KEYS = {'pose', 'duration', 'palm', 'rpy', 'value', 'circle', 'confidence'}
_CIRCLE_KEYS = {'radius', 'turns', 'direction'}
# A looped hand moving more than this from the script's end to its start is lost between
# passes. A script that closes its loop ends one frame's motion short of its start (0.43
# mm for the shipped two-hand steady script); 10 mm in a frame is a brisk hand (1.2 m/s at 120 Hz),
# while the jumps worth a new session are a script's travel, tens of mm and more.
SEAM_MAX_MM = 10.0
SEAM_MAX_DEG = 10.0     # the same for the palm's normal or direction: a quick wrist turn


def _vector(value, what, n=3, bound=1e5):
    try:
        arr = np.asarray(value, dtype=float).reshape(n)
    except (TypeError, ValueError, OverflowError):
        raise SourceError('%s must be a list of %d numbers, got %r' % (what, n, value))
    if not np.all(np.abs(arr) <= bound):         # NaN compares false
        raise SourceError('%s must be finite, within +-%g, got %r' % (what, bound, value))
    return arr


def _known_keys(mapping, known, where):
    """SourceError naming any key of `mapping` not in `known`: a misspelt key would
    otherwise be dropped and its default played without a word."""
    unknown = set(mapping) - known
    if unknown:     # key=str: YAML keys may be numbers too
        raise SourceError('%s: unknown keys %s; known: %s'
                          % (where, sorted(unknown, key=str), sorted(known)))


def _number(value, what, lo, hi):
    """value as a float in [lo, hi], else SourceError naming `what` and the range."""
    try:
        x = float(value)
    except (TypeError, ValueError, OverflowError):
        x = math.nan
    if not lo <= x <= hi:
        raise SourceError('%s must be a number in [%g, %g], got %r' % (what, lo, hi, value))
    return x


class _Segment:
    __slots__ = ('pose', 'duration', 'start', 'palm0', 'palm1', 'rpy0', 'rpy1',
                 'value', 'circle', 'confidence')


class GestureScript:
    """A parsed, validated gesture script; hand_at(side, t) samples it."""

    def __init__(self, data, name='<script>'):
        if not isinstance(data, dict) or not isinstance(data.get('hands'), dict):
            raise SourceError('%s: a gesture script is a mapping with a "hands" mapping '
                              '(right: [...], left: [...])' % name)
        self.name = name
        _known_keys(data, _TOP_KEYS, name)
        self.rate_hz = _number(data.get('rate_hz', 120.0), name + ': rate_hz', 1e-3,
                               MAX_RATE_HZ)
        self.noise_mm = _number(data.get('noise_mm', 0.0), name + ': noise_mm', 0.0, 999.0)
        seed = data.get('seed', 0)
        if not isinstance(seed, int) or isinstance(seed, bool) or not 0 <= seed < 2 ** 32:
            raise SourceError('%s: seed must be an integer in [0, 2^32), got %r' % (name, seed))
        self.seed = seed
        self.segments = {}
        for side, segs in data['hands'].items():
            if side not in SIDES:
                raise SourceError('%s: unknown hand %r; use right or left' % (name, side))
            self.segments[side] = self._parse_segments(side, segs)
        self.duration = max([s[-1].start + s[-1].duration for s in self.segments.values() if s]
                            or [0.0])
        self._last_basis = {}

    def _parse_segments(self, side, segs):
        where = '%s: hands.%s' % (self.name, side)
        if not isinstance(segs, list):
            raise SourceError('%s must be a list of segments' % where)
        out, t = [], 0.0
        palm, rpy = np.array(DEFAULT_PALM), np.zeros(3)
        for i, raw in enumerate(segs):
            here = '%s[%d]' % (where, i)
            if not isinstance(raw, dict):
                raise SourceError('%s must be a mapping, got %r' % (here, raw))
            _known_keys(raw, _SEGMENT_KEYS, here)
            seg = _Segment()
            seg.pose = raw.get('pose', 'open')
            if not isinstance(seg.pose, str) or (seg.pose != 'absent' and seg.pose not in POSES):
                raise SourceError('%s: unknown pose %r; known: absent, %s'
                                  % (here, seg.pose, ', '.join(sorted(POSES))))
            try:
                seg.duration = float(raw.get('duration', 1.0))
            except (TypeError, ValueError):
                raise SourceError('%s: duration must be a number' % here)
            if not (0 < seg.duration < 1e6):
                raise SourceError('%s: duration must be > 0 s, got %r' % (here, raw.get('duration')))
            seg.start = t
            # mm: a Leap sees under a metre; 10 m keeps every joint in the recognizer's range
            seg.palm1 = _vector(raw['palm'], here + '.palm', bound=1e4) if 'palm' in raw else palm
            seg.rpy1 = np.radians(_vector(raw['rpy'], here + '.rpy')) if 'rpy' in raw else rpy
            # A hand that (re)appears does so at its waypoint; otherwise it moves there.
            appears = not out or out[-1].pose == 'absent'
            seg.palm0 = seg.palm1 if appears else palm
            seg.rpy0 = seg.rpy1 if appears else rpy
            seg.value = _number(raw.get('value', 0.5), here + ': pinch value', 0.0, 0.8)
            seg.confidence = _number(raw.get('confidence', 1.0), here + ': confidence', 0.0, 1.0)
            seg.circle = None
            if 'circle' in raw:
                c = raw['circle']
                if not isinstance(c, dict):
                    raise SourceError('%s.circle needs a positive radius (mm)' % here)
                _known_keys(c, _CIRCLE_KEYS, here + '.circle')
                radius = _number(c.get('radius', 0), here + '.circle.radius (mm)', 1e-3, 1e4)
                turns = _number(c.get('turns', 1.0), here + '.circle.turns', 0.0, 1e3)
                direction = c.get('direction', 'cw')
                if direction not in ('cw', 'ccw'):
                    raise SourceError('%s.circle.direction must be cw or ccw' % here)
                seg.circle = (radius, turns, 1.0 if direction == 'cw' else -1.0)
            out.append(seg)
            t += seg.duration
            palm, rpy = seg.palm1, seg.rpy1
        return out

    @classmethod
    def load(cls, path):
        try:
            data = load_yaml_file(path, 'gesture script')
        except YamlFileError as e:
            raise SourceError(str(e)) from None
        return cls(data, name=str(path))

    def _palm(self, seg, u):
        if seg.circle:
            radius, turns, sign = seg.circle
            a = 2 * math.pi * turns * u
            # Seen from above (+y), cw: starts moving toward -z... away from the user.
            offset = np.array([radius * (math.cos(a) - 1.0), 0.0, -sign * radius * math.sin(a)])
            return seg.palm0 + offset
        return seg.palm0 + (seg.palm1 - seg.palm0) * u

    def _basis(self, side, roll, pitch, yaw):
        """rpy_to_basis, again only when the orientation changed (a hand mostly holds
        it): one remembered per side. Its arrays are read-only (render_hand copies)."""
        key = (side, roll, pitch, yaw)
        last = self._last_basis.get(side)
        if last is not None and last[0] == key:
            return last[1]
        basis = rpy_to_basis(roll, pitch, yaw, side)
        for a in basis:
            a.flags.writeable = False
        self._last_basis[side] = (key, basis)
        return basis

    def has_hand(self, side):
        """Whether `side`'s hand shows at some time of the script."""
        return any(seg.pose != 'absent' for seg in self.segments.get(side, ()))

    def hand_at(self, side, t):
        """The Hand of `side` at script time t (s), or None when absent."""
        for seg in self.segments.get(side, ()):
            if seg.start <= t < seg.start + seg.duration:
                if seg.pose == 'absent':
                    return None
                u = (t - seg.start) / seg.duration
                palm = self._palm(seg, u)
                dt = 1e-3
                velocity = (self._palm(seg, min(u + dt / seg.duration, 1.0)) - palm) / dt
                rpy = (seg.rpy0 + (seg.rpy1 - seg.rpy0) * u).tolist()
                normal = direction = None
                if seg.pose != 'thumbs_up' or any(a != 0.0 for a in rpy):
                    normal, direction = self._basis(side, *rpy)
                return render_hand(side, seg.pose, palm, normal, direction,
                                   pinch_value=seg.value, velocity=velocity,
                                   confidence=seg.confidence)
        return None


class ScriptedSource(HandSource):
    """Renders a GestureScript at rate_hz, paced in real time unless realtime=False.
    `sides`: the sides its reader publishes (None: not known); a script with a hand of
    none of them, which would publish nothing with no other word, is one warning."""

    def __init__(self, script, rate_hz=None, realtime=True, loop=False, noise_mm=None,
                 seed=None, clock=time.time, sides=None):
        if not isinstance(script, GestureScript):
            script = GestureScript.load(script)
        self.script = script
        # only when it plays none of them: a one-handed script beside a default of both
        # sides (ardrone.launch's flight) is as meant
        missing = [side for side in sides or () if not script.has_hand(side)]
        if sides and len(missing) == len(sides):
            log.warning('scripted source: %s has no %s hand, so no %s hand is published '
                        '(sides: %s); give it a "%s:" list of segments or pick a script '
                        'that has one', script.name, ' or '.join(missing), ' or '.join(missing),
                        ', '.join(sides), missing[0])
        self.rate_hz = float(rate_hz or script.rate_hz)
        if not (0 < self.rate_hz <= MAX_RATE_HZ):
            raise SourceError('rate_hz must be in (0, %g], got %r' % (MAX_RATE_HZ, rate_hz))
        self.realtime = realtime
        self.loop = loop
        self.noise_mm = script.noise_mm if noise_mm is None else float(noise_mm)
        self._rng = np.random.default_rng(script.seed if seed is None else seed)
        self._clock = clock

    def frames(self):
        period = 1.0 / self.rate_hz
        n_frames = max(1, int(round(self.script.duration * self.rate_hz)))
        # A looped pass whose hand jumps from the script's end to its start ends with one
        # hand-less frame (as a looped recording does): the hand ids are fixed, so without
        # it a tracker would follow the jump, keeping its origin. A script that starts or
        # ends without the hand loses it anyway; one that ends where it starts keeps it.
        seam = self.loop and self._seam_jumps((n_frames - 1) * period)
        per_pass = n_frames + 1 if seam else n_frames
        t0_wall, t0_mono = self._clock(), time.monotonic()
        k = 0
        while not self.stopped:
            i = k % per_pass
            if k >= per_pass and not self.loop:
                return
            if self.realtime:
                delay = t0_mono + k * period - time.monotonic()
                if delay > 0:
                    time.sleep(delay)
            script_t = i * period
            hands = []
            for side in SIDES if i < n_frames else ():
                hand = self.script.hand_at(side, script_t)
                if hand is not None:
                    if self.noise_mm > 0:
                        hand.palm_position = hand.palm_position + self._rng.normal(
                            0.0, self.noise_mm, 3)
                    hands.append(hand)
            # Live pacing stamps the moment the frame is complete, as a device would;
            # fast-as-possible runs keep the ideal grid (their time is virtual).
            stamp = self._clock() if self.realtime else t0_wall + k * period
            yield Frame(id=k + 1, timestamp=stamp, hands=hands)
            k += 1

    def _seam_jumps(self, end_t):
        """Whether a hand there at both ends of the script jumps from its last frame (at
        end_t) to its first."""
        for side in SIDES:
            end, start = self.script.hand_at(side, end_t), self.script.hand_at(side, 0.0)
            if end is None or start is None:
                continue
            if np.linalg.norm(end.palm_position - start.palm_position) > SEAM_MAX_MM:
                return True
            for a, b in ((end.palm_normal, start.palm_normal), (end.direction, start.direction)):
                cos = np.dot(a, b) / max(np.linalg.norm(a) * np.linalg.norm(b), 1e-12)
                if math.degrees(math.acos(min(1.0, max(-1.0, cos)))) > SEAM_MAX_DEG:
                    return True
        return False
