"""The arm node's loop without ROS: callbacks wake the step at once, changes are applied
between steps, and the status goes out on a change (logged) or at its rate."""
import math
import threading
import time

import numpy as np
import pytest

from leap_teleop.ur10 import kinematics as kin
from leap_teleop.ur10.kinematics import HOME_Q
from leap_teleop.ur10.teleop import DISARMED, HOLDING, TRACKING, ArmInput, ArmTeleopParams
from leap_teleop.ur10.teleop_runner import HAND_SLACK, ArmTeleopRunner, StatusReporter


def test_a_hand_wakes_the_step_before_the_period_ends():
    runner = ArmTeleopRunner(ArmTeleopParams(), rate=0.5)          # a 2 s period
    stop, ticks = threading.Event(), []
    thread = threading.Thread(target=runner.run, args=(time.monotonic, stop.is_set,
                                                       lambda *a: ticks.append(a)))
    thread.start()
    try:
        runner.on_joints(HOME_Q, time.monotonic())
        time.sleep(0.2)
        assert ticks == []                                          # waiting for the period
        sent = time.monotonic()
        assert not runner.on_hand(ArmInput(present=True, palm_mm=(0.0, 200.0, 0.0), stamp=sent), sent)
        deadline = time.monotonic() + 1.0
        while not ticks and time.monotonic() < deadline:
            time.sleep(0.01)
        assert ticks and ticks[0][2] - sent < 0.5, ticks
        cmd, snapshot, _ = ticks[0]
        assert snapshot == (DISARMED, 'waiting for thumbs-up', False)
        assert cmd.points is None                                   # disarmed: nothing moves
    finally:
        stop.set()
        runner.wake.set()
        thread.join(5.0)
    assert not thread.is_alive()


def test_a_bad_hand_is_refused_with_a_reason_and_retune_reaches_the_teleop():
    runner = ArmTeleopRunner(ArmTeleopParams(), rate=100.0)
    why = runner.on_hand(ArmInput(present=True, palm_mm=(float('nan'), 0.0, 0.0), stamp=1.0), 1.0)
    assert why and runner.teleop.status.rejected_inputs == 1
    runner.retune({'max_joint_speed': 0.02})
    assert runner.teleop.p.max_joint_speed == 0.02


def test_a_corrupt_joint_state_is_refused_so_that_the_node_can_say_so():
    runner = ArmTeleopRunner(ArmTeleopParams(), rate=100.0)
    assert runner.on_joints(HOME_Q, 1.0)
    bad = list(HOME_Q)
    bad[2] = float('nan')
    assert not runner.on_joints(bad, 1.1)
    bad[2] = 1e6
    assert not runner.on_joints(bad, 1.2)


def test_the_status_goes_out_on_a_change_or_at_its_rate():
    said = []
    r = StatusReporter(2.0, lambda t: said.append(('info', t)), lambda t: said.append(('warn', t)))
    armed = ('armed', 'thumbs-up', False)
    assert r.due(armed, 10.0) and said == [('info', 'armed (thumbs-up)')]
    assert not r.due(armed, 10.1) and not r.due(armed, 10.49)      # 2 Hz: not yet
    assert r.due(armed, 10.5) and len(said) == 1                     # due, not a change
    assert r.due((HOLDING, 'input stalled', True), 10.6)             # a change: at once
    assert said[-1] == ('warn', 'holding (input stalled)')
    assert r.due((TRACKING, 'input back', True), 10.61) and said[-1][0] == 'info'


def test_a_state_that_flips_many_times_a_second_is_logged_at_most_every_two_seconds():
    # A target on the edge of reach: holding (no IK) and tracking, 5 changes a second for
    # 10 s. Before: 51 log lines. The status still goes out on every change.
    said = []
    r = StatusReporter(2.0, lambda t: said.append(t), lambda t: said.append(t))
    states = [(HOLDING, 'no IK solution', True), (TRACKING, 'target reachable again', True)]
    assert all(r.due(states[k % 2], 20.0 + 0.2 * k) for k in range(50))
    assert 8 <= len(said) <= 12, said
    assert said[0] == 'holding (no IK solution)'
    assert any(t.startswith('holding (no IK solution) (') and 'similar suppressed' in t for t in said), said


def test_the_params_summary_names_what_an_operator_checks():
    assert ArmTeleopParams(max_joint_speed=0.05).summary() == (
        'mode imitation, orientation fixed, gripper binary, max joint speed 0.05 rad/s, '
        'acceleration %.3g rad/s^2' % ArmTeleopParams().max_joint_accel)


def _count_steps(hand_interval, hands, rate=10.0):
    """Steps of a runner at `rate` fed `hands` hands `hand_interval` s apart, then 0.5 s
    of no hands: (steps while hands came, steps after, gaps between hands (and before the
    first) long enough for a timer step of the new loop: a loaded machine's late hands)."""
    runner = ArmTeleopRunner(ArmTeleopParams(), rate=rate)
    stop, ticks = threading.Event(), []
    thread = threading.Thread(target=runner.run, args=(time.monotonic, stop.is_set,
                                                       lambda *a: ticks.append(a[2])))
    runner.on_joints(HOME_Q, time.monotonic())
    thread.start()
    try:
        time.sleep(0.01)
        start = sent = time.monotonic()
        late = 0
        for k in range(hands):
            time.sleep(max(0.0, start + (k + 1) * hand_interval - time.monotonic()))
            now = time.monotonic()
            late += now - sent > HAND_SLACK / rate
            sent = now
            runner.on_hand(ArmInput(present=True, palm_mm=(0.0, 200.0, 0.0), stamp=now), now)
        time.sleep(0.005)
        during = len(ticks)
        time.sleep(0.5)
        after = len(ticks) - during
    finally:
        stop.set()
        runner.wake.set()
        thread.join(5.0)
    return during, after, late


