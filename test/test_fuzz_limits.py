"""Bad input and property-based fuzzing: whatever arrives, nothing raises and no command
leaves the joint, workspace, gripper or tilt limits; any accepted watchdog setting still
hovers, lands and disarms. Also the stream checks (out of order, late, restarts, backlog
bursts), the pilot's worker and the live sources' queue behind the fault rostests
(test/fault_*.test).

Example budget (per `make test` run): 3000 + 2500 + 3000 + 150 + 100 here, on top of 3000
in test_arm_teleop.py, 1500 in test_params.py and ~400 in test_gesture_recognizer.py /
test_classify_frames.py. The two event-sequence tests draw a seed and build their events
with numpy (test/fuzz_values.py): half the time of drawing every value through hypothesis.
"""
import logging
import math

import numpy as np
import pytest
from fuzz_values import either, wild, within
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from leap_teleop.control.input_check import InputStream
from leap_teleop.drone.pilot import DronePilot, PilotInput, PilotParams
from leap_teleop.hands.frame import Finger, TrackedHand
from leap_teleop.hands.tracker import HandTracker
from leap_teleop.ros import hand_conversions
from leap_teleop.ur10 import kinematics as kin
from leap_teleop.ur10.teleop import ARMED, DISARMED, HOLDING, TRACKING, ArmInput, ArmTeleop, ArmTeleopParams
from leap_teleop.ur10.trajectory import TrajectoryFollower

HOME = kin.HOME_Q.copy()


# -- the stream checks --------------------------------------------------------------------
def test_stream_drops_out_of_order_and_late_messages_but_not_a_constant_offset():
    s = InputStream(max_age=0.25, gap=0.2)
    assert s.check(50.0, 100.0) is None           # 50 s offset: a replayed bag, accepted
    assert s.check(50.01, 100.01) is None
    assert 'out of order' in s.check(50.005, 100.02)
    # A backlog: messages keep coming (no silence) but fall ever further behind.
    verdicts = [s.check(50.02 + 0.01 * k, 100.02 + 0.09 * k) for k in range(10)]
    assert verdicts[:4] == [None] * 4 and all('late' in v for v in verdicts[4:])
    # A silence, then the same timeline still late: a stalled source's backlog, refused.
    assert 'late' in s.check(50.2, 101.2)
    # Only a real restart (fresh stamps, or a bag replayed again) starts a new stream.
    assert s.check(51.45, 101.5) is None
    assert s.check(1.0, 102.0) is None


def test_found_one_future_stamp_blocks_the_stream_for_a_gap_only():
    # Before: after one message stamped 1e6 s ahead, every later one was refused as out of
    # order (the arm disarmed, the drone landed) while valid input kept coming.
    s = InputStream(max_age=0.25, gap=0.2)
    for k in range(50):
        assert s.check(10.0 + 0.01 * k, 10.005 + 0.01 * k) is None
    assert s.check(1e6, 10.5) is None
    verdicts = [s.check(10.5 + 0.01 * k, 10.505 + 0.01 * k) for k in range(50)]
    refused = [v for v in verdicts if v is not None]
    assert 19 <= len(refused) <= 21 and verdicts[21:] == [None] * 29
    assert all(v.startswith('out of order') for v in refused)
    # one message out of order among ones in order is refused alone, as before
    assert 'out of order' in s.check(10.0, 11.0) and s.check(11.0, 11.005) is None
    # A stale second publisher (5 s behind) stays refused, while the live one publishes
    # and after it stops: no stamp leapt ahead, so its stream never takes over.
    now = 11.005
    for k in range(100):
        now += 0.005
        live = s.check(now - 0.005, now) if k < 50 else None
        assert live is None and 'out of order' in s.check(now - 5.0, now)


def test_found_a_first_message_stamped_far_ahead_blocks_for_a_gap_only():
    # Before: with no earlier message to judge it by, a first message stamped 1e6 s ahead
    # set the stream's order, and every valid message after it was refused until a silence.
    for max_age in (0.25, 0.0):                 # with the lateness check on and off
        s = InputStream(max_age=max_age, gap=0.2)
        assert s.check(1e6, 10.0) is None
        verdicts = [s.check(10.0 + 0.01 * k, 10.005 + 0.01 * k) for k in range(50)]
        refused = [v for v in verdicts if v is not None]
        assert 19 <= len(refused) <= 21 and verdicts[21:] == [None] * 29
        assert all(v.startswith('out of order') for v in refused)
    # A first message stamped within max_age of this clock is taken as any other: one live
    # message, then only an older publisher (a live pause after a reconnection), and the
    # older one stays refused.
    for max_age in (0.25, 0.0):
        s = InputStream(max_age=max_age, gap=0.2)
        assert s.check(10.0, 10.005) is None
        now = 10.005
        for k in range(100):
            now += 0.005
            live = s.check(now - 0.005, now) if k % 50 == 49 else None
            assert live is None and 'out of order' in s.check(now - 5.0, now)


def test_found_backlog_burst_after_a_stall_passes_only_its_last_max_age():
    # Before: the silence of the stall reset the stream, so a 2 s old backlog was accepted.
    s = InputStream(max_age=0.25, gap=0.2)
    for k in range(100):                       # 100 Hz, 5 ms latency
        assert s.check(10.0 + 0.01 * k, 10.005 + 0.01 * k) is None
    # Stall 2 s, then the 200 messages captured meanwhile arrive within 0.1 s.
    verdicts = [(stamp, s.check(stamp, 13.0 + 0.0005 * k))
                for k, stamp in enumerate(11.0 + 0.01 * np.arange(200))]
    passed = [stamp for stamp, why in verdicts if why is None]
    assert passed and all(13.1 - stamp <= 0.25 + 0.005 + 0.1 for stamp in passed)
    assert len(passed) <= 30 and all('late' in why for _, why in verdicts[:150])


def test_stream_restarts_after_silence_or_a_clock_jump():
    s = InputStream(max_age=0.25, gap=0.2)
    assert s.check(10.0, 10.0) is None
    assert s.check(5.0, 10.5) is None             # silence 0.5 s > gap: a new stream (bag again)
    assert s.check(5.01, 10.51) is None
    assert s.check(0.5, 0.5) is None              # the clock jumped back (sim restarted)
    assert s.check(0.0, 0.51) is not None         # unstamped after stamped: out of order
    assert InputStream(0.0, 0.2).check(1.0, 500.0) is None   # lateness check off


# -- arm: faults ---------------------------------------------------------------------------
def hand(**kw):
    kw.setdefault('present', True)
    kw.setdefault('palm_mm', (0.0, 200.0, 0.0))
    return ArmInput(**kw)


