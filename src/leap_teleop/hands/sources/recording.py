"""Replay of LeapJS Playback recordings (.json, .json.gz, .json.lz; formats 0.1 / 1 / 2).

Frames are stamped on the caller's clock: stamp = clock() at start + (ts - ts0), where ts
is the recorded Leap timestamp; realtime=True also paces them at that timing, otherwise
they come as fast as the consumer takes them. loop=True replays forever, each pass
continuing the stamps where the previous one ended.
"""
import logging
import math
import time

from leap_teleop.hands.frame import Frame
from leap_teleop.hands.sources import leapjs
from leap_teleop.hands.sources.source import HandSource, SourceError

log = logging.getLogger(__name__)


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
        self._frames = []          # (recorded time s, Frame)
        last_ts = None
        for frame in frames:
            ts = frame.timestamp
            if not math.isfinite(ts) or (last_ts is not None and ts < last_ts):
                self._warn_bad('no usable timestamp' if not math.isfinite(ts)
                               else 'timestamp goes backwards')
                continue
            self._frames.append((ts, frame))
            last_ts = ts
        if not self._frames:
            raise SourceError('recording %s has no frame with a usable timestamp' % self.path)
        span = self._frames[-1][0] - self._frames[0][0]
        n = len(self._frames)
        self.duration = span
        self.rate_hz = (n - 1) / span if span > 0 and n > 1 else None

    def _warn_bad(self, why):
        self.bad_frames += 1
        if self.bad_frames in (1, 10, 100) or self.bad_frames % 1000 == 0:
            log.warning('recording %s: skipped %d bad frame(s) (latest: %s)',
                        self.path, self.bad_frames, why)

    def frames(self):
        ts0 = self._frames[0][0]
        period = 1.0 / self.rate_hz if self.rate_hz else 0.01
        start_stamp = self._clock()
        start_mono = time.monotonic()
        offset = 0.0                 # recorded seconds of the passes already played
        while not self.stopped:
            for ts, f in self._frames:
                if self.stopped:
                    return
                rel = offset + ts - ts0
                if self.realtime:
                    delay = start_mono + rel - time.monotonic()
                    if delay > 0:
                        time.sleep(delay)
                # A fresh Frame per pass; its Hands are shared between loop passes
                # (read-only, as every source's are).
                frame = Frame(f.id, start_stamp + rel, f.hands, f.gestures)
                yield frame
            if not self.loop:
                return
            offset += self._frames[-1][0] - ts0 + period
