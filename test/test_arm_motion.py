"""Smoothing and motion of the arm teleop: the One Euro filter, the joint servo and the
trajectory follower it feeds (no ROS, no physics)."""
import copy
import math

import numpy as np
import pytest

from leap_teleop.control.one_euro import OneEuroFilter, smoothing_factor
from leap_teleop.control.servo import JointServo
from leap_teleop.hands.tracker import hand_angles
from leap_teleop.ur10 import kinematics as kin
from leap_teleop.ur10.orientation import hand_rotation
from leap_teleop.ur10.trajectory import TrajectoryError, TrajectoryFollower, _hermite, _hermite_peak


# -- One Euro filter --------------------------------------------------------------------
def test_one_euro_is_a_first_order_low_pass_at_min_cutoff_when_beta_is_zero():
    f = OneEuroFilter(min_cutoff_hz=2.0, beta=0.0)
    f.update([0.0], 0.0)
    y = f.update([1.0], 0.01)
    assert y[0] == pytest.approx(smoothing_factor(2.0, 0.01))
    assert smoothing_factor(2.0, 0.01) == pytest.approx(1 / (1 + 1 / (2 * math.pi * 2.0 * 0.01)))


def test_one_euro_smooths_noise_at_rest_and_follows_motion_with_little_lag():
    rng = np.random.default_rng(0)
    fs = 120.0
    still = OneEuroFilter(0.3, 0.08, 1.0)
    out = [still.update(rng.normal(0, 1.0, 3), k / fs) for k in range(600)]
    assert np.std(np.asarray(out[240:])) < 0.35         # 1 mm noise -> about a third
    moving = OneEuroFilter(0.3, 0.08, 1.0)
    t = np.arange(600) / fs
    path = np.stack([100 * np.sin(2 * math.pi * 0.3 * t)] * 3, 1)
    out = np.asarray([moving.update(p, tk).copy() for p, tk in zip(path, t)])
    fixed = OneEuroFilter(0.3, 0.0, 1.0)                # the same filter without beta
    slow = np.asarray([fixed.update(p, tk).copy() for p, tk in zip(path, t)])
    err = np.sqrt(np.mean((out[120:] - path[120:]) ** 2))
    assert err < 0.2 * np.sqrt(np.mean((slow[120:] - path[120:]) ** 2))


def test_one_euro_ignores_repeated_and_older_times_and_passes_through_when_disabled():
    f = OneEuroFilter(1.0, 0.1, 1.0)
    f.update([0.0], 1.0)
    assert f.update([5.0], 1.0)[0] == 0.0
    assert f.update([5.0], 0.5)[0] == 0.0
    off = OneEuroFilter(0.0, 0.1, 1.0)
    off.update([0.0], 0.0)
    assert off.update([5.0], 0.01)[0] == 5.0
    with pytest.raises(ValueError):
        OneEuroFilter(1.0, -1.0, 1.0)


# -- hand rotation ------------------------------------------------------------------------
def test_hand_rotation_reproduces_the_angles_the_sender_measures():
    rng = np.random.default_rng(1)
    for rotate, turn, swing in rng.uniform(-1.3, 1.3, size=(300, 3)):
        R = hand_rotation(rotate, turn, swing)
        np.testing.assert_allclose(R @ R.T, np.eye(3), atol=1e-12)
        normal, direction = R @ [0.0, -1.0, 0.0], R @ [0.0, 0.0, -1.0]
        np.testing.assert_allclose(hand_angles(normal, direction), (rotate, turn, swing),
                                   atol=1e-9)


def test_hand_rotation_rebuilds_hands_turned_past_the_vertical():
    # Any real hand, also one pointing up and back at the user, where the sender's yaw
    # and pitch both pass pi/2 (and its roll jumps by pi): the same hand comes back.
    rng = np.random.default_rng(2)
    neutral_normal, neutral_direction = np.array([0.0, -1.0, 0.0]), np.array([0.0, 0.0, -1.0])
    back = 0
    for w in rng.normal(size=(300, 3)):
        w *= rng.uniform(0.0, math.pi) / np.linalg.norm(w)
        R = kin.rotation_from_vector(w)
        normal, direction = R @ neutral_normal, R @ neutral_direction
        back += direction[2] > 0
        np.testing.assert_allclose(hand_rotation(*hand_angles(normal, direction)), R, atol=1e-9)
    assert back > 30


