"""Source stamps on the caller's clock: the recorded or device timing in real time, shifted
only by how far a faster clock (a simulator under /use_sim_time) runs ahead of it."""
import time

import numpy as np
import pytest

from leap_teleop.hands.frame import Frame
from leap_teleop.hands.rendered_hand import render_hand
from leap_teleop.hands.sources import leapjs, make_source


def _recording(tmp_path, n, dt):
    frames = [leapjs.frame_to_dict(Frame(i, 5.0 + i * dt, [render_hand('right', 'open', (i, 200, 0))]))
              for i in range(n)]
    path = str(tmp_path / 'r.json')
    leapjs.save(path, frames)
    return path


def test_a_recording_in_real_time_keeps_its_recorded_timing_and_a_stalls_lateness(tmp_path):
    # Stamped at release instead, the stamps carried the pacing's jitter, and the backlog
    # after a consumer stall came stamped microseconds apart: speeds from the stamps read
    # 7-20 m/s and the arm's lateness guard saw fresh frames.
    path = _recording(tmp_path, 40, 0.01)
    stamps, lags = [], []
    for k, f in enumerate(make_source('recording', path=path, realtime=True, clock=time.time).frames()):
        stamps.append(f.timestamp)
        lags.append(time.time() - f.timestamp)
        if k == 10:
            time.sleep(0.25)                  # the consumer stalls once
    assert len(stamps) == 40
    np.testing.assert_allclose(np.diff(stamps), 0.01, atol=1e-6)
    # the frames held back by the stall reach the consumer late, and read late
    assert min(lags[11:20]) > 0.15 and max(lags[:10]) < 0.05


def _device_run(rate, n=240, pairs=True, stall_at=None, restart_at=None):
    """A 120 Hz device (each frame arriving 2 ms after capture) through a PushQueue whose
    caller clock runs at `rate` x real time; the consumer takes two frames at a time.
    [(frame, caller clock at its capture, caller clock at its release)]."""
    from types import SimpleNamespace

    from leap_teleop.hands.sources.device_queue import PushQueue
    mono, sim = [50.0], [1000.0]
    pq = PushQueue(lambda: sim[0], monotonic=lambda: mono[0])
    got, captured = [], {}
    for i in range(n):
        if i == restart_at:
            sim[0] = 0.0                       # the simulator restarts
        mono[0] += 1 / 120
        sim[0] += rate / 120
        captured[i] = sim[0] - rate * 0.002
        pq.put(SimpleNamespace(id=i, timestamp=pq.stamp(mono[0] * 1e6 - 2000)))
        if stall_at is not None and stall_at <= i < stall_at + 6:
            continue                           # the consumer stalls for 6 frames (50 ms)
        if not pairs or i % 2:
            while True:
                f = pq.get(0.0)
                if f is None:
                    break
                got.append((f, captured[f.id], sim[0]))
    assert pq.dropped == 0
    return got


def test_device_frames_taken_together_under_a_faster_clock_keep_their_spacing_and_age():
    # The age in real seconds was taken off a 3x clock at release: frames 25 ms apart were
    # stamped 8.3 / 41.7 ms apart in turn, and their ages read 3 times short.
    got = _device_run(3.0)
    stamps = [f.timestamp for f, _, _ in got]
    np.testing.assert_allclose(np.diff(stamps), 3 / 120, atol=1e-9)
    ages = [(released - f.timestamp) for f, _, released in got[-2:]]
    np.testing.assert_allclose(ages, [3 / 120, 0.0], atol=1e-9)


def test_device_frames_in_real_time_keep_the_device_timing_and_a_stalls_age():
    got = _device_run(1.0, stall_at=100)
    # the device's timing on the caller's clock: each frame at its arrival (2 ms after
    # its capture: the least delay seen is taken as none)
    assert [f.id for f, _, _ in got] == list(range(240))
    np.testing.assert_allclose([f.timestamp - captured for f, captured, _ in got], 0.002, atol=1e-9)
    # the frames held back by the stall are released late, and read so
    ages = {f.id: released - f.timestamp for f, _, released in got}
    assert ages[100] == pytest.approx(7 / 120) and ages[106] == pytest.approx(1 / 120)


@pytest.mark.parametrize('rate, restart_at', [(0.5, None), (0.0, None), (3.0, 121)])
def test_device_frames_are_never_stamped_after_the_callers_clock(rate, restart_at):
    # a clock slower than real time, a paused one, one that restarts from 0
    got = _device_run(rate, pairs=False, restart_at=restart_at)
    assert all(f.timestamp <= released for f, _, released in got)
    after = [f.timestamp for f, _, _ in got[(restart_at or 0) + 2:]]
    assert all(b >= a for a, b in zip(after, after[1:]))
    if restart_at:     # after the restart, the device's timing again
        np.testing.assert_allclose(np.diff(after), 3 / 120, atol=1e-9)


def _slow_run(path, clocks, n=30):
    """(stamp, the caller's clock right after the frame's release) of a recording played
    in real time on a clock that `clocks(t)` gives after t real seconds."""
    t0 = time.monotonic()

    def clock():
        return clocks(time.monotonic() - t0)
    got = []
    source = make_source('recording', path=path, realtime=True, clock=clock)
    for f in source.frames():
        got.append((f.timestamp, clock()))
        if len(got) == n:
            source.stop()
    return got


@pytest.mark.parametrize('rate', [0.5, 0.0])
def test_a_recording_is_never_stamped_after_a_slower_callers_clock(tmp_path, rate):
    # Before: shifted by the lead only, the stamps ran ahead of a clock at half real time
    # by half the time played (+2 s after 4 s), and the stage ages read negative.
    path = _recording(tmp_path, 30, 0.01)
    got = _slow_run(path, lambda t: 1000.0 + rate * t)
    assert len(got) == 30
    assert all(stamp <= after for stamp, after in got), max(s - a for s, a in got)
    stamps = [s for s, _ in got]
    assert all(b >= a for a, b in zip(stamps, stamps[1:]))


def test_a_recording_follows_a_callers_clock_that_goes_back(tmp_path):
    # a simulator restarted from 0 at 0.1 s: its time again, at the recorded spacing
    path = _recording(tmp_path, 30, 0.01)
    got = _slow_run(path, lambda t: 1000.0 + t if t < 0.1 else t - 0.1)
    assert all(stamp <= after for stamp, after in got)
    after = [s for s, _ in got if s < 500.0]
    assert len(after) >= 15
    np.testing.assert_allclose(np.diff(after[1:]), 0.01, atol=2e-3)
