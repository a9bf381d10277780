"""Input age: the capture stamp behind each command, its age over a window (no ROS)."""
import math

import numpy as np
import pytest

from leap_teleop.control.input_age import InputAgeWindow
from leap_teleop.drone.pilot import DronePilot, PilotInput, PilotParams
from leap_teleop.ur10 import kinematics as kin
from leap_teleop.ur10.teleop import ArmInput, ArmTeleop, ArmTeleopParams


def test_window_percentiles_over_the_last_seconds_only():
    w = InputAgeWindow(window_s=10.0)
    for k in range(100):                       # 100 s ago: 1 s old inputs, outside
        w.add(float(k) * 0.01, k * 0.01 - 1.0)
    for k in range(1, 101):                    # the last 1 s: ages 1..100 ms
        w.add(100.0 + k * 0.01, 100.0 + k * 0.01 - k * 0.001)
    p50, p99, n = w.summary(101.0)
    assert n == 100
    assert p50 == pytest.approx(np.percentile(np.arange(1, 101) * 0.001, 50))
    assert p99 == pytest.approx(np.percentile(np.arange(1, 101) * 0.001, 99))
    assert w.last_stamp == pytest.approx(101.0 - 0.1)
    values = dict(w.diagnostic_values(101.0))
    assert values['input age p50 (ms, last 10 s)'] == '%.1f' % (p50 * 1000)
    assert values['input age samples'] == '100'


def test_window_ignores_unstamped_input_and_forgets_a_clock_jump_back():
    w = InputAgeWindow(window_s=5.0)
    assert w.add(10.0, 0.0) is None and w.add(10.0, math.nan) is None
    assert w.summary(10.0) == (None, None, 0)
    assert dict(w.diagnostic_values(10.0))['input age p99 (ms, last 5 s)'] == 'n/a'
    assert w.add(10.0, 9.99) == pytest.approx(0.01)
    assert w.summary(2.0) == (None, None, 0)          # /clock restarted: not this stream's
    with pytest.raises(ValueError):
        InputAgeWindow(window_s=0.0)


def hand(stamp, **kw):
    kw.setdefault('present', True)
    kw.setdefault('palm_mm', (0.0, 200.0, 0.0))
    return ArmInput(stamp=stamp, **kw)


def test_arm_commands_and_status_carry_the_capture_stamp_of_their_hand():
    # The grasp goes with the first command (no wait for the tool): one command, both.
    t = ArmTeleop(ArmTeleopParams(arm_hold_s=0.0, filter_min_cutoff_hz=0.0, gripper_wait_s=0.0))
    t.on_joints(kin.HOME_Q)
    now = 100.0
    for h in (hand(99.95, thumb_up=True), hand(99.96, rock=True)):
        now += 0.01
        t.on_hand(h, now)
        t.step(now)
    now += 0.01
    t.on_hand(hand(99.97, palm_mm=(0.0, 230.0, 0.0), pinch=True), now)
    cmd = t.step(now)
    assert cmd.points is not None and cmd.gripper is not None
    assert cmd.input_stamp == 99.97 and t.status.input_stamp == 99.97
    # A watchdog hold acts on no input: it carries none, the status keeps the last one.
    cmd = t.step(now + 0.3)
    assert cmd.points is not None and cmd.input_stamp == 0.0
    assert t.status.input_stamp == 99.97
    # A fist's hold is that hand's.
    t.on_hand(hand(100.3, fist=True), now + 0.31)
    cmd = t.step(now + 0.31)
    assert t.status.state == 'disarmed' and cmd.input_stamp == 100.3


def test_pilot_twists_and_gesture_commands_carry_the_capture_stamp():
    pilot = DronePilot(PilotParams(navdata_timeout=10.0))
    pilot.on_navdata(2, 0, 0.0)
    pilot.on_hand(PilotInput(True, (0.0, 0.2, 0.0), stamp=0.05), 0.06)
    pilot.on_gesture('unfold', True, 0.07, stamp=0.055)
    cmd = pilot.queue.popleft()
    assert cmd.kind == 'takeoff' and cmd.input_stamp == 0.055
    pilot.on_navdata(3, 1000, 0.1)
    pilot.on_hand(PilotInput(True, (0.0, 0.2, -0.1), stamp=0.11), 0.12)
    cmd = pilot.queue.popleft()
    assert cmd.kind == 'twist' and cmd.twist[0] > 0 and cmd.input_stamp == 0.11
    pilot.watchdog(0.5)                                   # the watchdog's hover: no input
    cmd = pilot.queue.popleft()
    assert cmd.kind == 'twist' and cmd.twist == (0.0,) * 6 and cmd.input_stamp == 0.0


