"""ur10_sim against extreme trajectories: accelerations beyond what the arm can follow are
refused naming the joint, legal ones never carry a joint past its points, a maximal
trajectory with accelerations costs no more than one without, a start far ahead is warned
about while the arm finishes what it was doing and then holds, and each command topic's type
is watched."""
import math
import sys

import numpy as np
import pytest
import rospy
from test_ur10_cell_runner import RosTimeStub

from leap_teleop.params import check_params
from leap_teleop.ros.ur10_conversions import MAX_TRAJECTORY_POINTS
from leap_teleop.ur10 import kinematics as kin
from leap_teleop.ur10.cell import POINT_ACCEL_RAMP_S, UR10Cell
from leap_teleop.ur10.cell_runner import RUNNER_PARAMS, CellRunner
from leap_teleop.ur10.config import load_config
from leap_teleop.ur10.trajectory import TrajectoryError, TrajectoryFollower

ARM = 'ur10_1'
HOME = np.array(kin.HOME_Q)
ZERO = np.zeros(6)
PAN_ACCEL_LIMIT = kin.MAX_JOINT_SPEED[0] / POINT_ACCEL_RAMP_S      # 10 pi rad/s^2


def pan(x):
    return HOME + [x, 0, 0, 0, 0, 0]


@pytest.fixture
def events():
    return {'rejected': [], 'warned': []}


@pytest.fixture
def runner(events):
    p = check_params(RUNNER_PARAMS, {'realtime_factor': 0.0})
    r = CellRunner(p, True, RosTimeStub(), lambda *why: events['rejected'].append(why),
                   lambda *what: events['warned'].append(what))
    yield r
    r.close()


@pytest.mark.integration
@pytest.mark.parametrize('kind, acc, joint, value', [
    ('arm', [1000.0, 0, 0, 0, 0, 0], 'shoulder_pan_joint', '1000'),
    ('arm', [1e300, 0, 0, 0, 0, 0], 'shoulder_pan_joint', '1e+300'),
    ('arm', [0, 0, 0, 0, 0, -50.0], 'wrist_3_joint', '-50'),
    ('gripper', [100.0], 'finger_joint', '100'),
])
def test_an_acceleration_beyond_the_arm_refuses_the_command_naming_joint_and_value(
        runner, events, kind, acc, joint, value):
    runner.cell.run(0.2)
    q0, _, g0, _ = runner.cell.joint_state(ARM)
    point = (0.5, pan(0.5), ZERO, acc) if kind == 'arm' else (0.5, [0.4], [0.0], acc)
    runner.queue(ARM, kind, [point], 0.0)
    runner.step()
    assert len(events['rejected']) == 1
    arm, rejected_kind, why = events['rejected'][0]
    assert (arm, rejected_kind) == (ARM, kind)
    assert joint in str(why) and value in str(why) and 'acceleration' in str(why)
    runner.cell.run(1.0)                                     # the arm holds
    q1, _, g1, _ = runner.cell.joint_state(ARM)
    assert np.max(np.abs(q1 - q0)) < 1e-4 and abs(g1 - g0) < 1e-3


@pytest.mark.integration
@pytest.mark.parametrize('acc', [PAN_ACCEL_LIMIT * 0.99, PAN_ACCEL_LIMIT * 0.5])
def test_a_legal_acceleration_never_carries_the_arm_past_its_points(acc):
    """The audit's command with an acceleration the sim takes, pulling on past the point:
    the pan joint goes from 0 to 0.5 and stops there, then back to 0 (pulled on the other
    way) without overshooting either way."""
    with UR10Cell('ur10_cell.yaml', visuals=False) as cell:
        cell.run(0.2)
        seen = []
        for target, a in ((0.5, acc), (0.0, -acc)):
            cell.command_arm(ARM, [(0.5, pan(target), ZERO, [a, 0, 0, 0, 0, 0])])
            for _ in range(int(1.5 / cell.dt)):
                cell.step()
                seen.append(cell.joint_state(ARM)[0])
            assert cell.joint_state(ARM)[0][0] == pytest.approx(target, abs=2e-3)
        seen = np.array(seen)
        assert -2e-3 < seen[:, 0].min() and seen[:, 0].max() < 0.5 + 2e-3
        assert np.max(np.abs(seen[:, 1:] - HOME[1:])) < 2e-3


