"""Replay of LeapJS Playback recordings (.json, .json.gz, .json.lz; formats 0.1 / 1 / 2).

Frames are stamped on the caller's clock: stamp = clock() at start + (ts - ts0), where ts
is the recorded Leap timestamp (time going back, or stopping for over MAX_GAP_S, is a
break); realtime=True also paces them at that timing (on a monotonic clock), and adds how
far the caller's clock has run ahead of real time since the start (the most seen yet, so
never behind the recorded timing): under /use_sim_time with a simulator faster than real
time the stamps follow its clock (at the recorded timing they fell behind it, and consumers
refused them as late), while in real time they are the recorded timing exactly, so frames
released late (a consumer that stalled) keep their lateness. They are never stamped after
the caller's clock's time at their release: under a clock slower than real time (a
simulator at a realtime_factor under 1, or one that falls behind) or a stopped one, a frame
is stamped with that time; a clock that goes back (a simulator restarted) is followed from
there. Otherwise they come as fast as the consumer takes them. loop=True replays forever,
each pass continuing the stamps where the previous one ended.

At each break and between loop passes comes one frame without hands, then play goes on,
each one frame period after the last: with the same hand ids the trackers would otherwise
follow one hand that jumps in a frame, keeping its origin; this way it is lost, and the
next part is a new session.

A file whose stamps mostly do not advance (all one stamp, or going back) has no usable
timing: its frames are spaced by its metadata.frameRate (else DEFAULT_RATE_HZ), with a
warning, rather than played all at once.
"""
import logging
import math
import time

from leap_teleop.hands.frame import Frame
from leap_teleop.hands.sources import leapjs
from leap_teleop.hands.sources.source import HandSource, SourceError

log = logging.getLogger(__name__)
MAX_GAP_S = 2.0     # s between two frames: longer (or back) is a break in the recording
DEFAULT_RATE_HZ = 100.0     # a file without usable timing nor a usable metadata.frameRate
RATE_RANGE_HZ = (1.0, 1000.0)   # a metadata.frameRate outside is not believed


def file_frame_rate(metadata):
    """(Hz, where from): the recording's metadata.frameRate (LeapJS writes it, maybe as
    text, e.g. '1.1e+2'), when a number in RATE_RANGE_HZ; else DEFAULT_RATE_HZ."""
    try:
        rate = float(metadata.get('frameRate'))
    except (TypeError, ValueError, OverflowError):
        rate = math.nan
    if RATE_RANGE_HZ[0] <= rate <= RATE_RANGE_HZ[1]:      # NaN compares false
        return rate, 'its metadata.frameRate'
    return DEFAULT_RATE_HZ, 'the default; no usable metadata.frameRate'


def stalled_steps(stamps):
    """(steps that are not forward in time, all steps) between successive stamps (s) when
    most of them are such (all one stamp, an exporter that wrote 0, a counter that did not
    advance, or going back): the recording has no usable timing and is spaced by its frame
    rate instead. None when its timing is usable."""
    steps = [b - a for a, b in zip(stamps, stamps[1:])]
    regular = sum(1 for d in steps if 0 < d <= MAX_GAP_S)
    return (len(steps) - regular, len(steps)) if 2 * regular < len(steps) else None


def stalled_warning(path, stalled, metadata):
    """(frames a second, the warning) for a recording whose stalled_steps are `stalled`."""
    rate, why = file_frame_rate(metadata)
    return rate, ('recording %s: its timestamps do not advance (%d of %d steps between frames '
                  'are not forward in time); played at %g frames/s (%s)'
                  % ((path,) + tuple(stalled) + (rate, why)))