class Arm:
    """An ArmTeleop fed like the node feeds it: hand + joints + step per period."""

    def __init__(self, **params):
        params.setdefault('arm_hold_s', 0.0)     # arming on one message (the hold: test_arm_teleop)
        self.t = ArmTeleop(ArmTeleopParams(filter_min_cutoff_hz=0.0, rotation_min_cutoff_hz=0.0, **params))
        self.now = 100.0
        self.q = HOME.copy()

    def period(self, h=None, joints=True, dt=0.008):
        self.now += dt
        if h is not None:
            h.stamp = h.stamp or self.now
            self.t.on_hand(h, self.now)
        if joints:
            self.t.on_joints(self.q, self.now)
        cmd = self.t.step(self.now)
        # A perfect controller: the joints follow the plan, reported or not.
        planned = self.t._servo.planned_at(self.now + dt)
        if planned is not None:
            self.q = planned
        return cmd

    def arm_with_origin(self):
        self.period(hand(thumb_up=True))
        self.period(hand(rock=True))
        assert self.t.status.state == TRACKING


def test_lost_joint_states_disarm_without_commanding_the_old_pose():
    a = Arm()
    a.arm_with_origin()
    assert a.period(hand(palm_mm=(0.0, 260.0, 0.0))).q is not None
    # joint_timeout (0.5 s = 62.5 periods) holds: nothing is commanded to an unknown pose.
    cmds = [a.period(hand(palm_mm=(0.0, 260.0, 0.0)), joints=False) for _ in range(80)]
    assert a.t.status.state == HOLDING and 'no joint states' in a.t.status.reason
    assert not any(c.q is not None or c.points is not None for c in cmds[63:])
    # joint_loss_after (3 s) without states: the robot is gone, still nothing commanded.
    reasons = []
    for _ in range(320):
        cmd = a.period(hand(palm_mm=(0.0, 260.0, 0.0)), joints=False)
        assert cmd.q is None and cmd.points is None
        reasons.append((a.t.status.state, a.t.status.reason))
    assert reasons[-1][0] == DISARMED
    first = next(i for i, r in enumerate(reasons) if r[0] == DISARMED)
    assert reasons[first][1] == 'no joint states for 3.00 s'
    assert 80 + first == pytest.approx(3.0 / 0.008, abs=2)
    # The simulator comes back at home: nothing moves until thumbs-up + rock, and the
    # new origin is the new pose (no jump back to the old target).
    a.q = HOME.copy()
    for _ in range(10):
        assert a.period(hand(palm_mm=(0.0, 260.0, 0.0))).q is None
    a.period(hand(thumb_up=True, palm_mm=(0.0, 260.0, 0.0)))
    assert a.t.status.state == ARMED
    a.period(hand(rock=True, palm_mm=(0.0, 260.0, 0.0)))
    cmd = a.period(hand(palm_mm=(0.0, 260.0, 0.0)))
    np.testing.assert_allclose(cmd.q, HOME, atol=1e-6)


def test_a_joint_state_stall_holds_then_resumes_from_the_current_pose_without_a_jump():
    a = Arm()
    a.arm_with_origin()
    for _ in range(20):
        a.period(hand(palm_mm=(0.0, 260.0, -40.0)))
    assert a.t.status.state == TRACKING
    q_before = a.q.copy()
    # A loaded simulator sends no joint states for 1 s while the hand moves 80 mm; the
    # robot runs each trajectory it gets to its end (rest).
    cmds = []
    for i in range(125):
        cmds.append(a.period(hand(palm_mm=(80.0 * i / 125, 260.0, -40.0)), joints=False))
        if cmds[-1].points is not None:
            a.q = cmds[-1].points[-1][1].copy()
    assert a.t.status.state == HOLDING and a.t.status.origin_set
    assert not any(c.q is not None for c in cmds[63:])
    q_stopped = a.q.copy()             # where the last trajectory before the hold left it
    assert np.max(np.abs(q_stopped - q_before)) > 0.02
    # States come back (the robot where it stopped): tracking resumes, no jump.
    cmd = a.period(hand(palm_mm=(80.0, 260.0, -40.0)))
    assert a.t.status.state == TRACKING, a.t.status.reason
    assert 'joint states back after' in a.t.status.reason
    assert 'same origin' in a.t.status.reason           # the hand's mapping is kept
    # The target is where the hand says; the trajectory starts at rest from the current
    # joints and accelerates within the limit: no step.
    h, acc = a.t.p.command_horizon, a.t.p.max_joint_accel
    assert np.max(np.abs(cmd.points[0][1] - q_stopped)) <= 0.5 * acc * h * h + 1e-9
    assert np.max(np.abs(cmd.points[0][2])) <= acc * h + 1e-9
    cmd = a.period(hand(palm_mm=(80.0, 280.0, -40.0)))    # and follows the hand from there
    assert cmd.q is not None and a.t.status.state == TRACKING


def test_joint_states_back_at_another_pose_after_a_stall_disarm_without_a_command():
    a = Arm(max_joint_speed=1.0, max_joint_accel=math.pi)     # well away from home
    a.arm_with_origin()
    for _ in range(30):
        a.period(hand(palm_mm=(60.0, 300.0, -60.0)))
    for _ in range(125):                             # 1 s without states (< joint_loss_after)
        a.period(hand(palm_mm=(60.0, 300.0, -60.0)), joints=False)
    assert a.t.status.state == HOLDING
    a.q = HOME.copy()                                # a simulator restarted at home
    cmd = a.period(hand(palm_mm=(60.0, 300.0, -60.0)))
    assert a.t.status.state == DISARMED and 'another pose' in a.t.status.reason
    assert 'rad beyond where its last trajectory could have left it' in a.t.status.reason
    assert cmd.q is None and cmd.points is None
    for _ in range(5):
        assert a.period(hand(palm_mm=(60.0, 300.0, -60.0))).q is None


@pytest.mark.parametrize('beyond, speed, resumes', [
    (0.05, 0.6, True), (-0.05, 0.6, False), (0.11, 0.6, False), (-0.01, 0.6, True),
    (0.2, 5.0, False)])          # a spike brakes from max_joint_speed: 0.16 rad at most