def test_quintic_segments_stay_within_their_points_and_the_speed_limits():
    """Random points with legal accelerations: the desired position never leaves the range
    of the positions (widened by how far the cubic with the same velocities reaches), and
    the desired speed stays within the limits."""
    rng = np.random.default_rng(11)
    vmax = kin.MAX_JOINT_SPEED
    amax = vmax / POINT_ACCEL_RAMP_S
    for _ in range(40):
        f = TrajectoryFollower(HOME, vmax, kin.JOINT_LOWER, kin.JOINT_UPPER, amax, kin.JOINT_NAMES)
        n = 4
        times = np.cumsum(rng.uniform(0.05, 2.0, n))
        qs = np.clip(HOME + rng.uniform(-1.5, 1.5, (n, 6)), kin.JOINT_LOWER, kin.JOINT_UPPER)
        vs = rng.uniform(-1, 1, (n, 6)) * vmax * rng.choice([0.0, 0.3, 1.0])
        vs[-1] = 0.0
        accs = rng.uniform(-1, 1, (n, 6)) * amax
        end = f.command(0.0, [(t, q, v, a) for t, q, v, a in zip(times, qs, vs, accs)])
        bounds = []
        for seg in f.segments:
            spread = 4 / 27 * (seg[1] - seg[0]) * (np.abs(seg[4]) + np.abs(seg[5]))
            bounds.append((seg[0], seg[1], np.minimum(seg[2], seg[3]) - spread - 1e-9,
                           np.maximum(seg[2], seg[3]) + spread + 1e-9))
        for t in np.linspace(0.0, end + 0.1, 3000):
            q, qd = f.sample(t)
            assert np.all(np.abs(qd) <= vmax * 1.02), (t, qd / vmax)
            for t0, t1, lo, hi in bounds:
                if t0 <= t <= t1:
                    assert np.all(q >= lo) and np.all(q <= hi), (t, q, lo, hi)
        np.testing.assert_allclose(f.q, qs[-1])
        assert not f.qd.any()


def _calls(fn):
    """How many Python and builtin calls fn() makes: work, independent of the machine."""
    count = [0]

    def profile(_frame, event, _arg):
        if event in ('call', 'c_call'):
            count[0] += 1
    sys.setprofile(profile)
    try:
        fn()
    finally:
        sys.setprofile(None)
    return count[0]


def test_a_long_trajectory_with_accelerations_costs_about_what_it_costs_without():
    """Accepting and following 2000 points with accelerations takes no more calls than
    without (~1.1x here; evaluating each quintic at 20 instants one by one took ~14x and froze
    the sim's physics for 10 s on a 10000-point command)."""
    n = 2000
    times = 0.01 * np.arange(1, n + 1)
    work = {}
    for with_acc in (False, True):
        f = TrajectoryFollower(HOME, kin.MAX_JOINT_SPEED, kin.JOINT_LOWER, kin.JOINT_UPPER,
                               kin.MAX_JOINT_SPEED / POINT_ACCEL_RAMP_S, kin.JOINT_NAMES)
        q = HOME + 0.2 * np.sin(times)[:, None]
        v = 0.2 * np.cos(times)[:, None] * np.ones(6)
        a = -0.2 * np.sin(times)[:, None] * np.ones(6)
        points = [(t, q[k], v[k]) + ((a[k],) if with_acc else ()) for k, t in enumerate(times)]
        accept = _calls(lambda: f.command(0.0, points))
        assert (f.segments[1][6] is not None) == with_acc          # quintics with them
        follow = _calls(lambda: [f.sample(k / 240.0) for k in range(1, 2401)])
        work[with_acc] = accept, follow
    assert work[True][0] <= 1.5 * work[False][0], work
    assert work[True][1] <= 1.5 * work[False][1], work


def test_a_maximal_trajectory_with_accelerations_is_accepted_quickly():
    """A loose sanity bound (the audit's 10000-point command took 9 s)."""
    import time
    f = TrajectoryFollower(HOME, kin.MAX_JOINT_SPEED, kin.JOINT_LOWER, kin.JOINT_UPPER,
                           kin.MAX_JOINT_SPEED / POINT_ACCEL_RAMP_S, kin.JOINT_NAMES)
    points = [(0.01 * (k + 1), HOME, ZERO, ZERO) for k in range(MAX_TRAJECTORY_POINTS)]
    t0 = time.process_time()
    f.command(0.0, points)
    assert time.process_time() - t0 < 3.0


