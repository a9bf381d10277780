"""What the device-driven sources share: frames pushed from the SDK's thread into a
bounded queue, stamped on the caller's clock, pulled by frames()."""
import logging
import math
import queue
import time

import numpy as np

log = logging.getLogger(__name__)


def xyz(v):
    """A float (3,) array from an SDK vector (.x/.y/.z, or a sequence); NaN if unusable."""
    try:
        if hasattr(v, 'x'):
            return np.array([float(v.x), float(v.y), float(v.z)])
        return np.asarray(v, dtype=float).reshape(3)
    except (TypeError, ValueError, AttributeError):
        return np.full(3, math.nan)


def attr(obj, name, default=None):
    """obj.name, calling it when the binding exposes it as a method."""
    value = getattr(obj, name, default)
    return value() if callable(value) else value


class PushQueue:
    """Frames from an SDK callback thread to the consumer; the oldest frame is dropped
    when the consumer falls behind (live data: the newest matters)."""

    def __init__(self, clock, maxsize=256):
        self.q = queue.Queue(maxsize)
        self.clock = clock
        self.dropped = 0
        self._sync = None            # (device seconds, clock seconds)

    def stamp(self, device_us):
        """Map a device timestamp (us) onto the clock, re-syncing on drift > 0.2 s."""
        now = self.clock()
        try:
            dev = float(device_us) * 1e-6
        except (TypeError, ValueError):
            return now
        if not math.isfinite(dev):
            return now
        if self._sync is None or abs(self._sync[1] + dev - self._sync[0] - now) > 0.2:
            self._sync = (dev, now)
        return self._sync[1] + dev - self._sync[0]

    def put(self, frame):
        while True:
            try:
                self.q.put_nowait(frame)
                return
            except queue.Full:
                try:
                    self.q.get_nowait()
                    self.dropped += 1
                    if self.dropped in (1, 100) or self.dropped % 10000 == 0:
                        log.warning('hand source: consumer too slow, dropped %d frame(s)',
                                    self.dropped)
                except queue.Empty:
                    pass

    def get(self, timeout=0.1):
        try:
            return self.q.get(timeout=timeout)
        except queue.Empty:
            return None


def wait_loop(source, pq):
    """Yield queued frames until the source is stopped."""
    while not source.stopped:
        frame = pq.get(0.1)
        if frame is not None:
            yield frame
        else:
            time.sleep(0)