def test_a_robot_still_moving_when_states_stopped_may_coast_its_braking_distance(beyond, speed,
                                                                                resumes):
    # The last state reports joint 1 turning at 0.6 rad/s (a simulator that was catching up
    # when it stalled): it can coast 0.6^2 / (2 pi) = 0.057 rad on (+ 0.02), not back.
    a = Arm(max_joint_speed=1.0, max_joint_accel=math.pi)
    a.arm_with_origin()
    for _ in range(10):                    # the hand at the origin: the servo plans no motion
        a.period(hand())
    a.now += 0.008
    a.t.on_joints(a.q, a.now, [speed, 0, 0, 0, 0, 0])
    a.t.step(a.now)
    for _ in range(70):
        a.period(hand(), joints=False)
    assert a.t.status.state == HOLDING
    a.q = a.q + [beyond, 0, 0, 0, 0, 0]
    a.period(hand())
    if resumes:
        assert a.t.status.state == TRACKING and 'joint states back' in a.t.status.reason
    else:
        assert a.t.status.state == DISARMED and 'another pose' in a.t.status.reason


def test_a_fist_during_a_joint_state_stall_disarms_at_once_without_a_command():
    a = Arm()
    a.arm_with_origin()
    for _ in range(70):
        a.period(hand(palm_mm=(0.0, 260.0, 0.0)), joints=False)
    assert a.t.status.state == HOLDING
    cmd = a.period(hand(fist=True), joints=False)
    assert a.t.status.state == DISARMED and a.t.status.reason == 'fist'
    assert cmd.q is None and cmd.points is None
    for _ in range(5):                                 # states back: still disarmed
        assert a.period(hand(palm_mm=(0.0, 260.0, 0.0))).q is None
    assert a.t.status.state == DISARMED


def test_a_hand_lost_longer_than_disarm_after_during_a_joint_state_stall_disarms():
    # The hand's watchdog runs during a joint stall too: joints and hand back after 2 s
    # (hand silent for all of it) once tracked on from the old origin, no thumbs-up.
    a = Arm()
    a.arm_with_origin()
    a.period(hand(palm_mm=(0.0, 260.0, 0.0)))
    cmds, reasons = [], set()
    for _ in range(250):                                           # 2 s: no states, no hand
        cmds.append(a.period(None, joints=False))
        reasons.add((a.t.status.state, a.t.status.reason))
    assert not any(c.q is not None or c.points is not None for c in cmds[63:])
    assert (DISARMED, 'no hand input for 1.00 s (watchdog)') in reasons
    assert a.t.status.state == DISARMED
    for _ in range(5):
        assert a.period(hand(palm_mm=(100.0, 260.0, 0.0))).q is None
    assert a.t.status.state == DISARMED and not a.t.status.origin_set


@pytest.mark.parametrize('hand_first', [False, True])
def test_a_hand_stall_overlapping_a_joint_state_stall_re_anchors_on_its_return(hand_first):
    # Whichever stalled first, the hand was not followed meanwhile: back 100 mm further on
    # (0.25 m of target), it re-anchors instead of driving the arm there.
    a = Arm()
    a.arm_with_origin()
    for _ in range(5):
        a.period(hand(palm_mm=(0.0, 260.0, 0.0)))
    before = np.array(a.t.status.target)       # where the hand's last message puts it
    periods = [(True, False)] * 20 + [(False, False)] * 70 if hand_first else \
        [(False, True)] * 20 + [(False, False)] * 70
    for joints, with_hand in periods:
        a.period(hand(palm_mm=(0.0, 260.0, 0.0)) if with_hand else None, joints=joints)
    assert a.t.status.state == HOLDING
    held = kin.fk(a.q)[:3, 3]
    cmd = a.period(hand(palm_mm=(100.0, 260.0, 0.0)))
    assert a.t.status.state == TRACKING and 'origin re-anchored' in a.t.status.reason
    # none of the motion unseen is driven (the arm's lag behind that target is caught up)
    np.testing.assert_allclose(a.t.status.target, before, atol=1e-9)
    assert np.linalg.norm(kin.fk(cmd.q)[:3, 3] - held) < 1e-3


class FollowedArm(Arm):
    """Arm in a closed loop with the simulated controller, which starts every trajectory
    from its own desired state; the robot goes on following its commands while its joint
    states are withheld. `executed`: its desired (t, q, qd) every millisecond."""

    def __init__(self, **params):
        super().__init__(**params)
        self.jtc = TrajectoryFollower(HOME, kin.MAX_JOINT_SPEED, kin.JOINT_LOWER, kin.JOINT_UPPER)
        self.executed = []

    def period(self, h=None, joints=True, dt=0.008):
        for k in range(1, 9):
            t = self.now + dt * k / 8
            self.executed.append((t, *(x.copy() for x in self.jtc.sample(t))))
        self.now += dt
        if h is not None:
            h.stamp = h.stamp or self.now
            self.t.on_hand(h, self.now)
        q, qd = self.jtc.sample(self.now)
        if joints:
            self.t.on_joints(q.copy(), self.now, qd.copy())
        cmd = self.t.step(self.now)
        if cmd.points is not None:
            self.jtc.command(self.now, cmd.points, cmd.stamp)
        return cmd


@pytest.mark.parametrize('limits', [(1.0, math.pi), (0.05, 0.5)])
@pytest.mark.parametrize('event', ['fist', 'rock', 'target back in reach'])
def test_joint_states_stopped_before_a_hold_ended_are_not_where_the_arm_rests(event, limits):
    # States stop while the arm moves; a hold (an IK hold, or a fist before a re-arm) brings
    # it to rest meanwhile; then, within joint_timeout of the last state: a fist, a rock with
    # the hand still, or the target back in reach. Planned from the last state, the
    # controller drove the arm back there: 125 mm at up to 2 rad/s against 1.
    speed, accel = limits
    a = FollowedArm(max_joint_speed=speed, max_joint_accel=accel, arm_hold_s=0.3)
    a.t.on_joints(HOME, a.now, np.zeros(6))
    for _ in range(40):
        a.period(hand(thumb_up=True))
    a.period(hand(rock=True))
    assert a.t.status.state == TRACKING
    sweep = [(-min(1.28 * k, 100.0), 200.0, 0.0) for k in range(200)]
    for palm in sweep[:50]:
        a.period(hand(palm_mm=palm))
    assert np.abs(a.executed[-1][2]).max() > 0.5 * speed          # moving
    last = a.now                                                   # the last joint state
    out = (-400.0, 200.0, -400.0)                                  # out of reach
    if event == 'rock':
        a.period(hand(palm_mm=sweep[50], fist=True), joints=False)
        while a.now < last + 0.36:
            a.period(hand(palm_mm=sweep[50], thumb_up=True), joints=False)
        assert a.t.status.state == ARMED
    else:
        for palm in sweep[50:75]:
            a.period(hand(palm_mm=palm), joints=False)
        a.period(hand(palm_mm=out), joints=False)
        assert a.t.status.state == HOLDING and 'no IK solution' in a.t.status.reason
    while a.now < last + 0.44:
        a.period(hand(palm_mm=sweep[50] if event == 'rock' else out), joints=False)
    at = a.now
    rest = a.jtc.sample(at)[0]
    assert not np.abs(a.jtc.sample(at)[1]).any()                  # the hold has ended
    h = {'fist': hand(palm_mm=out, fist=True), 'rock': hand(palm_mm=sweep[50], rock=True),
         'target back in reach': hand(palm_mm=sweep[75])}[event]
    a.period(h, joints=False)
    while a.now < last + 0.49:                                     # < joint_timeout
        a.period(ArmInput(**{**vars(h), 'rock': False, 'stamp': 0.0}), joints=False)
    for _ in range(60):
        a.period(ArmInput(**{**vars(h), 'rock': False, 'stamp': 0.0}))
    assert a.t.status.state == (DISARMED if event == 'fist' else TRACKING), a.t.status.reason
    after = [(t, q, qd) for t, q, qd in a.executed if t > at]
    assert max(float(np.abs(qd).max()) for _, _, qd in after) <= speed + 1e-9
    # nothing jumps back: within the first horizon the joints move no further from the
    # hold's rest than max_joint_speed allows, and the fist and the still hand's rock
    # leave the arm where it rests
    horizon = a.t.p.command_horizon
    moved = max(float(np.abs(q - rest).max()) for t, q, _ in after if t <= at + horizon)
    assert moved <= speed * horizon + 1e-9
    if event != 'target back in reach':       # (the rock's origin: IK rounding only)
        assert max(float(np.abs(q - rest).max()) for _, q, _ in after) < 1e-6