# -- servo and follower ---------------------------------------------------------------------
def _follow(servo, goals, dt=0.008, substeps=4, delay_steps=0):
    """Drive a follower with the servo's commands; returns desired (q, qd) per substep."""
    q0 = kin.HOME_Q.copy()
    follower = TrajectoryFollower(q0, kin.MAX_JOINT_SPEED, kin.JOINT_LOWER, kin.JOINT_UPPER)
    t, out, queue = 0.0, [], []
    for goal in goals:
        points = servo.track(t, follower.q, goal)
        queue.append(points)
        if len(queue) > delay_steps:
            follower.command(t, queue.pop(0))
        for _ in range(substeps):
            t += dt / substeps
            q, qd = follower.sample(t)
            out.append((q.copy(), qd.copy()))
    return out


@pytest.mark.parametrize('reach_fast', [False, True])
@pytest.mark.parametrize('delay_steps', [0, 1])
def test_servo_keeps_velocity_continuous_and_acceleration_bounded(delay_steps, reach_fast):
    servo = JointServo(np.full(6, 1.0), np.full(6, math.pi), horizon=0.032, gain=10.0,
                       lower=kin.JOINT_LOWER, upper=kin.JOINT_UPPER, reach_fast=reach_fast)
    t = np.arange(400) * 0.008
    goals = [kin.HOME_Q + 0.4 * np.sin(2 * math.pi * 0.5 * tk) * np.ones(6) for tk in t]
    goals[200:] = [goals[200] + 0.3] * 200                 # and a step
    states = _follow(servo, goals, delay_steps=delay_steps)
    qd = np.asarray([s[1] for s in states])
    accel = np.abs(np.diff(qd, axis=0)) / 0.002
    assert np.max(np.abs(qd)) <= 1.0 + 1e-9
    # A delayed command starts from the controller's state: a small correction only.
    assert np.max(accel) <= math.pi * (1.0 if delay_steps == 0 else 1.6) + 1e-6
    np.testing.assert_allclose(states[-1][0], goals[-1], atol=1e-3)     # gets there


def _teleop_peak_accel(lead, delay, periods=250):
    """Peak desired acceleration of a follower that gets each ArmTeleop command `delay` s
    after it was planned, sampled every 0.5 ms, the palm swinging 100 mm (the arm faster
    than 0.5 rad/s on the way, or AssertionError)."""
    from leap_teleop.ur10.teleop import ArmInput, ArmTeleop, ArmTeleopParams
    t = ArmTeleop(ArmTeleopParams(filter_min_cutoff_hz=0.0, max_joint_speed=1.0,
                                  max_joint_accel=math.pi, command_lead=lead))
    follower = TrajectoryFollower(kin.HOME_Q.copy(), kin.MAX_JOINT_SPEED, kin.JOINT_LOWER,
                                  kin.JOINT_UPPER)
    now, pending, prev, peak, speed = 100.0, [], None, 0.0, 0.0
    for k in range(periods + 50):
        for _ in range(16):
            now += 0.0005
            while pending and pending[0][0] <= now + 1e-12:
                _, points, stamp = pending.pop(0)
                follower.command(now, points, stamp)
            q, qd = follower.sample(now)
            if prev is not None and k >= 50:
                peak = max(peak, float(np.max(np.abs(qd - prev))) / 0.0005)
                speed = max(speed, float(np.max(np.abs(qd))))
            prev = qd.copy()
        flags = {'thumb_up': True} if k < 45 else {'rock': True} if k == 45 else {}
        palm = (100.0 * math.sin(max(0, k - 46) * 0.05), 200.0, 0.0)
        t.on_hand(ArmInput(present=True, palm_mm=palm, stamp=now, **flags), now)
        q, qd = follower.sample(now)
        t.on_joints(q.copy(), now, qd.copy())
        cmd = t.step(now)
        if cmd.points:
            assert cmd.stamp == pytest.approx(now + lead)
            pending.append((now + delay, cmd.points, cmd.stamp))
    assert speed > 0.5, speed                       # the arm did swing
    return peak