def test_a_segment_too_fast_is_stretched_in_a_few_tries_to_within_a_tenth_of_its_shortest(monkeypatch):
    # Growing by 10 % a try took 48 tries a segment: a 10,000-point command of segments
    # too fast held the physics 4.6 s (6.5 s with accelerations).
    from leap_teleop.ur10 import trajectory
    tries = []
    real = trajectory._peak_ratio
    monkeypatch.setattr(trajectory, '_peak_ratio', lambda seg, vmax: tries.append(1) or real(seg, vmax))
    f = TrajectoryFollower(HOME, kin.MAX_JOINT_SPEED, kin.JOINT_LOWER, kin.JOINT_UPPER)
    v = np.full(6, 2.0)
    points = [(0.01 * (k + 1), HOME + (0.5 if k % 2 else -0.5), v) for k in range(200)]
    end = f.command(0.0, points)
    assert len(tries) <= 200 * 13
    # Every segment keeps the limits, and is no more than 10 % longer than it must be.
    for seg in f.segments:
        T = seg[1] - seg[0]
        assert real(seg, f.vmax) <= 1.0 + 1e-9
        assert real(trajectory._retimed(seg, T / 1.1), f.vmax) > 1.0
    assert end > 2.0


@pytest.mark.parametrize('with_accelerations', [False, True], ids=['cubic', 'quintic'])
def test_no_segment_swings_a_joint_past_its_limit(with_accelerations):
    # Both points inside the elbow's +-pi, at +3 then -3 rad/s: the cubic's desired elbow
    # reached 3.75 rad (the quintic was already held at the limit).
    f = TrajectoryFollower(HOME, kin.MAX_JOINT_SPEED, kin.JOINT_LOWER, kin.JOINT_UPPER)
    q = HOME.copy()
    q[2] = 3.0
    f.command(0.0, [(1.0, q, ZERO)])
    v = np.zeros(6)
    v[2] = 3.0
    extra = (ZERO,) if with_accelerations else ()
    f.command(1.0, [(1.5, q, v) + extra, (2.0, q, -v) + extra])
    elbow = [f.sample(t)[0][2] for t in np.linspace(1.0, 3.0, 2001)]
    assert max(elbow) <= math.pi and max(elbow) == pytest.approx(math.pi)


@pytest.mark.parametrize('cell_age', [1.0, 5.0])
def test_a_command_stamped_in_the_past_is_judged_alike_however_old_the_cell(cell_age):
    # Stamped 3 s ago with points 1 and 2 s after it: on a cell 1 s old its start (-2) was
    # read as 'now' and the whole command played; on one 5 s old it was refused.
    f = TrajectoryFollower(HOME, kin.MAX_JOINT_SPEED, kin.JOINT_LOWER, kin.JOINT_UPPER)
    f.sample(cell_age)
    with pytest.raises(TrajectoryError, match='ends in the past'):
        f.command(cell_age, [(1.0, pan(0.1), None), (2.0, pan(0.2), None)],
                  start_time=cell_age - 3.0)
    assert not f.active


def test_a_later_start_lets_the_current_motion_finish_then_holds_at_rest():
    f = TrajectoryFollower(HOME, kin.MAX_JOINT_SPEED, kin.JOINT_LOWER, kin.JOINT_UPPER)
    f.command(0.0, [(2.0, pan(1.0), ZERO)])
    q_before, qd_before = (x.copy() for x in f.sample(1.0))
    assert qd_before[0] > 0.5
    f.command(1.0, [(1.0, pan(-1.0), None)], start_time=1.0 + 2 ** 31)
    # Under way as before (the JTC keeps the old trajectory until the new one starts) ...
    q, qd = f.sample(1.0 + 1 / 240)
    assert qd[0] == pytest.approx(qd_before[0], rel=0.01) and q[0] > q_before[0]
    # ... to its end, where it holds at rest until then.
    for t in (2.0, 3.0, 1e6):
        q, qd = f.sample(t)
        np.testing.assert_allclose(q, pan(1.0))
        assert not qd.any() and not f.qdd.any()
    q, _ = f.sample(1.0 + 2 ** 31 + 1.0)
    np.testing.assert_allclose(q, pan(-1.0))
    # A start ahead with nothing under way: at rest where it is.
    f.command(0.0, [(1.0, pan(0.5), ZERO)], start_time=50.0)
    for t in (1.0, 49.9):
        q, qd = f.sample(t)
        np.testing.assert_allclose(q, pan(-1.0))
        assert not qd.any()