@pytest.mark.parametrize('limits', [(1.0, math.pi), (0.3, 0.5)])
def test_joint_states_back_where_a_hold_after_their_stop_rested_resume(limits):
    # The same IK hold, the states back after a stall: where the hold rested is where the
    # robot could have got to (it was disarmed as 'another pose').
    a = FollowedArm(max_joint_speed=limits[0], max_joint_accel=limits[1])
    a.arm_with_origin()
    for k in range(50):
        a.period(hand(palm_mm=(-min(1.28 * k, 100.0), 200.0, 0.0)))
    for k in range(50, 75):
        a.period(hand(palm_mm=(-min(1.28 * k, 100.0), 200.0, 0.0)), joints=False)
    for _ in range(100):
        a.period(hand(palm_mm=(-400.0, 200.0, -400.0)), joints=False)
    assert a.t.status.state == HOLDING and 'no joint states' in a.t.status.reason
    a.period(hand(palm_mm=(-400.0, 200.0, -400.0)))
    assert a.t.status.state == HOLDING and 'no IK solution' in a.t.status.reason


def test_clock_jumping_back_disarms_and_forgets_the_robot():
    a = Arm()
    a.arm_with_origin()
    a.now = 1.0                                       # /clock restarted
    assert a.period(hand(palm_mm=(0.0, 300.0, 0.0))).q is None
    assert a.t.status.state == DISARMED and not a.t.status.origin_set
    a.period(hand(palm_mm=(0.0, 300.0, 0.0)))
    a.period(hand(thumb_up=True))
    assert a.t.status.state == ARMED                  # new stream accepted, re-arm works


def test_late_and_out_of_order_hand_messages_are_counted_and_ignored():
    a = Arm()
    a.arm_with_origin()
    target = a.t.status.target
    a.period(hand(palm_mm=(0.0, 400.0, 0.0), stamp=a.now - 0.5))   # held up 0.5 s
    a.period(hand(palm_mm=(0.0, 400.0, 0.0), stamp=a.now - 0.05))  # older than the last
    assert a.t.status.rejected_inputs == 2
    np.testing.assert_allclose(a.t.status.target, target, atol=1e-9)


@pytest.mark.parametrize('value, expected', [(5.0, 0.8), (1e9, 0.8), (0.81, 0.8), (-3.0, None)])
def test_pinch_values_outside_0_to_0_8_keep_the_gripper_in_range(value, expected):
    a = Arm(gripper_mode='proportional')
    a.arm_with_origin()
    cmd = a.period(hand(pinch=True, pinch_value=value))
    assert cmd.gripper == expected          # None: clamped to 0 = already open, nothing sent


# -- fuzz: recognizer + tracker + message builder -------------------------------------------
@st.composite
def raw_hands(draw):
    """A hand from a few draws (cheap to generate): seeded values in +-600, with the
    fields picked by a bit mask replaced by one special value (NaN, inf, 1e9, 0)."""
    rng = np.random.default_rng(draw(st.integers(0, 2 ** 32 - 1)))
    special = draw(st.sampled_from([math.nan, math.inf, -math.inf, 1e9, 0.0, -1.0]))
    mask = draw(st.integers(0, 2 ** 10 - 1))
    n = draw(st.sampled_from([0, 2, 5, 5]))

    def value(bit, shape=(3,)):
        v = rng.uniform(-600, 600, shape).reshape(-1)
        if mask >> bit & 1:
            v[rng.integers(0, v.size)] = special
        return v if shape != () else float(v[0])

    fingers = tuple(Finger(tip=value(0), direction=value(1),
                           extended=[None, True, False][int(rng.integers(0, 3))],
                           mcp=value(2), pip=None, dip=value(3) if mask & 1 else None)
                    for _ in range(n))
    return TrackedHand(side='right', palm_position=value(4), palm_velocity=value(5),
                palm_normal=value(6), direction=value(7),
                grab_strength=value(8, ()) / 600 + 0.5, pinch_strength=value(9, ()) / 600 + 0.5,
                confidence=float(rng.uniform(-0.5, 1.5)), fingers=fingers)


@settings(max_examples=3000, deadline=None, suppress_health_check=list(HealthCheck))
@given(st.lists(st.tuples(raw_hands(), st.floats(0.0, 1e6)), min_size=1, max_size=3),
       st.sampled_from(['right', 'left']))