def test_a_command_lead_keeps_the_acceleration_bound_through_a_delay_as_long():
    # A command reaching the controller after its stamp joins the last one from where the
    # arm is by then, in less time than planned: faster than max_joint_accel.
    assert _teleop_peak_accel(lead=0.0, delay=0.004) > 2.0 * math.pi
    assert _teleop_peak_accel(lead=0.008, delay=0.004) <= math.pi + 1e-6
    assert _teleop_peak_accel(lead=0.008, delay=0.008) <= math.pi + 1e-6


def test_joint_states_back_while_the_arm_still_brakes_plan_on_from_its_motion():
    # Joint states stall 0.64 s while the arm moves at 0.5 rad/s (1 rad/s and 1 rad/s^2
    # allowed): it is still braking along its last trajectory when they return. The servo planned from
    # rest there (its plan reset by the stall): 100 rad/s^2.
    from leap_teleop.ur10.teleop import HOLDING, ArmInput, ArmTeleop, ArmTeleopParams
    t = ArmTeleop(ArmTeleopParams(filter_min_cutoff_hz=0.0, max_joint_speed=1.0,
                                  max_joint_accel=1.0))
    follower = TrajectoryFollower(kin.HOME_Q.copy(), kin.MAX_JOINT_SPEED, kin.JOINT_LOWER,
                                  kin.JOINT_UPPER)
    now, prev, peak, held, speeds = 100.0, None, 0.0, False, {}
    for k in range(290):
        for _ in range(8):
            now += 0.001
            q, qd = follower.sample(now)
            if prev is not None and k > 46:
                peak = max(peak, float(np.max(np.abs(qd - prev))) / 0.001)
            prev = qd.copy()
        flags = {'thumb_up': True} if k < 45 else {'rock': True} if k == 45 else {}
        palm = (min(150.0, 5.0 * max(0, k - 46)) if k < 110 else 150.0 + 0.5 * (k - 110), 200.0, 0.0)
        t.on_hand(ArmInput(present=True, palm_mm=palm, stamp=now, **flags), now)
        if not 110 <= k < 190:                          # the joint states stall
            q, qd = follower.sample(now)
            t.on_joints(q.copy(), now, qd.copy())
        cmd = t.step(now)
        held = held or t.status.state == HOLDING
        speeds[k] = float(np.max(np.abs(follower.sample(now)[1])))
        if cmd.points:
            follower.command(now, cmd.points, cmd.stamp)
    # cruising when the states stop, still moving (braking) when they return
    assert speeds[109] >= 0.4 and speeds[190] > 0.05, (speeds[109], speeds[190])
    assert held and peak <= 1.0 + 1e-6, peak


def test_joystick_mode_moves_on_from_where_the_arm_is_after_a_joint_state_stall():
    # The stall cleared the target and the joystick fell back to the origin: the arm drove
    # 0.1 m back to where rock had been shown, the hand in the dead zone all along.
    from leap_teleop.ur10.teleop import HOLDING, ArmInput, ArmTeleop, ArmTeleopParams
    t = ArmTeleop(ArmTeleopParams(mode='joystick', filter_min_cutoff_hz=0.0, dead_zone=0.03,
                                  max_tcp_speed=0.1, max_joint_speed=1.0,
                                  max_joint_accel=math.pi))
    follower = TrajectoryFollower(kin.HOME_Q.copy(), kin.MAX_JOINT_SPEED, kin.JOINT_LOWER,
                                  kin.JOINT_UPPER)
    now, held, origin = 100.0, False, kin.fk(kin.HOME_Q)[:3, 3]
    for k in range(480):
        now += 0.008
        flags = {'thumb_up': True} if k < 45 else {'rock': True} if k == 45 else {}
        palm_z = -300.0 if 46 <= k < 171 else 0.0           # 1 s forward, then the dead zone
        t.on_hand(ArmInput(present=True, palm_mm=(0.0, 200.0, palm_z), stamp=now, **flags), now)
        if not 250 <= k < 325:                              # 0.6 s without joint states
            q, qd = follower.sample(now)
            t.on_joints(q.copy(), now, qd.copy())
        cmd = t.step(now)
        held = held or t.status.state == HOLDING
        if k == 249:
            where = kin.fk(follower.sample(now)[0])[:3, 3].copy()
        if cmd.points:
            follower.command(now, cmd.points, cmd.stamp)
    assert held and np.linalg.norm(where - origin) > 0.08
    assert np.linalg.norm(kin.fk(follower.sample(now)[0])[:3, 3] - where) < 0.002