def test_a_hand_stream_near_the_rate_steps_once_per_hand():
    # Hands 110 ms apart against a 100 ms period: a timer restarted at each hand would
    # end 10 ms before the next hand and step twice per hand.
    during, after, late = _count_steps(0.110, 10)
    # each hand, plus at most a timer step for the first and for each hand that came late
    assert 10 <= during <= 11 + late, (during, late)
    # hands stop: the timer steps at the rate again (0.5 s: the first 150 ms, then 100)
    assert 2 <= after <= 5, after


@pytest.mark.parametrize('command_horizon, rate', [(0.004, 125.0), (0.024, 20.0)])
def test_commands_last_until_the_next_step_whatever_the_command_horizon(command_horizon, rate):
    # The hand steps 40 mm (0.1 m of TCP) and holds, the loop steps at its rate. Each
    # command gains a * horizon of speed and brakes to rest after it: shorter than the
    # period, the arm moved 7.6 (4 ms at 125 Hz) or 41 mm (24 ms at 20 Hz) in 2 s.
    params = ArmTeleopParams(max_joint_speed=1.0, max_joint_accel=math.pi,
                             command_horizon=command_horizon, filter_min_cutoff_hz=0.0)
    teleop = ArmTeleopRunner(params, rate=rate).teleop
    now, q, start = 100.0, HOME_Q.copy(), kin.fk(HOME_Q)[:3, 3]
    for k in range(int(2.5 * rate)):
        now += 1.0 / rate
        flags = {'thumb_up': True} if k < 0.4 * rate else {'rock': True} if k < 0.5 * rate else {}
        palm = (0.0, 200.0, 0.0 if k < 0.5 * rate else -40.0)
        teleop.on_hand(ArmInput(present=True, palm_mm=palm, stamp=now, **flags), now)
        q = teleop._servo.state_at(now, q)[0]            # a controller following it
        teleop.on_joints(q, now)
        teleop.step(now)
    assert teleop.status.state == TRACKING
    target = np.array(teleop.status.target)
    assert np.linalg.norm(target - start) == pytest.approx(0.1, abs=1e-6)
    assert np.linalg.norm(kin.fk(q)[:3, 3] - target) < 0.002


@pytest.mark.parametrize('rate', [10.0, 20.0])
def test_a_slow_loop_woken_by_a_fast_hand_plans_over_the_steps_it_takes(rate):
    # A 120 Hz hand wakes a step every 8 ms: every command planned over 1.5 periods of a
    # slow ~rate (150 ms at 10 Hz) ramped the velocity over that long, and a 100 mm step
    # overshot by 11 mm, crossing the target four times (1.2 mm at ~rate 125 Hz).
    def overshoot(loop_rate):
        params = ArmTeleopParams(max_joint_speed=1.0, max_joint_accel=math.pi, filter_min_cutoff_hz=0.0)
        teleop = ArmTeleopRunner(params, rate=loop_rate).teleop
        now, q, start = 100.0, HOME_Q.copy(), kin.fk(HOME_Q)[:3, 3]
        reach = []
        for k in range(360):                    # 3 s of hand frames at 120 Hz, a step after each
            now += 1.0 / 120.0
            flags = {'thumb_up': True} if k < 48 else {'rock': True} if k < 60 else {}
            palm = (0.0, 200.0, 0.0 if k < 60 else -40.0)
            teleop.on_hand(ArmInput(present=True, palm_mm=palm, stamp=now, **flags), now)
            q = teleop._servo.state_at(now, q)[0]
            teleop.on_joints(q, now)
            teleop.step(now)
            if k >= 60:
                target = np.array(teleop.status.target)
                direction = (target - start) / np.linalg.norm(target - start)
                reach.append(float(np.dot(kin.fk(q)[:3, 3] - start, direction)))
        return max(reach) - 0.1
    assert overshoot(rate) <= overshoot(125.0) + 1e-4


def test_the_step_intervals_kept_stay_few_after_the_clock_jumps_back_or_stands_still():
    # After a simulator restart (or on a stopped clock) none aged out: one more a step,
    # all scanned every step.
    teleop = ArmTeleopRunner(ArmTeleopParams(), rate=20.0).teleop
    q, now = HOME_Q.copy(), 3600.0
    for now in (3600.0 + 0.05 * k for k in range(100)):
        teleop.on_joints(q, now)
        teleop.step(now)
    for k in range(2000):                       # /clock back to 0, then a stopped clock
        now = min(k / 130.0, 5.0)
        teleop.on_joints(q, now)
        teleop.step(now)
    assert len(teleop._step_intervals) <= 256