def test_fuzz_recognizer_to_messages_stays_in_range(frames, side):
    # Frame times are >= 0: every source produces them so (a negative one cannot be stamped).
    log = logging.getLogger('leap_teleop.hands.tracker')
    level = log.level
    log.setLevel(logging.ERROR)        # its rate-limited warnings restart with each tracker
    try:
        tracker = HandTracker(side)
        for i, (h, t) in enumerate(frames):
            h.side = side
            state = tracker.update(h, t, i)
            assert 0.0 <= state.pinch_value <= 0.8
            for key in ('rotate', 'turn', 'swing', 'grab_strength', 'confidence'):
                assert math.isfinite(getattr(state, key)), key
            for flag in ('fist', 'thumb_up', 'pinch'):
                assert isinstance(getattr(state, flag), bool)
            kinds = []
            for kind, msg in hand_conversions.hand_messages(state):
                kinds.append(kind)
                if kind == 'leapcobot':       # the message carries the state's values
                    d = hand_conversions.from_leapcobot(msg)
                    assert d['pinch_value'] == pytest.approx(state.pinch_value, abs=1e-6)
                    assert d['present'] == state.present and d['side'] == side
            assert kinds[:2] == ['leapcobot', 'hand']
    finally:
        log.setLevel(level)


# -- fuzz: arm mapping over event sequences --------------------------------------------------
@st.composite
def arm_events(draw, max_size=8):
    """1..max_size events for the arm: a hand (palm, pinch value, flags, stamp age, angles),
    joint states (in range, or wild) or time passing (usually a little, sometimes back)."""
    rng = np.random.default_rng(draw(st.integers(0, 2 ** 32 - 1)))
    seq = []
    for _ in range(draw(st.integers(1, max_size))):
        kind = rng.integers(0, 3)
        if kind == 0:
            seq.append(('hand', wild(rng, 3), either(rng, lambda r: within(r, 0.0, 1.0)),
                        tuple(bool(b) for b in rng.integers(0, 2, 5)), within(rng, -1.0, 0.01),
                        tuple(either(rng, lambda r: within(r, -3.5, 3.5)) for _ in range(3))))
        elif kind == 1:
            seq.append(('joints', either(rng, lambda r: tuple(within(r, -6.2, 6.2) for _ in range(6)), 6)))
        else:
            seq.append(('time', within(rng, -0.5, 1.0) if rng.integers(0, 2) else 0.3))
    return seq


@settings(max_examples=2500, deadline=None, suppress_health_check=list(HealthCheck))
@given(seq=arm_events(),
       mode=st.sampled_from(['imitation', 'joystick']),
       gripper_mode=st.sampled_from(['binary', 'proportional']),
       cutoff=st.sampled_from([0.0, 0.3]),
       orientation=st.sampled_from(['fixed', 'yaw', 'full']))
def test_fuzz_arm_sequences_never_leave_the_limits(seq, mode, gripper_mode, cutoff, orientation):
    t = ArmTeleop(ArmTeleopParams(mode=mode, gripper_mode=gripper_mode,
                                  filter_min_cutoff_hz=cutoff, rotation_min_cutoff_hz=cutoff,
                                  orientation=orientation, max_joint_speed=1.0,
                                  max_joint_accel=2.0, arm_hold_s=0.0))
    lo, hi = np.asarray(t.p.workspace_min), np.asarray(t.p.workspace_max)
    now = 100.0
    t.on_joints(HOME, now)
    for h in (hand(thumb_up=True), hand(rock=True)):
        now += 0.008
        h.stamp = now
        t.on_hand(h, now)
        t.step(now)
    for ev in seq:
        if ev[0] == 'hand':
            _, palm, pinch_value, (present, fist, thumb, pinch, rock), age, angles = ev
            t.on_hand(ArmInput(present=present, palm_mm=palm, fist=fist, thumb_up=thumb,
                                pinch=pinch, pinch_value=pinch_value, rock=rock,
                                stamp=now + age, rotate=angles[0], turn=angles[1],
                                swing=angles[2]), now)
        elif ev[0] == 'joints':
            t.on_joints(ev[1], now)
        else:
            now += ev[1]
        q_before = None if t._q is None else t._q.copy()
        cmd = t.step(now)
        if cmd.q is not None:
            assert q_before is not None
            assert np.all(np.isfinite(cmd.q))
            assert np.all(cmd.q <= kin.JOINT_UPPER) and np.all(cmd.q >= kin.JOINT_LOWER)
            t_prev, v_prev = 0.0, None
            for tfs, q, v in cmd.points:
                assert np.all(q <= kin.JOINT_UPPER) and np.all(q >= kin.JOINT_LOWER)
                assert np.all(np.abs(v) <= 1.0 + 1e-9)
                if v_prev is not None:     # within the UR10's acceleration limit
                    assert np.all(np.abs(v - v_prev) <= np.pi * (tfs - t_prev) + 1e-9)
                t_prev, v_prev = tfs, v
            np.testing.assert_array_equal(cmd.points[-1][2], np.zeros(6))
        if len(t.status.target_rotation) == 3:
            tilt, _ = kin.tilt_and_yaw(np.asarray(t.status.target_rotation))
            assert tilt <= t.p.max_tool_tilt + 1e-6
        if cmd.gripper is not None:
            assert 0.0 <= cmd.gripper <= 0.8
        if len(t.status.target) == 3:
            target = np.asarray(t.status.target)
            assert np.all(target >= lo - 1e-9) and np.all(target <= hi + 1e-9)


# -- fuzz: drone pilot ------------------------------------------------------------------------
GESTURES = ['unfold', 'fold', 'circle_cw', 'circle_ccw', 'hand_lost', 'fist', 'swipe', '',
            'x' * 300]


@st.composite
def pilot_events(draw, max_size=10):
    """1..max_size events for the pilot: a hand (present, palm, normal, direction, stamp
    age), a gesture (known, empty, unknown or overlong; with a wild or usual radius),
    navdata (any state code, wild altitude) or time passing."""
    rng = np.random.default_rng(draw(st.integers(0, 2 ** 32 - 1)))
    seq = []
    for _ in range(draw(st.integers(1, max_size))):
        kind = rng.integers(0, 4)
        if kind == 0:
            seq.append(('hand', bool(rng.integers(0, 2)), wild(rng, 3), wild(rng, 3), wild(rng, 3),
                        within(rng, -1.0, 0.01)))
        elif kind == 1:
            seq.append(('gesture', GESTURES[rng.integers(0, len(GESTURES))],
                        either(rng, lambda r: 0.035)))
        elif kind == 2:
            seq.append(('nav', int(rng.integers(-5, 301)), wild(rng)))
        else:
            seq.append(('time', within(rng, -1.0, 4.0) if rng.integers(0, 2) else 0.2))
    return seq


@settings(max_examples=3000, deadline=None, suppress_health_check=list(HealthCheck))
@given(seq=pilot_events(),
       mode=st.sampled_from(['tilt', 'paper']), max_cmd=st.sampled_from([1.0, 0.5, 0.25]))