def test_servo_reach_brackets_the_rest_of_its_plan_and_the_turn_back():
    import copy
    servo = JointServo(np.full(6, 1.0), np.full(6, math.pi), horizon=0.032, gain=10.0)
    q0 = kin.HOME_Q.copy()
    servo.track(0.0, q0, q0 + 0.005)          # moving on at 0.05 rad/s
    q1 = servo.state_at(0.032, q0)[0]
    servo.track(0.032, q1, q1 - 0.1)          # then a goal behind: each joint turns back
    lo, hi = servo.reach(0.032, q1)
    probe = copy.deepcopy(servo)
    dense = np.array([probe._planned(probe._plan, tau)[0] for tau in np.linspace(0, 0.2, 4001)])
    np.testing.assert_allclose(lo, dense.min(axis=0), atol=1e-9)
    np.testing.assert_allclose(hi, dense.max(axis=0), atol=1e-9)
    assert np.all(hi > q1 + 1e-6) and np.all(hi > dense[-1] + 1e-6)   # the turning point
    # From later on, only what is still ahead; with no plan, the measured joints.
    later_lo, later_hi = servo.reach(0.032 + 0.05, q1)
    assert np.all(later_hi < hi) and np.all(later_lo >= lo - 1e-12)
    servo.reset()
    assert [list(x) for x in servo.reach(1.0, q1)] == [list(q1), list(q1)]


def _ramp_lag(**servo_args):
    """Velocity lag (s) of the desired joint behind a goal that starts moving at 0.06 rad/s
    (a change the bound allows within one horizon), its velocity fed forward as the teleop
    does."""
    servo = JointServo(np.full(6, 1.0), np.full(6, math.pi), horizon=0.032, gain=10.0,
                       **servo_args)
    t = np.arange(100) * 0.008
    goals = [kin.HOME_Q + 0.06 * max(tk - 0.1, 0.0) for tk in t]
    q0 = kin.HOME_Q.copy()
    follower = TrajectoryFollower(q0, kin.MAX_JOINT_SPEED, kin.JOINT_LOWER, kin.JOINT_UPPER)
    qd = []
    for k, goal in enumerate(goals):
        ff = None if k == 0 else (goal - goals[k - 1]) / 0.008
        follower.command(t[k], servo.track(t[k], follower.q, goal, ff))
        for j in range(4):
            follower.sample(t[k] + 0.002 * (j + 1))
            qd.append(follower.qd[0])
    qd = np.asarray(qd)
    # When the joint first reaches half the goal's speed, after the goal started.
    return (np.argmax(qd >= 0.03) + 1) * 0.002 - 0.1


def test_servo_reaching_fast_cuts_the_velocity_lag_within_the_bound():
    slow, fast = _ramp_lag(), _ramp_lag(reach_fast=True)
    assert fast < slow - 0.005
    # The bound: 0.03 rad/s at pi rad/s^2 takes 9.5 ms.
    assert fast >= 0.03 / math.pi - 1e-9


def test_servo_lead_aims_ahead_of_a_moving_goal():
    servo = JointServo(np.full(6, 1.0), np.full(6, math.pi), horizon=0.032, gain=10.0,
                       lead=0.05)
    plain = JointServo(np.full(6, 1.0), np.full(6, math.pi), horizon=0.032, gain=10.0)
    q, goal, v = kin.HOME_Q.copy(), kin.HOME_Q + 0.001, np.full(6, 0.02)
    ahead = servo.track(0.0, q, goal, v)[0][2]
    here = plain.track(0.0, q, goal, v)[0][2]
    assert np.all(ahead > here)
    # No goal velocity: nothing to extrapolate, the same command.
    np.testing.assert_allclose(servo.track(0.0, q, goal)[0][1], plain.track(0.0, q, goal)[0][1])


