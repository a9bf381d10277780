"""What the device-driven sources share: frames pushed from the SDK's thread into a
short queue that keeps the newest, stamped on the caller's clock, pulled by frames().

The device's frames are mapped and aged on a monotonic clock, and stamped on the caller's
clock with the device's timing, shifted by how far that clock has run ahead of real time:
under /use_sim_time the caller's clock may run faster than the device's (a simulator
faster than real time), and mapped onto it the frames fell behind and were all dropped
as old."""
import collections
import logging
import math
import threading
import time

import numpy as np

from leap_teleop.hands.frame import Frame

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
    """Frames from an SDK callback thread to the consumer, newest first in importance: a
    short queue (`maxsize` frames, ~67 ms at 120 Hz) whose oldest frame is dropped when
    the consumer falls behind, and frames older than `max_age` s (by their capture time,
    on the `monotonic` clock) are dropped when read. After any stall the consumer gets the
    newest frames, never a backlog; `dropped` counts what it never saw.

    `monotonic` (time.monotonic for a device) maps the device's time and ages frames; as
    a frame arrives (put) it is given its stamp on `clock`: its monotonic time, shifted by
    how far `clock` has run ahead of real time (the most seen yet), never after clock()
    then (a clock slower than real time, or paused, is followed), and going forward; get()
    hands it on with that stamp. With `monotonic` None, `clock` does both (a clock that
    runs at the device's pace)."""

    def __init__(self, clock, maxsize=8, max_age=0.25, leak=1e-3, monotonic=None):
        self.frames = collections.deque()
        self.maxsize = maxsize
        self.max_age = max_age
        self.clock = clock
        self._mono = monotonic or clock
        # `clock` read before the monotonic clock, here and in _on_clock: a pause between
        # the two reads can only make its lead look smaller, never latch a false one.
        self._base = (clock(), monotonic()) if monotonic else None
        self._lead = 0.0             # s `clock` has run ahead of real time since _base
        self._last_clock = self._base[0] if monotonic else None
        # the last stamp given on `clock`: none is before the queue was made (frames
        # come only after it), nor before the one given before it
        self._last_out = self._last_clock
        self.dropped = 0
        self._cond = threading.Condition()
        self._offset = None          # monotonic - device time of the least-delayed frame
        self._last_dev = None
        self._last_now = None
        self._leak = leak            # s per s the offset may drift (device vs host clock)

    def stamp(self, device_us):
        """Map a device timestamp (us) onto the monotonic clock, keeping the device's
        spacing. Late frames move the mapping only slowly (it absorbs clock drift), so a
        backlog delivered late keeps its capture time and reads as old; a frame less
        delayed than every one before becomes the reference at once (a late start-up burst
        taken as the reference stamped every later frame up to 0.15 s ahead of its
        capture, for good), so no stamp is later than its arrival; a device clock that
        jumps back (device restart) or an absurd offset re-syncs."""
        now = self._mono()
        try:
            dev = float(device_us) * 1e-6
        except (TypeError, ValueError):
            return now
        if not math.isfinite(dev):
            return now
        offset = now - dev
        if (self._offset is None or dev < self._last_dev or offset < self._offset
                or offset - self._offset > 60.0 or now < self._last_now):
            self._offset = offset         # first or least delayed frame, restart, clock jump
        elif offset > self._offset:       # a late frame moves the mapping only slowly
            self._offset = min(offset, self._offset + self._leak * (now - self._last_now))
        self._last_dev, self._last_now = dev, now
        return self._offset + dev

    def put(self, frame):
        """Queue a frame as it arrives; its timestamp is on the monotonic clock (stamp())."""
        with self._cond:
            stamp = getattr(frame, 'timestamp', None)
            on_clock = None if stamp is None or self._base is None else self._on_clock(stamp)
            if len(self.frames) >= self.maxsize:
                self.frames.popleft()
                self._count_drop(1)
            self.frames.append((frame, on_clock))
            self._cond.notify()

    def _on_clock(self, mono_stamp):
        """The stamp on `clock` of a frame arriving now, captured at `mono_stamp` on the
        monotonic clock. The lead is measured at arrival: measured at release, frames
        released together got one lead and, under a 3x clock, alternating spacings."""
        now = self.clock()
        mono = self._mono()
        if now < self._last_clock:           # that clock went back (a simulator restarted)
            self._base, self._lead = (now, mono), 0.0
        self._last_clock = now
        clock0, mono0 = self._base
        self._lead = max(self._lead, (now - clock0) - (mono - mono0))
        stamp = min(clock0 + (mono_stamp - mono0) + self._lead, now)
        last = self._last_out
        # The caller's clock may step coarser than the device (a /clock tick): stamps keep
        # going forward, unless that clock itself went back.
        if last is not None and stamp <= last <= now:
            stamp = min(last + 1e-6, now)
        self._last_out = stamp
        return stamp

    def put_converted(self, source_name, convert):
        """From the SDK's thread: put the Frame of convert() -> (frame id, device timestamp
        us, hands), its capture time on the monotonic clock until get() hands it on with
        its stamp on the caller's clock. A frame that fails to convert is dropped with a
        warning: an exception must never kill the SDK's thread."""
        try:
            frame_id, device_us, hands = convert()
            self.put(Frame(id=int(frame_id or 0), timestamp=self.stamp(device_us), hands=hands))
        except Exception as e:
            log.warning('%s source: dropped a frame that failed to convert: %s', source_name, e)

    def get(self, timeout=0.1):
        """The oldest frame not older than max_age, stamped on the caller's clock, or None
        after `timeout` s."""
        with self._cond:
            deadline = None
            while True:
                while self.frames:
                    frame, on_clock = self.frames.popleft()
                    stamp = getattr(frame, 'timestamp', None)
                    if stamp is None:
                        return frame
                    if self.max_age is None or self._mono() - stamp <= self.max_age:
                        if on_clock is not None:
                            frame.timestamp = on_clock
                        return frame
                    self._count_drop(1)
                if deadline is None:
                    deadline = time.monotonic() + timeout
                left = deadline - time.monotonic()
                if left <= 0:
                    return None
                self._cond.wait(left)

    def __len__(self):
        return len(self.frames)

    def _count_drop(self, n):
        before = self.dropped
        self.dropped += n
        if before == 0 or before // 1000 != self.dropped // 1000:
            log.warning('hand source: consumer or device behind, dropped %d frame(s) so far '
                        '(only the newest frames are delivered)', self.dropped)


def wait_loop(source, pq):
    """Yield queued frames until the source is stopped."""
    while not source.stopped:
        frame = pq.get(0.1)
        if frame is not None:
            yield frame
        else:
            time.sleep(0)