def test_fuzz_pilot_commands_stay_within_the_tilt_limits(seq, mode, max_cmd):
    pilot = DronePilot(PilotParams(mode=mode, max_cmd=max_cmd))
    now, mono = 0.0, 0.0
    for ev in seq:
        if ev[0] == 'hand':
            _, present, palm, normal, direction, age = ev
            pilot.on_hand(PilotInput(present, palm, normal, direction, now + age), now)
        elif ev[0] == 'gesture':
            pilot.on_gesture(ev[1], True, now, ev[2])
        elif ev[0] == 'nav':              # also altitudes no Navdata (int32) carries
            pilot.on_navdata(ev[1], ev[2], now)
        else:
            now += ev[1]
        pilot.watchdog(now)
        while True:
            mono += 1.0
            cmd, _ = pilot.pop(mono)
            if cmd is None:
                break
            assert cmd.kind in ('twist', 'takeoff', 'land', 'flip')
            if cmd.kind == 'flip':
                assert cmd.anim == (19, 0) and pilot.altitude >= 0.6
            if cmd.kind == 'twist':
                if mode == 'tilt':
                    cap = min(max_cmd, 1.0)
                    assert all(math.isfinite(v) and abs(v) <= cap for v in cmd.twist)
                    assert cmd.twist[3] == 0.0 and cmd.twist[4] == 0.0   # auto-hover possible
                else:   # Algorithm 1 as published; the driver clamps each component to [-1, 1]
                    assert all(math.isfinite(v) for v in cmd.twist)


def _engaged_pilot(t0):
    """A pilot flying at 1 m, engaged at t0 and steered by one hand sample 10 ms later."""
    pilot = DronePilot(PilotParams())
    pilot.on_navdata(4, 1000, t0)
    pilot.on_gesture('unfold', True, t0)
    pilot.on_hand(PilotInput(True, (0.0, 0.2, 0.0), stamp=t0), t0)
    pilot.on_hand(PilotInput(True, (0.0, 0.2, -0.2), stamp=t0 + 0.01), t0 + 0.01)
    return pilot


def test_pilot_hovers_then_lands_on_a_stream_of_bad_hands():
    pilot = _engaged_pilot(0.0)
    t = 0.01
    out = []
    while t < 4.0:          # NaN palms (and late ones) keep coming: they must not feed the watchdog
        t += 0.01
        pilot.on_hand(PilotInput(True, (math.nan, 0.2, 0.0), stamp=t), t)
        pilot.on_hand(PilotInput(True, (0.0, 0.2, -0.2), stamp=t - 1.0), t)
        pilot.on_navdata(4, 1000, t)
        pilot.watchdog(t)
        while True:
            cmd, _ = pilot.pop(1e6 + t * 1e3)
            if cmd is None:
                break
            out.append((t, cmd))
    zero = [t for t, c in out if c.kind == 'twist' and c.twist == (0.0,) * 6]
    assert zero and zero[0] - 0.01 <= 0.2
    land = [t for t, c in out if c.kind == 'land']
    assert land and 3.0 <= land[0] - 0.01 <= 3.0 + 0.2 + 0.05
    assert pilot.rejected_inputs > 600


def test_pilot_clock_jump_back_hovers():
    pilot = _engaged_pilot(50.0)
    pilot.watchdog(0.5)
    cmds = []
    while True:
        cmd, _ = pilot.pop(1e9 + len(cmds))
        if cmd is None:
            break
        cmds.append(cmd)
    assert cmds[-1].twist == (0.0,) * 6


# -- the drone simulator: bad animations ------------------------------------------------------
def test_flight_animation_type_200_refused_and_duration_overflow_harmless():
    from leap_teleop.drone import sim as ds
    warnings = []
    d = ds.ArDroneSim(warn=lambda key, text: warnings.append(text))
    try:
        assert d.takeoff()
        while d.state != ds.HOVERING and d.time < 8.0:
            d.step()
        d.advance(1.0)
        assert not d.flight_animation(200, 0)
        assert not d.flight_animation('flip', 0)
        assert any('not in 0..19' in w for w in warnings)
        assert d.flight_animation(19, 2 ** 32 - 1)             # flips ignore the duration
        worst = 0.0
        for _ in range(int(3.0 / d.dt)):
            d.step()
        assert d.state == ds.HOVERING
        assert d.flight_animation(6, 2 ** 32 - 1)              # a 49-day yaw turn: slow, level
        for _ in range(int(2.0 / d.dt)):
            d.step()
            worst = max(worst, abs(d.roll), abs(d.pitch))
        assert worst <= d.p.euler_angle_max + 0.02 and math.isfinite(d.altitude)
    finally:
        d.close()


# -- no parameter disables a watchdog: any accepted value keeps it working ------------------
from leap_teleop.control.service_call import ServiceCall  # noqa: E402
from leap_teleop.drone.pilot import PILOT_PARAMS, PilotWorker  # noqa: E402
from leap_teleop.ur10.teleop import TELEOP_PARAMS  # noqa: E402

# fits models or fuzzes for minutes: not in make check
pytestmark = pytest.mark.slow


def _accepted(p):
    lo = p.gt if p.gt is not None else p.ge
    hi = p.lt if p.lt is not None else p.le
    return st.floats(lo, hi, exclude_min=p.gt is not None, exclude_max=p.lt is not None)


def _pilot_run(pilot, t0, until, dt=0.01, hand=False, navdata=True):
    """Step the pilot from t0 to `until`; [(t, cmd)] of what it sends."""
    out, t = [], t0
    while t < until:
        t += dt
        if hand:
            pilot.on_hand(PilotInput(True, (0.0, 0.2, -0.2), stamp=t), t)
        if navdata:
            pilot.on_navdata(4, 1000, t)
        pilot.watchdog(t)
        while True:
            cmd, _ = pilot.pop(1e6 + t * 1e3 + len(out))
            if cmd is None:
                break
            out.append((t, cmd))
    return out


@settings(max_examples=150, deadline=None, suppress_health_check=list(HealthCheck))
@given(hand_timeout=_accepted(PILOT_PARAMS['hand_timeout']),
       land_after=_accepted(PILOT_PARAMS['land_after']),
       navdata_timeout=_accepted(PILOT_PARAMS['navdata_timeout']),
       lose=st.sampled_from(['hand', 'navdata']))