def test_servo_stops_by_itself_when_commands_stop():
    servo = JointServo(np.full(6, 1.0), np.full(6, 2.0), horizon=0.032)
    q = kin.HOME_Q.copy()
    for k in range(100):
        points = servo.track(k * 0.008, q, kin.HOME_Q + 1.0)
    (t1, q1, v1), (t2, q2, v2) = points
    assert np.max(np.abs(v1)) > 0.5
    # The last point is rest, reached at the acceleration bound: a silent node's robot stops.
    np.testing.assert_array_equal(v2, np.zeros(6))
    assert t2 - t1 == pytest.approx(np.max(np.abs(v1)) / 2.0)
    np.testing.assert_allclose(q2, q1 + v1 * (t2 - t1) / 2)
    follower = TrajectoryFollower(kin.HOME_Q, kin.MAX_JOINT_SPEED)
    follower.command(0.0, points)
    follower.sample(follower.end_time + 0.01)
    np.testing.assert_array_equal(follower.qd, np.zeros(6))
    np.testing.assert_allclose(follower.q, q2)      # (from rest: stretched in time)


@pytest.mark.parametrize('speed', [0.05, 1e-6])
def test_a_hold_from_motion_lasts_min_duration_too(speed):
    # It lasted |v| / a: 16 ms at the real robot's 0.05 rad/s whatever min_duration said,
    # nanoseconds from a nearly still arm.
    servo = JointServo(np.full(6, speed), np.full(6, 0.5), horizon=0.024)
    q = kin.HOME_Q.copy()
    for k in range(200):
        servo.track(k * 0.008, q, kin.HOME_Q + 1.0)
    rest = servo.stop(200 * 0.008, q, 0.05, np.full(6, math.pi))[-1][1]
    points = servo.stop(200 * 0.008, q, 1.0, np.full(6, math.pi))
    assert points[0][0] == pytest.approx(speed / math.pi) and np.all(points[0][2] == 0.0)
    assert points[-1][0] == 1.0 and np.all(points[-1][2] == 0.0)
    np.testing.assert_array_equal(points[-1][1], rest)              # staying where it stopped
    np.testing.assert_array_equal(points[-1][1], points[-2][1])


def _points_peak_accel(q, v, points):
    """Peak |acceleration| per joint of the cubics a controller runs from (q, v) through
    the points (each cubic's acceleration is linear in time: at its ends)."""
    peak, t = np.zeros(len(q)), 0.0
    for tp, qp, vp in points:
        T = tp - t
        for s in (0.0, 1.0):
            a = ((12 * s - 6) * q + (6 * s - 4) * T * v + (6 - 12 * s) * qp
                 + (6 * s - 2) * T * vp) / (T * T)
            peak = np.maximum(peak, np.abs(a))
        t, q, v = tp, np.asarray(qp), np.asarray(vp)
    return peak


@pytest.mark.parametrize('reach_fast', [False, True])
def test_servo_brakes_within_its_acceleration_short_of_a_joint_limit(reach_fast):
    # Wrist 3 runs into its +2pi limit (its goal moves there and stops on it) while the
    # base turns faster: every point stays inside the limit, no point on it still moves,
    # and the controller's cubics through them keep to max_accel (a point clipped to the
    # limit with its velocity kept asked for 27 rad/s^2). Holds on the way too (braking
    # every joint over the slowest one's time ran it past the limit).
    a, upper = math.pi, kin.JOINT_UPPER[5]
    servo = JointServo(np.full(6, 1.0), np.full(6, a), horizon=0.024, gain=10.0,
                       lower=kin.JOINT_LOWER, upper=kin.JOINT_UPPER, reach_fast=reach_fast)
    q = kin.HOME_Q.copy()
    q[5] = upper - 0.4
    goal, holds = q.copy(), 0
    for k in range(200):
        t = k * 0.008
        goal = goal + np.array([0.008, 0.0, 0.0, 0.0, 0.0, 0.006])
        goal[5] = min(goal[5], upper)
        state = servo.state_at(t, q)
        if k % 10 == 5:
            hold = copy.deepcopy(servo)
            points = hold.stop(t, q, 0.05, np.full(6, a))
            # planned to stop there, not clipped to it
            assert hold.rest(q)[5] <= upper and points[-1][1][5] == pytest.approx(hold.rest(q)[5], abs=1e-12), k
            assert np.max(_points_peak_accel(*state, points)) <= a * (1 + 1e-6), k
            holds += 1
        points = servo.track(t, q, goal, np.array([1.0, 0, 0, 0, 0, 0.75]))
        assert servo.rest(q)[5] <= upper and points[-1][1][5] == pytest.approx(servo.rest(q)[5], abs=1e-12), k
        for _, pq, pv in points:
            assert pq[5] < upper or pv[5] <= 0.0
        assert np.max(_points_peak_accel(*state, points)) <= a * (1 + 1e-6), k
        q = servo.state_at(t + 0.008, q)[0]
    assert q[5] == pytest.approx(upper, abs=1e-3) and holds == 20