def test_a_start_cut_into_the_current_motion_takes_it_over_without_a_jump():
    f = TrajectoryFollower(HOME, kin.MAX_JOINT_SPEED, kin.JOINT_LOWER, kin.JOINT_UPPER)
    f.command(0.0, [(2.0, pan(1.0), ZERO)])
    f.sample(0.5)
    f.command(0.5, [(1.0, pan(0.2), ZERO)], start_time=1.0)
    q_old = HOME[0] + 1.0 * (3 * 0.5 ** 2 - 2 * 0.5 ** 3)          # the old cubic at t = 1
    q, qd = f.sample(1.0)
    assert q[0] == pytest.approx(q_old) and qd[0] == pytest.approx(0.75)
    q, qd = f.sample(1.0 + 1e-6)
    assert q[0] == pytest.approx(q_old, abs=1e-5) and qd[0] == pytest.approx(0.75, rel=1e-3)
    q, qd = f.sample(2.0)
    assert q[0] == pytest.approx(0.2) and not qd.any()


@pytest.mark.integration
def test_a_command_stamped_far_ahead_is_warned_and_the_moving_arm_finishes_then_holds(
        runner, events):
    runner.queue(ARM, 'arm', [(4.0, pan(1.0), None)], 0.0)
    runner.step()
    runner.cell.run(1.0)
    runner.queue(ARM, 'arm', [(1.0, pan(-1.0), None)], float(2 ** 31 - 1))
    runner.step()
    assert not events['rejected']
    (arm, kind, what), = events['warned']
    assert (arm, kind) == (ARM, 'arm') and 'starts in 2147482' in what
    runner.cell.run(4.0)
    q, qd = runner.cell.joint_state(ARM)[:2]
    assert q[0] == pytest.approx(1.0, abs=1e-3) and np.max(np.abs(qd)) < 1e-3
    runner.cell.run(2.0)
    assert runner.cell.joint_state(ARM)[0][0] == pytest.approx(1.0, abs=1e-3)
    # A start a second ahead says nothing; a command now replaces both.
    runner.queue(ARM, 'arm', [(1.0, pan(0.5), None)], RosTimeStub.now + 1.0)
    runner.queue(ARM, 'arm', [(1.0, HOME, None)], 0.0)
    runner.step()
    assert len(events['warned']) == 1
    runner.cell.run(2.0)
    assert runner.cell.joint_state(ARM)[0][0] == pytest.approx(HOME[0], abs=1e-3)


class WarnLog:
    def __init__(self):
        self.lines = []

    def warn(self, key, fmt, *args):
        self.lines.append((key, fmt % args))


def test_each_command_topic_says_what_to_publish_when_it_carries_another_type(monkeypatch):
    from leap_teleop.ros import cell_state_topics
    monkeypatch.setattr(rospy, 'Timer', lambda *args, **kwargs: None)   # no master: no timer
    log = WarnLog()
    watch = cell_state_topics.command_type_watch(load_config('ur10_dual_cell.yaml'), log)
    assert sorted(w.topic for w in watch.topics) == [
        '/ur10_%d/%s' % (i, t) for i in (1, 2) for t in ('arm_controller/command',
                                                          'gripper/command')]
    monkeypatch.setattr(rospy, 'get_published_topics', lambda: [
        ['/ur10_1/arm_controller/command', 'std_msgs/String'],
        ['/ur10_2/gripper/command', 'trajectory_msgs/JointTrajectory']])
    watch.check()
    (key, line), = log.lines
    assert line.startswith('ur10_sim: /ur10_1/arm_controller/command carries std_msgs/String')
    assert 'trajectory_msgs/JointTrajectory' in line and 'wrist_3_joint' in line


@pytest.mark.integration
def test_commands_arriving_while_a_step_applies_others_wait_for_the_next_step(runner):
    """So a burst of long commands cannot hold the physics (and joint_states) until its
    end: the ten-command audit burst kept one step busy for all ten."""
    command_arm = runner.cell.command_arm
    arriving = [pan(0.1), pan(0.2)]

    def slow_command(arm, points, start):
        if arriving:                                 # the next one arrives meanwhile
            runner.queue(ARM, 'arm', [(1.0, arriving.pop(0), None)], 0.0)
        return command_arm(arm, points, start)
    runner.cell.command_arm = slow_command
    runner.queue(ARM, 'arm', [(1.0, pan(0.3), None)], 0.0)
    runner.step()
    assert len(runner.pending) == 1
    runner.step()
    assert len(runner.pending) == 1
    runner.step()
    assert not runner.pending
    runner.cell.run(1.5)
    assert runner.cell.joint_state(ARM)[0][0] == pytest.approx(0.2, abs=1e-3)