def test_fuzz_any_accepted_pilot_timeouts_still_hover_then_land(hand_timeout, land_after,
                                                                navdata_timeout, lose):
    cfg = PilotParams().update(dict(hand_timeout=hand_timeout, land_after=land_after,
                                    navdata_timeout=navdata_timeout))
    pilot = DronePilot(cfg)
    pilot.on_navdata(4, 1000, 0.0)
    pilot.on_gesture('unfold', True, 0.0)
    pilot.on_hand(PilotInput(True, (0.0, 0.2, 0.0), stamp=0.0), 0.0)
    _pilot_run(pilot, 0.0, 0.05, hand=True)
    limit = (hand_timeout if lose == 'hand' else navdata_timeout) + land_after + 0.05
    out = _pilot_run(pilot, 0.05, 0.05 + limit, dt=0.02, hand=lose == 'navdata',
                     navdata=lose == 'hand')
    zero = [t for t, c in out if c.kind == 'twist' and c.twist == (0.0,) * 6]
    assert zero and zero[0] <= 0.05 + limit - land_after
    assert any(c.kind == 'land' for _, c in out)
    first_zero = zero[0]
    assert not any(c.kind == 'twist' and c.twist != (0.0,) * 6 for t, c in out
                   if t > first_zero)


@settings(max_examples=100, deadline=None, suppress_health_check=list(HealthCheck))
@given(input_timeout=_accepted(TELEOP_PARAMS['input_timeout']),
       disarm_after=_accepted(TELEOP_PARAMS['disarm_after']))
def test_fuzz_any_accepted_input_timeout_still_holds_then_disarms_the_arm(input_timeout,
                                                                         disarm_after):
    disarm_after = max(disarm_after, input_timeout)     # validate() refuses less
    a = Arm(input_timeout=input_timeout, disarm_after=disarm_after)
    a.arm_with_origin()
    held, sent = False, 0
    steps = int((disarm_after + 0.1) / 0.05) + 2
    for _ in range(steps):
        cmd = a.period(None, dt=0.05)
        held = held or a.t.status.state == HOLDING
        if a.t.status.state != TRACKING:         # stale: one hold, nothing after it
            sent += cmd.points is not None
    assert a.t.status.state == DISARMED and sent == 1
    assert held or disarm_after - input_timeout < 0.05


# -- navdata staleness ---------------------------------------------------------------------
def test_found_no_navdata_no_takeoff_and_no_twist_beyond_hover():
    # Before: with no navdata at all an unfold took off and hand twists were sent.
    warnings = []
    pilot = DronePilot(PilotParams(), warn=lambda key, text: warnings.append(text))
    pilot.on_hand(PilotInput(True, (0.0, 0.2, 0.0), stamp=0.0), 0.0)
    pilot.on_gesture('unfold', True, 0.0)
    out = _pilot_run(pilot, 0.0, 2.0, hand=True, navdata=False)
    assert not any(c.kind == 'takeoff' for _, c in out)
    assert all(c.twist == (0.0,) * 6 for _, c in out if c.kind == 'twist')
    assert any('no navdata' in w for w in warnings)
    # Fresh navdata (landed): the next unfold takes off.
    pilot.on_navdata(2, 0, 2.0)
    pilot.on_gesture('unfold', True, 2.0)
    assert any(c.kind == 'takeoff' for _, c in _pilot_run(pilot, 2.0, 2.05, hand=True))


def test_found_navdata_stopping_mid_flight_hovers_then_lands():
    # Before: the pilot kept believing the last navdata and kept sending hand twists.
    pilot = DronePilot(PilotParams(navdata_timeout=0.5, land_after=3.0))
    pilot.on_navdata(2, 0, 0.0)
    pilot.on_gesture('unfold', True, 0.0)
    pilot.on_hand(PilotInput(True, (0.0, 0.2, 0.0), stamp=0.0), 0.0)
    out = _pilot_run(pilot, 0.0, 1.0, hand=True)
    assert any(c.kind == 'twist' and c.twist[0] > 0.5 for _, c in out)    # flying forward
    out = _pilot_run(pilot, 1.0, 5.0, hand=True, navdata=False)          # navdata stops
    zero = [t for t, c in out if c.kind == 'twist' and c.twist == (0.0,) * 6]
    assert zero and 1.5 <= zero[0] <= 1.55
    assert not any(c.kind == 'twist' and c.twist != (0.0,) * 6 for t, c in out if t >= zero[0])
    assert len(zero) >= 3                                     # hover repeated while stale
    land = [t for t, c in out if c.kind == 'land']
    assert len(land) == 1 and 4.5 <= land[0] <= 4.55
    assert pilot.navdata_lost_since is not None


# -- the pilot's worker: a hung peer or a fault never stops the watchdog -----------------------
class FakeClock:
    def __init__(self, t=0.0):
        self.t = t

    def __call__(self):
        return self.t


def _worker(pilot, flip, clock, timeout=0.5):
    sent, warnings = [], []
    call = ServiceCall(flip, timeout, 'flip', clock=clock)
    w = PilotWorker(pilot, lambda cmd: sent.append((clock.t, cmd)), call, clock,
                    warn=lambda key, text: warnings.append(text), mono=lambda: 1e6 + clock.t)
    return w, sent, warnings


def test_found_hung_flip_call_never_blocks_the_watchdog():
    # Before: the worker made the flip call itself; a peer that accepted the call and never
    # answered stopped every hover and land command.
    import threading
    release = threading.Event()
    clock = FakeClock()
    pilot = DronePilot(PilotParams(navdata_timeout=10.0, land_after=3.0))
    w, sent, warnings = _worker(pilot, lambda *anim: release.wait(30.0), clock)
    pilot.on_navdata(4, 1500, 0.0)
    pilot.on_gesture('unfold', True, 0.0)
    pilot.on_hand(PilotInput(True, (0.0, 0.2, 0.0), stamp=0.0), 0.0)
    pilot.on_gesture('circle_cw', True, 0.0, 0.035)
    try:
        while clock.t < 4.0:                   # the hand went silent right after the circle
            clock.t += 0.01
            pilot.on_navdata(4, 1500, clock.t)
            w.step()
        assert w.flip_call.busy                # the call still hangs on its own thread
        assert w.flip_call.counts['timeout'] == 1
        assert any('timed out' in text for text in warnings)
        zero = [t for t, c in sent if c.kind == 'twist' and c.twist == (0.0,) * 6]
        assert zero and zero[0] <= 0.17
        land = [t for t, c in sent if c.kind == 'land']
        assert land and 3.1 <= land[0] <= 3.2
        # A second circle while the first call hangs (the hand back): refused, nothing
        # piles up.
        pilot.on_navdata(4, 1500, clock.t)
        pilot.on_hand(PilotInput(True, (0.0, 0.2, 0.0), stamp=clock.t), clock.t)
        pilot.on_gesture('circle_cw', True, clock.t, 0.035)
        w.step()
        assert w.flip_call.counts['refused'] == 1 and any('not returned' in x for x in warnings)
    finally:
        release.set()


