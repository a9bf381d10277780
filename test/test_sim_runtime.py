"""The simulators' loop helpers: pacing to the wall clock, sim-time schedules, snapshot paths."""
import os

import pytest

from leap_teleop.sim_runtime import (
    MAX_LAG_S,
    Every,
    RealtimePacer,
    SendGate,
    pace_factor,
    snapshot_path,
)


class ManualClock:
    def __init__(self):
        self.now, self.sleeps = 100.0, []

    def __call__(self):
        return self.now

    def sleep(self, s):
        self.sleeps.append(s)
        self.now += s


@pytest.mark.parametrize('factor', [0.0, 0.5, 2.5, 4.0])
def test_any_speed_but_real_time_needs_sim_time(factor):
    # At 4x without /use_sim_time, the other nodes (wall time) saw the arm move at 4 times
    # its speed limits; nothing said so.
    assert pace_factor(factor, use_sim_time=True) == (factor, None)
    run_at, warning = pace_factor(factor, use_sim_time=False)
    assert run_at == 1.0 and 'without /use_sim_time' in warning
    assert pace_factor(1.0, use_sim_time=False) == (1.0, None)


def test_pacer_sleeps_until_the_wall_clock_catches_up_with_sim_time():
    clock = ManualClock()
    pacer = RealtimePacer(2.0, sim_time=10.0, clock=clock, sleep=clock.sleep)
    assert pacer.wait(11.0) == pytest.approx(0.5)      # 1 s of sim at x2 = 0.5 s wall
    assert clock.sleeps == [pytest.approx(0.5)]
    clock.now += 0.2                                    # the steps took 0.2 s of wall
    assert pacer.wait(11.6) == pytest.approx(0.1)       # due 0.8 s after the start
    assert clock.now == pytest.approx(100.8)


def test_pacer_behind_restarts_instead_of_sprinting():
    clock, behind = ManualClock(), []
    pacer = RealtimePacer(1.0, sim_time=0.0, clock=clock, sleep=clock.sleep,
                          on_behind=behind.append)
    clock.now += 0.3                                    # a little late: no sleep, no restart
    assert pacer.wait(0.1) == pytest.approx(-0.2) and pacer.t0_sim == 0.0
    assert behind == []
    clock.now += 2.0                                    # far behind (loaded machine)
    assert pacer.wait(0.2) < -0.5
    assert pacer.t0_sim == 0.2 and pacer.t0_wall == clock.now
    assert behind == [pytest.approx(2.1)]               # and says by how much
    assert pacer.wait(0.3) == pytest.approx(0.1)        # paced from the restart
    assert clock.sleeps == [pytest.approx(0.1)]


def test_a_simulation_that_is_the_clock_never_sprints_its_time_on():
    # Under /use_sim_time the simulation's time is everyone's: after a 0.1 s stall it runs
    # on from where it is (its consumers see no jump); in wall time it makes the stall good.
    for sim_time, sprint in ((True, False), (False, True)):
        clock = ManualClock()
        pacer = RealtimePacer(1.0, sim_time=0.0, max_lag=MAX_LAG_S[sim_time], clock=clock,
                              sleep=clock.sleep)
        clock.now += 0.1 + 0.004                          # stalled during a 4 ms step
        pacer.wait(0.004)
        steps = 0
        while not clock.sleeps:                           # steps run back to back
            clock.now += 0.001
            steps += 1
            pacer.wait(0.004 * (steps + 1))
        assert (steps > 10) == sprint, (sim_time, steps)


def test_pacer_at_factor_zero_only_yields():
    clock = ManualClock()
    pacer = RealtimePacer(0.0, sim_time=0.0, clock=clock, sleep=clock.sleep)
    assert pacer.wait(1000.0) == 0.0 and clock.sleeps == [0]


def test_every_ticks_once_per_period_without_bursts():
    every = Every(0.1, start=0.0)
    ticks = [t / 100 for t in range(0, 101) if every.due(t / 100)]
    assert len(ticks) == 11 and ticks[:3] == [0.0, 0.1, 0.2]
    late = Every(0.1, start=0.0)
    assert late.due(0.0) and late.due(0.55)             # a late step: one tick, not five,
    assert late.due(0.56)                               # and the schedule restarts from it
    assert not late.due(0.6) and late.due(0.66)


def test_send_gate_waits_a_period_and_opens_when_time_goes_back():
    gate = SendGate(0.2)
    assert gate.open(5.0)
    gate.sent(5.0)
    assert not gate.open(5.1) and gate.open(5.2)
    assert gate.open(1.0)                               # the clock went back (a reset)
    assert not SendGate(None).open(5.0)


def test_snapshot_path_prefers_the_folder_then_ros_home(tmp_path, monkeypatch):
    folder = tmp_path / 'new' / 'pictures'
    path = snapshot_path(str(folder), 'ardrone', 12.3456)
    assert path == str(folder / 'ardrone_0012.346.png') and folder.is_dir()
    monkeypatch.setenv('ROS_HOME', str(tmp_path / 'ros_home'))
    assert snapshot_path('', 'ur10_sim', 1.0) == os.path.join(str(tmp_path), 'ros_home',
                                                              'ur10_sim_0001.000.png')
    monkeypatch.delenv('ROS_HOME')
    name = 'test_sim_runtime_%d' % os.getpid()
    path = snapshot_path('', name, 0.0)
    try:
        assert os.path.dirname(path) == '/tmp'
    finally:
        os.remove(path)


def test_a_snapshot_never_takes_the_name_of_an_earlier_one(tmp_path):
    # Named by sim time alone, a picture replaced an earlier run's taken at the same sim
    # time (each run starts at 0), or one taken in the same physics step.
    earlier = tmp_path / 'ur10_sim_0002.000.png'
    earlier.write_bytes(b'an earlier run')
    paths = [snapshot_path(str(tmp_path), 'ur10_sim', 2.0) for _ in range(3)]
    assert [os.path.basename(p) for p in paths] == [
        'ur10_sim_0002.000_1.png', 'ur10_sim_0002.000_2.png', 'ur10_sim_0002.000_3.png']
    assert earlier.read_bytes() == b'an earlier run'
    assert all(os.path.exists(p) for p in paths)     # each name is taken once returned


def test_callers_at_the_same_time_get_names_of_their_own(tmp_path):
    import threading
    paths, start = [], threading.Barrier(8)

    def take():
        start.wait()
        paths.append(snapshot_path(str(tmp_path), 'ardrone', 0.5))
    threads = [threading.Thread(target=take) for _ in range(8)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert len(set(paths)) == 8 and str(tmp_path / 'ardrone_0000.500.png') in paths


def test_a_name_whose_picture_never_came_is_given_back(tmp_path):
    from leap_teleop.sim_runtime import release_snapshot_path
    path = snapshot_path(str(tmp_path), 'ur10_sim', 1.0)
    release_snapshot_path(path)                      # nothing written: no empty file left
    assert not os.path.exists(path)
    written = snapshot_path(str(tmp_path), 'ur10_sim', 1.0)
    assert written == path
    with open(written, 'wb') as f:
        f.write(b'\x89PNG\r\n\x1a\n')
    release_snapshot_path(written)                   # cut short (a renderer killed while
    assert not os.path.exists(written)               # writing it): no picture, given back
    written = snapshot_path(str(tmp_path), 'ur10_sim', 1.0)
    from PIL import Image
    Image.new('RGB', (4, 3)).save(written, format='PNG')
    release_snapshot_path(written)                   # a whole picture in it is kept
    assert os.path.exists(written)
    release_snapshot_path(str(tmp_path / 'never_there.png'))