class RecordingSource(HandSource):
    def __init__(self, path, loop=False, realtime=True, clock=time.time):
        self.path = str(path)
        self.loop = bool(loop)
        self.realtime = bool(realtime)
        self._clock = clock
        # Decoded once, up front (leapjs.load_frames: the fast path); playback re-stamps.
        self.metadata, frames, errors = leapjs.load_frames(self.path)
        self.bad_frames = 0
        for _, why in errors:
            self._warn_bad(why)
        usable = []
        for frame in frames:
            if math.isfinite(frame.timestamp):
                usable.append(frame)
            else:
                self._warn_bad('no usable timestamp')
        if not usable:
            raise SourceError('recording %s has no frame with a usable timestamp' % self.path)
        # Camera hands keep their picture's landmarks: the keypoint model judges them.
        self.hand_family = 'keypoints' if any(
            h.image_landmarks is not None for f in usable for h in f.hands) else 'leap'
        # Time going back, or a silence longer than MAX_GAP_S, is a break (two takes in one
        # file, a corrupt stamp): the next frame follows one frame period later. Measured
        # against the last stamp instead, one stamp days ahead dropped the rest of the take
        # and made realtime playback sleep until then.
        steps = [b.timestamp - a.timestamp for a, b in zip(usable, usable[1:])]
        regular = sorted(d for d in steps if 0 < d <= MAX_GAP_S)
        period = regular[len(regular) // 2] if regular else 0.01
        # (seconds since the first frame, Frame); a Frame of None is a hand-less one
        self._frames = [(0.0, usable[0])]
        self.breaks = 0
        stalled = stalled_steps([f.timestamp for f in usable])
        if stalled:
            # Played as recorded, the whole take came at once with one stamp, or as a
            # break at every frame.
            rate, warning = stalled_warning(self.path, stalled, self.metadata)
            log.warning('%s', warning)
            self._frames = [(k / rate, frame) for k, frame in enumerate(usable)]
            steps = []
        for step, frame in zip(steps, usable[1:]):
            if not 0 <= step <= MAX_GAP_S:
                self.breaks += 1
                self._frames.append((self._frames[-1][0] + period, None))
                step = period
            self._frames.append((self._frames[-1][0] + step, frame))
        if self.breaks:
            log.warning('recording %s: time went back or stopped for over %g s %d time(s); '
                        'played on after a hand-less frame, one frame period (%.4f s) apart, '
                        'each time', self.path, MAX_GAP_S, self.breaks, period)
        span = self._frames[-1][0]
        n = len(self._frames)
        self.duration = span
        self.rate_hz = (n - 1) / span if span > 0 and n > 1 else None

    def _warn_bad(self, why):
        self.bad_frames += 1
        if self.bad_frames in (1, 10, 100) or self.bad_frames % 1000 == 0:
            log.warning('recording %s: skipped %d bad frame(s) (latest: %s)',
                        self.path, self.bad_frames, why)

    def frames(self):
        period = 1.0 / self.rate_hz if self.rate_hz else 0.01
        # The caller's clock read before the monotonic one, here and below: a pause between
        # the two reads can only make its lead look smaller, never latch a false one.
        start_stamp = self._clock()
        start_mono = time.monotonic()
        offset = 0.0                 # recorded seconds of the passes already played
        lead = 0.0                   # s the caller's clock has run ahead of real time
        last = -math.inf             # the last stamp given
        base = last_clock = start_stamp     # the stamp of recorded time 0; the clock's last read
        seam = [(self._frames[-1][0] + period, None)]    # between passes: no hand
        while not self.stopped:
            for ts, f in self._frames + seam if self.loop else self._frames:
                if self.stopped:
                    return
                rel = offset + ts
                if self.realtime:           # in slices: stop() takes effect at once
                    delay = start_mono + rel - time.monotonic()
                    while delay > 0 and not self.stopped:
                        time.sleep(min(delay, 0.05))
                        delay = start_mono + rel - time.monotonic()
                if not self.realtime:
                    stamp = start_stamp + rel
                else:
                    # Shifted by the lead, not stamped at release: release times carry the
                    # pacing's jitter, and a backlog released at once got stamps us apart.
                    now = self._clock()
                    elapsed = time.monotonic() - start_mono
                    if now < last_clock:    # that clock went back (a simulator restarted)
                        base, lead, last = now - elapsed, 0.0, -math.inf
                    last_clock = now
                    lead = max(lead, now - base - elapsed)
                    # Never after that clock's time: one slower than real time (a simulator
                    # at a realtime_factor under 1, or behind) would read ever more ahead.
                    stamp = min(max(base + rel + lead, last + 1e-6), now)
                last = stamp
                # A fresh Frame per pass; its Hands are shared between loop passes
                # (read-only, as every source's are).
                if f is None:
                    yield Frame(0, stamp)
                else:
                    yield Frame(f.id, stamp, f.hands, f.gestures)
            if not self.loop:
                return
            offset += seam[0][0] + period