@pytest.mark.slow
def test_cubic_peak_speed_in_closed_form_matches_dense_sampling():
    rng = np.random.default_rng(2)
    s = np.linspace(0.0, 1.0, 2001)
    for _ in range(200):
        q0, q1, v0, v1 = rng.normal(size=(4, 6))
        T = rng.uniform(0.01, 2.0)
        # every sample at once: rows are the 2001 points of s, columns the joints
        dense = np.max(np.abs(_hermite(q0, q1, v0, v1, T, s[:, None])[1]), axis=0)
        np.testing.assert_allclose(np.maximum(_hermite_peak(q0, q1, v0, v1, T), np.abs(v0)),
                                   dense, rtol=1e-4, atol=1e-6)


def test_follower_interpolates_quintic_segments_with_accelerations():
    f = TrajectoryFollower(np.zeros(1), [10.0])
    f.command(0.0, [(1.0, [1.0], [0.0], [0.0])])
    q, qd = f.sample(0.5)
    assert q[0] == pytest.approx(0.5) and qd[0] == pytest.approx(1.875)   # 30/16
    assert f.qdd[0] == pytest.approx(0.0, abs=1e-9)
    q, _ = f.sample(0.25)
    assert q[0] == pytest.approx(10 * 0.25 ** 3 - 15 * 0.25 ** 4 + 6 * 0.25 ** 5)


def test_a_follower_takes_both_joint_limits_or_neither():
    for lower, upper in ((kin.JOINT_LOWER, None), (None, kin.JOINT_UPPER)):
        with pytest.raises(ValueError, match='both'):
            TrajectoryFollower(kin.HOME_Q, kin.MAX_JOINT_SPEED, lower, upper)
    follower = TrajectoryFollower(kin.HOME_Q, kin.MAX_JOINT_SPEED, kin.JOINT_LOWER, kin.JOINT_UPPER)
    beyond = np.array(kin.HOME_Q, dtype=float)
    beyond[0] = kin.JOINT_UPPER[0] + 1e-6
    with pytest.raises(TrajectoryError, match='joint limits'):
        follower.command(0.0, [(1.0, beyond, None)])


def _moving_follower():
    """One joint at 1 rad/s (its limit), 0.5 s into a 2 s ramp."""
    f = TrajectoryFollower(np.zeros(1), [1.0])
    f.command(0.0, [(2.0, [2.0], [1.0])])
    f.sample(0.5)
    return f


def test_a_plan_made_ahead_is_followed_as_the_command_planned_at_once():
    points = [(0.2, [0.6], [0.5], [0.1]), (0.6, [0.8], [0.2], [-0.2]), (1.0, [0.9], [0.0], [0.0])]
    ahead, at_once = _moving_follower(), _moving_follower()
    plan = ahead.plan(points)                  # before the state it will start from
    ahead.sample(0.7)
    at_once.sample(0.7)
    assert ahead.command(0.7, plan, 0.65) == pytest.approx(at_once.command(0.7, points, 0.65))
    for t in np.linspace(0.7, 2.0, 27):
        np.testing.assert_allclose(ahead.sample(t), at_once.sample(t), atol=1e-12)


def test_a_first_point_whose_accelerations_the_arm_cannot_follow_replans_the_next_segment():
    # The plan assumed the first point's accelerations (2 rad/s^2); from a joint moving at
    # +1 rad/s, turning to -1 rad/s in 0.1 s is too fast for them: the cubic is followed
    # instead and the second segment must start at rest in acceleration, not at 2.
    f = _moving_follower()
    points = [(0.1, [0.5], [-1.0], [2.0]), (0.6, [0.2], [-0.5], [0.5]), (1.2, [0.0], [0.0], [0.0])]
    plan = f.plan(points)
    assert plan.segments[1][6][0] == 2.0
    f.command(0.5, plan)
    first, second, third = f.segments
    assert first[6] is None and first[7] is None               # let go: the cubic
    assert second[6][0] == 0.0                                 # replanned from that
    assert third[2:4] == (plan.segments[2][2], plan.segments[2][3])
    assert third[1] - third[0] == pytest.approx(plan.segments[2][1] - plan.segments[2][0])