def test_stage_ages_keep_one_window_per_stage_with_its_own_keys():
    from leap_teleop.control.input_age import StageAges
    ages = StageAges(('recognized', 'published'), window_s=10.0)
    for k in range(100):
        stamp = 50.0 + k * 0.01
        ages.add('recognized', stamp + 0.002, stamp)
        ages.add('published', stamp + 0.003 + (0.01 if k == 99 else 0.0), stamp)
    ages.add('not a stage', 51.0, 50.0)               # ignored, not a crash
    ages.add('published', 51.0, 0.0)                  # unstamped: no sample
    summary = ages.summary(51.5)
    p50, p99, n = summary['recognized']
    assert n == 100 and p50 == pytest.approx(0.002) and p99 == pytest.approx(0.002)
    p50, p99, n = summary['published']
    assert n == 100 and p50 == pytest.approx(0.003) and 0.003 < p99 < 0.013
    values = dict(ages.diagnostic_values(51.5))
    assert values['input age (recognized) p50 (ms, last 10 s)'] == '2.0'
    assert values['input age (published) samples'] == '100'
    assert 'input stamp of the last command' not in values     # a command's key only
    assert dict(ages.diagnostic_values(70.0))['input age (published) samples'] == '0'


def test_stage_ages_are_written_and_read_on_two_threads_without_a_lock():
    import threading
    import time

    from leap_teleop.control.input_age import StageAges
    ages = StageAges(('published',), window_s=1000.0)
    n = 4000                                  # within a window's 5000 samples
    done = threading.Event()
    reads = []

    def writer():
        try:
            for k in range(n):
                ages.add('published', 1.0 + k * 1e-4 + 0.005, 1.0 + k * 1e-4)
                if k % 500 == 0:              # wait for a read mid-stream, not only after
                    seen, deadline = len(reads), time.monotonic() + 10.0
                    while len(reads) == seen and time.monotonic() < deadline:
                        time.sleep(0.0005)
        finally:
            done.set()                        # a reader that failed must not hang the run
    t = threading.Thread(target=writer, daemon=True)
    t.start()
    while not done.is_set():                  # the reader drains while the writer appends
        reads.append(ages.summary(10.0)['published'][2])
    t.join()
    assert ages.summary(10.0)['published'][2] == n         # nothing lost, nothing twice
    assert reads == sorted(reads)
    assert len({r for r in reads if 0 < r < n}) >= 4       # it did read while they wrote


def test_a_full_window_keeps_its_newest_samples():
    w = InputAgeWindow(window_s=100.0, max_samples=64)
    for k in range(1000):
        w.add(10.0 + k * 0.01, 10.0 + k * 0.01 - (0.001 if k < 936 else 0.002))
    ages = w.ages(20.0)
    assert len(ages) == 64 and np.all(ages == pytest.approx(0.002))
    assert w.summary(20.0)[2] == 64


def test_an_event_beside_the_stream_is_judged_by_its_latency_and_not_taken():
    from leap_teleop.control.input_check import InputStream
    s = InputStream(max_age=0.25, gap=1.0)
    assert 'no stamped Hand' in s.judge_beside(50.0, 100.0)       # no baseline: this clock
    assert s.judge_beside(99.9, 100.0) is None and s.judge_beside(0.0, 100.0) is None
    assert s.check(40.0, 100.0) is None                            # a bag's hands: 60 s back
    assert s.judge_beside(40.01, 100.02) is None                   # its events with them
    assert s.judge_beside(39.5, 100.02).startswith('late: arrived 0.520 s')
    assert s.judge_beside(41.0, 100.02).startswith('stamped 0.980 s ahead')
    assert s.last_stamp == 40.0                                    # nothing was taken
    assert InputStream(max_age=0.0, gap=1.0).judge_beside(1.0, 100.0) is None