def test_found_a_flip_waiting_for_its_service_is_not_called_after_a_fold():
    # The service appeared 0.3 s after the circle; the fold's land went out meanwhile,
    # then the flip was called all the same.
    import types

    from leap_teleop.ros.ardrone_commands import ArdroneCommands
    clock = FakeClock()
    called, answers = [], []

    class SlowService:
        def wait_for_service(self, timeout):
            clock.t += 0.3                    # the fold comes while this waits
            pilot.on_gesture('fold', True, clock.t)

        def __call__(self, anim, duration):
            called.append(anim)
            return types.SimpleNamespace(result=True)

    commands = object.__new__(ArdroneCommands)      # its ROS parts are not needed here
    commands.flight_animation, commands.service_timeout = SlowService(), 0.5
    pilot = DronePilot(PilotParams(navdata_timeout=10.0))
    w, sent, warnings = _worker(pilot, lambda *args: answers.append(commands.flip(*args)) or answers[-1],
                                clock)
    pilot.on_navdata(4, 1500, 0.0)
    pilot.on_gesture('unfold', True, 0.0)
    pilot.on_hand(PilotInput(True, (0.0, 0.2, 0.0), stamp=0.0), 0.0)
    pilot.on_gesture('circle_cw', True, 0.01, 0.035)
    clock.t = 0.01
    while w.flip_call._thread is None and len(pilot.queue):     # the hover, then the flip
        w.step()
    w.flip_call._thread.join(2.0)
    w.step()
    assert called == [] and answers == ['not called'] and w.flips_not_called == 1
    assert not warnings                      # a safety refusal: said at info level
    diag = dict(w.diagnostics(clock.t)[2])
    assert diag['flip calls ok'] == 0 and diag['flip calls failed'] == 0
    assert 'land' in [c.kind for _, c in sent]
    # Without the fold the same flip is called.
    pilot = DronePilot(PilotParams(navdata_timeout=10.0))
    SlowService.wait_for_service = lambda self, timeout: None
    w, sent, warnings = _worker(pilot, commands.flip, clock)
    pilot.on_navdata(4, 1500, clock.t)
    pilot.on_gesture('unfold', True, clock.t)
    pilot.on_hand(PilotInput(True, (0.0, 0.2, 0.0), stamp=clock.t), clock.t)
    pilot.on_gesture('circle_cw', True, clock.t, 0.035)
    while w.flip_call._thread is None and len(pilot.queue):
        w.step()
    w.flip_call._thread.join(2.0)
    assert called == [19]


def test_found_any_worker_exception_is_answered_with_hover_then_land():
    # Before: any exception other than ROSException killed the worker while the node
    # looked alive.
    clock = FakeClock()
    pilot = DronePilot(PilotParams(navdata_timeout=10.0, land_after=1.0))
    w, sent, warnings = _worker(pilot, lambda *anim: True, clock)

    def broken(now):
        raise ZeroDivisionError('boom')
    pilot.watchdog = broken
    while clock.t < 1.5:
        clock.t += 0.02
        assert w.step() > 0
    assert w.errors > 50 and 'ZeroDivisionError' in w.last_error
    assert sent[0][1].kind == 'twist' and sent[0][1].twist == (0.0,) * 6
    land = [t for t, c in sent if c.kind == 'land']
    assert len(land) == 1 and 1.0 <= land[0] <= 1.05
    assert any('worker fault' in text for text in warnings)


def test_service_call_reports_failures_and_times_out_once():
    clock = FakeClock()

    def fails(*args):
        raise OSError('connection refused')
    call = ServiceCall(fails, 0.5, clock=clock)
    assert call.submit(19, 0)
    call._thread.join(2.0)
    assert call.poll()[0] == 'failed' and call.poll() is None
    ok = ServiceCall(lambda a, b: a + b, 0.5, clock=clock)
    ok.submit(2, 3)
    ok._thread.join(2.0)
    assert ok.poll() == ('ok', 5)
    with pytest.raises(ValueError):
        ServiceCall(fails, math.nan)


# -- live sources: the newest frame after a stall ------------------------------------------
def test_found_a_late_start_up_burst_does_not_stamp_later_frames_ahead():
    # Before: the first frames, delivered 150 ms late in one burst, set the mapping, and
    # every later frame was stamped 0.148 s after its arrival, for the whole session.
    from leap_teleop.hands.sources.device_queue import PushQueue
    clock = FakeClock()
    pq = PushQueue(clock)
    ahead = []
    for k in range(3000):                     # 100 Hz; each frame arrives 2 ms after capture
        clock.t = max(1000.15, 1000.0 + 0.01 * k + 0.002)      # but the first 15 at 1000.15
        stamp = pq.stamp((5.0 + 0.01 * k) * 1e6)
        ahead.append(stamp - clock.t)
    assert max(ahead) <= 1e-9                 # never stamped after it arrived
    # From the first frame on time, stamps are its arrival less the least delay seen: 0.
    assert ahead[16] == pytest.approx(0.0, abs=1e-9) and ahead[-1] == pytest.approx(0.0, abs=1e-6)


def test_found_live_queue_delivers_the_newest_frame_after_a_stall():
    # Before: a 256-frame queue handed a 2 s old hand to the robots after a stall.
    from types import SimpleNamespace

    from leap_teleop.hands.sources.device_queue import PushQueue
    clock = FakeClock(100.0)
    pq = PushQueue(clock, maxsize=8, max_age=0.25)
    for i in range(10):                       # the device runs at 120 Hz, the consumer keeps up
        clock.t += 1 / 120
        pq.put(SimpleNamespace(id=i, timestamp=pq.stamp(i * 1e6 / 120)))
        assert pq.get(0.0).id == i
    # The device's thread stalls 2 s, then bursts the 240 frames it captured meanwhile.
    clock.t += 2.0
    for i in range(10, 250):
        pq.put(SimpleNamespace(id=i, timestamp=pq.stamp(i * 1e6 / 120)))
    got = []
    while True:
        f = pq.get(0.0)
        if f is None:
            break
        got.append(f)
    assert all(clock.t - f.timestamp <= 0.25 for f in got)
    assert got and got[-1].id == 249                    # the newest frame is delivered
    assert pq.dropped == 240 - len(got)
    # The consumer stalls instead: after it, only the newest maxsize frames are left.
    for i in range(250, 500):
        clock.t += 1 / 120
        pq.put(SimpleNamespace(id=i, timestamp=pq.stamp(i * 1e6 / 120)))
    assert len(pq) == 8 and pq.get(0.0).id == 492
