"""Arm teleop logic: protocol, modes, limits, watchdog, bad input (no ROS)."""
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from leap_teleop.hands.gestures.bindings import Bindings, load_bindings
from leap_teleop.hands.tracker import hand_angles, wrap_angle
from leap_teleop.ur10 import kinematics as kin
from leap_teleop.ur10.teleop import (
    ARMED,
    DISARMED,
    HOLDING,
    OFF_PLAN_LAG_S,
    OFF_PLAN_S,
    REANCHOR_TURN_RAD,
    TELEOP_PARAMS,
    TRACKING,
    ArmInput,
    ArmTeleop,
    ArmTeleopParams,
)
from leap_teleop.ur10.trajectory import TrajectoryFollower

HOME = kin.HOME_Q.copy()
PALM = (0.0, 200.0, 0.0)
HOLD_PERIODS = 40                  # 0.32 s of 8 ms periods: past the default arm_hold_s


class Clock:
    def __init__(self):
        self.t = 100.0

    def tick(self, dt=0.008):
        self.t += dt
        return self.t


def hand(**kw):
    kw.setdefault('present', True)
    kw.setdefault('palm_mm', PALM)
    return ArmInput(**kw)


def drive(teleop, clock, h, periods=1, q=None):
    """Feed the same hand for some control periods; the joints are at q, or where the
    servo's plan puts them (a perfect controller)."""
    cmd = None
    for _ in range(periods):
        now = clock.tick()
        h.stamp = now
        teleop.on_hand(h, now)
        if q is None:
            planned = teleop._servo.planned_at(now)
            teleop.on_joints(teleop._q if planned is None else planned)
        else:
            teleop.on_joints(q)
        cmd = teleop.step(now)
    return cmd


def target_q(t, seed=HOME):
    """The joints that put the tool on the target (where the goals head)."""
    return kin.ik_nearest(kin.pose(np.array(t.status.target), np.array(t.status.target_rotation)), seed)


def target_rotation(t):
    return np.array(t.status.target_rotation)


def armed_with_origin(mode='imitation', **params):
    t = ArmTeleop(ArmTeleopParams(mode=mode, filter_min_cutoff_hz=0.0, rotation_min_cutoff_hz=0.0, **params))
    c = Clock()
    t.on_joints(HOME)
    drive(t, c, hand(thumb_up=True), periods=HOLD_PERIODS)
    assert t.status.state == ARMED
    drive(t, c, hand(rock=True))
    assert t.status.state == TRACKING and t.status.origin_set
    return t, c


def test_nothing_moves_until_thumbs_up_and_rock():
    t = ArmTeleop()
    c = Clock()
    t.on_joints(HOME)
    cmd = drive(t, c, hand(palm_mm=(50, 250, 0)), periods=5)
    assert t.status.state == DISARMED and cmd.q is None and cmd.gripper is None
    drive(t, c, hand(thumb_up=True), periods=HOLD_PERIODS)
    cmd = drive(t, c, hand(palm_mm=(50, 250, 0), pinch=True, pinch_value=0.5))
    assert t.status.state == ARMED and cmd.q is None     # no origin yet: gripper only
    assert cmd.gripper == pytest.approx(0.43)


def test_arming_needs_the_thumbs_up_held():
    t = ArmTeleop()
    c = Clock()
    t.on_joints(HOME)
    drive(t, c, hand(thumb_up=True), periods=30)              # 0.24 s: not yet
    assert t.status.state == DISARMED
    drive(t, c, hand(), periods=1)                             # let go: the hold restarts
    drive(t, c, hand(thumb_up=True), periods=30)
    assert t.status.state == DISARMED
    drive(t, c, hand(thumb_up=True), periods=10)              # 0.32 s in a row
    assert t.status.state == ARMED
    with pytest.raises(ValueError):
        ArmTeleopParams.from_dict({'arm_hold_s': -1.0})


def test_the_state_lines_name_the_gestures_the_bindings_chose():
    # The arm reads flags only; a V sign bound to arm raises the thumb_up flag. Its lines
    # said "hold the thumbs-up" to someone who had to show a V.
    words = load_bindings(None).arm_words()
    assert words == {'arm': 'thumbs-up', 'origin': 'rock', 'stop': 'fist', 'gripper': 'pinch'}
    assert ArmTeleop().status.reason == 'waiting for thumbs-up'
    assert Bindings({'arm': {'gripper': []}}).arm_words()['gripper'] == 'no gesture (unbound)'
    words = Bindings({'arm': {'arm': 'peace', 'origin': ['open', 'thumb_up'],
                              'stop': 'thumb_down'}}).arm_words()
    t = ArmTeleop(gesture_words=words)
    c = Clock()
    assert t.status.reason == 'waiting for peace'
    t.on_joints(HOME)
    drive(t, c, hand(thumb_up=True), periods=5)
    assert t.status.reason == 'hold the peace'
    drive(t, c, hand(thumb_up=True), periods=HOLD_PERIODS)
    assert t.status.reason == 'peace; show open or thumbs-up to set the origin'
    drive(t, c, hand(fist=True))
    assert t.status.state == DISARMED and t.status.reason == 'thumbs-down'


def test_the_thumbs_up_hold_counts_on_the_clock_that_says_less():
    # Unstamped input (the original sender's) arms on its receipt times; it never armed.
    t = ArmTeleop()
    t.on_joints(HOME)
    for k in range(HOLD_PERIODS):
        now = 100.0 + 0.008 * k
        t.on_hand(hand(thumb_up=True, stamp=0.0), now)
        t.step(now)
    assert t.status.state == ARMED
    # Two messages 20 ms apart whose stamps leap 10 s: no hold (it armed at once).
    for leap in (0.35, 10.0):
        t = ArmTeleop()
        t.on_joints(HOME)
        t.on_hand(hand(thumb_up=True, stamp=100.0), 100.0)
        t.step(100.0)
        t.on_hand(hand(thumb_up=True, stamp=100.0 + leap), 100.02)
        t.step(100.02)
        assert t.status.state == DISARMED, leap


def test_imitation_maps_palm_offset_through_axis_map_and_scale():
    t, c = armed_with_origin(scale=2.0)
    tcp_ref = kin.fk(HOME)[:3, 3]
    cmd = drive(t, c, hand(palm_mm=(0.0, 250.0, -40.0)))   # up 50 mm, away from user 40 mm
    expected = tcp_ref + np.array([0.08, 0.0, 0.1])        # base x = -leap z, z = leap y
    np.testing.assert_allclose(t.status.target, expected, atol=1e-9)
    np.testing.assert_allclose(target_rotation(t), kin.tool_down(), atol=1e-9)
    # Further than the joints go in one period: the goal is a step along the straight line.
    goal = kin.fk(cmd.q)
    np.testing.assert_allclose(goal[:3, :3], kin.tool_down(), atol=1e-9)
    along = goal[:3, 3] - tcp_ref
    assert 0.0 < np.linalg.norm(along) < 0.001
    np.testing.assert_allclose(np.cross(along, expected - tcp_ref), 0.0, atol=1e-9)


def check_points(cmd, speed, accel):
    """A command's trajectory: inside the joint limits, no joint faster than speed, no
    acceleration between its points above accel, at rest at its end."""
    t_prev, v_prev = 0.0, None
    for tfs, q, v in cmd.points:
        assert np.all(q <= kin.JOINT_UPPER) and np.all(q >= kin.JOINT_LOWER)
        assert np.all(np.abs(v) <= speed + 1e-9)
        if v_prev is not None:
            assert np.all(np.abs(v - v_prev) <= accel * (tfs - t_prev) + 1e-9)
        t_prev, v_prev = tfs, v
    np.testing.assert_array_equal(cmd.points[-1][2], np.zeros(6))


def test_commands_respect_the_joint_speed_and_acceleration_limits():
    t, c = armed_with_origin(max_joint_speed=0.05, max_joint_accel=0.5)
    speeds, goal = [], HOME
    for _ in range(125):                                  # 1 s toward a far target
        cmd = drive(t, c, hand(palm_mm=(60.0, 200.0, 0.0)))
        check_points(cmd, 0.05, 0.5)
        speeds.append(np.max(np.abs(cmd.points[0][2])))
        # the goal steps toward the target's IK no faster than the joints go
        assert np.max(np.abs(cmd.q - goal)) <= 0.05 * 0.008 + 1e-12
        goal = cmd.q
    # Accelerates within 0.5 rad/s^2 (one horizon ahead) up to 0.05 rad/s, then cruises.
    assert 0.0 < speeds[0] <= 0.5 * t.p.command_horizon + 1e-12
    assert speeds[-1] == pytest.approx(0.05)


def test_target_is_clamped_to_the_workspace_box():
    t, c = armed_with_origin(scale=3.0, workspace_min=(0.3, -0.5, 0.05),
                             workspace_max=(1.0, 0.5, 0.6))
    drive(t, c, hand(palm_mm=(0.0, 800.0, 0.0)))           # +1.8 m up
    assert t.status.target[2] == pytest.approx(0.6)
    drive(t, c, hand(palm_mm=(0.0, -500.0, 0.0)))          # far below the table
    assert t.status.target[2] == pytest.approx(0.05)


def test_joystick_dead_zone_moves_nothing_and_excess_moves_at_capped_speed():
    # An arm fast enough for the cap (the target leads a slower one by a bounded distance)
    t, c = armed_with_origin(mode='joystick', dead_zone=0.03, max_tcp_speed=0.1,
                             max_joint_speed=1.0, max_joint_accel=math.pi)
    for _ in range(50):
        drive(t, c, hand(palm_mm=(20.0, 210.0, 0.0)))      # 22 mm from the origin
    np.testing.assert_allclose(t.status.target, kin.fk(HOME)[:3, 3], atol=1e-12)
    for _ in range(125):                                   # 1 s far beyond the dead zone
        drive(t, c, hand(palm_mm=(0.0, 200.0, -300.0)))
    moved = np.array(t.status.target) - kin.fk(HOME)[:3, 3]
    assert moved[0] == pytest.approx(0.1, rel=0.02)        # forward at the 0.1 m/s cap
    assert abs(moved[1]) < 1e-9 and abs(moved[2]) < 1e-9


def test_fist_disarms_holds_and_later_pinch_moves_nothing():
    t, c = armed_with_origin()
    drive(t, c, hand(palm_mm=(40.0, 220.0, 0.0)))
    q_now = HOME + 0.01
    t.on_joints(q_now)
    cmd = drive(t, c, hand(fist=True), q=q_now)
    assert t.status.state == DISARMED and t.status.reason == 'fist'
    # Hold: decelerate within the UR10's limit and stay where the motion stops.
    check_points(cmd, t.p.max_joint_speed, kin.MAX_JOINT_ACCEL[0])
    assert np.max(np.abs(cmd.q - HOME)) < 0.01
    for _ in range(20):
        cmd = drive(t, c, hand(pinch=True, pinch_value=0.6, palm_mm=(90, 260, -50)), q=q_now)
        assert cmd.q is None and cmd.gripper is None


def stall(t, c, seconds, q=None):
    """Control periods with no hand input for `seconds`; the commands once not tracking."""
    cmds = []
    end = c.t + seconds
    while c.t < end - 1e-9:
        now = c.tick()
        t.on_joints(q if q is not None else t._q)
        cmd = t.step(now)
        if t.status.state != TRACKING:   # within input_timeout the last hand still counts
            cmds.append(cmd)
    return cmds


def stall_following(t, c, q, periods):
    """Control periods with no hand input, the joints following the servo's plan (a
    perfect controller); the joints at the end."""
    for _ in range(periods):
        now = c.tick()
        t.on_joints(q)
        t.step(now)
        q = t._servo.state_at(now + 0.008, q)[0]
    return q


def sent(cmd):
    return cmd.q is not None or cmd.points is not None or cmd.gripper is not None


def test_watchdog_holds_on_a_stall_and_disarms_after_disarm_after():
    t, c = armed_with_origin()
    drive(t, c, hand(palm_mm=(40.0, 220.0, 0.0)))
    t_input = c.t
    now = c.tick(0.1)                                       # within input_timeout: still on
    t.step(now)
    assert t.status.state == TRACKING, t.status
    now = c.tick(0.15)                                      # 0.25 s since the last input
    cmd = t.step(now)
    assert t.status.state == HOLDING and 'no hand input' in t.status.reason
    assert t.status.origin_set
    check_points(cmd, t.p.max_joint_speed, kin.MAX_JOINT_ACCEL[0])
    assert np.max(np.abs(cmd.q - t._q)) < 0.01
    # Held: nothing more is commanded while the input stays stale ...
    cmds = stall(t, c, t.p.disarm_after - (c.t - t_input) - 0.01)
    assert t.status.state == HOLDING and not any(sent(x) for x in cmds)
    # ... and the loss disarms once no input came for disarm_after.
    cmds = stall(t, c, 0.02)
    assert t.status.state == DISARMED and 'watchdog' in t.status.reason
    assert not any(sent(x) for x in cmds)                  # the stall's hold was enough
    assert not t.status.origin_set


def follow(t, c, h, periods, q):
    """Like drive, but the joints follow the servo's plan (a perfect controller)."""
    cmd = None
    for _ in range(periods):
        now = c.tick()
        h.stamp = now
        t.on_hand(h, now)
        t.on_joints(q)
        cmd = t.step(now)
        q = t._servo.state_at(now + 0.008, q)[0]
    return cmd, q


def test_stall_shorter_than_disarm_after_resumes_from_the_current_pose_without_a_jump():
    t, c = armed_with_origin(max_joint_speed=1.0, max_joint_accel=2.0)
    q = HOME.copy()
    cmd, q = follow(t, c, hand(palm_mm=(0.0, 260.0, -60.0)), 60, q)    # moving forward / up
    assert np.max(np.abs(q - HOME)) > 0.05
    # The sender stalls 0.7 s (< disarm_after) while the arm moves: the arm holds.
    cmds = stall(t, c, 0.7, q=q)
    holds = [x for x in cmds if sent(x)]
    assert len(holds) == 1 and t.status.state == HOLDING
    q = holds[0].points[-1][1]                 # where the hold comes to rest
    # Meanwhile the hand moved 100 mm: the old origin would put the target 0.25 m away.
    palm = (100.0, 260.0, -60.0)
    last_target = np.array(t.status.target)            # where its last message put it
    old_target = t._tcp_ref + t._axes @ (np.array(palm) - t._palm_ref) * 0.001 * t.p.scale
    assert np.linalg.norm(old_target - kin.fk(q)[:3, 3]) > 0.2
    cmd, _ = follow(t, c, hand(palm_mm=palm), 1, q)
    assert t.status.state == TRACKING and 'origin re-anchored' in t.status.reason
    assert t.status.origin_set
    # None of the motion unseen is driven: the target is where the last message put it.
    np.testing.assert_allclose(t.status.target, last_target, atol=1e-9)
    # The trajectory starts at rest from the current joints, accelerating within the
    # limit: no step in position or velocity.
    h, a = t.p.command_horizon, t.p.max_joint_accel
    assert np.max(np.abs(cmd.points[0][1] - q)) <= 0.5 * a * h * h + 1e-9
    assert np.max(np.abs(cmd.points[0][2])) <= a * h + 1e-9
    # Motion resumes from there: 20 mm of hand up is 50 mm of TCP up (scale 2.5).
    cmd, _ = follow(t, c, hand(palm_mm=(100.0, 280.0, -60.0)), 1, q)
    np.testing.assert_allclose(np.array(t.status.target) - last_target, [0.0, 0.0, 0.05], atol=1e-6)


def test_a_small_gap_after_a_stall_keeps_the_origin_and_is_caught_up_within_the_limits():
    t, c = armed_with_origin(max_joint_speed=1.0, max_joint_accel=2.0)
    q = HOME.copy()
    cmd, q = follow(t, c, hand(palm_mm=(0.0, 260.0, -60.0)), 60, q)
    palm_ref, tcp_ref = t._palm_ref.copy(), t._tcp_ref.copy()
    holds = [x for x in stall(t, c, 0.5, q=q) if sent(x)]
    q = holds[0].points[-1][1]
    # The hand moved 20 mm meanwhile: 0.05 m of TCP (scale 2.5), less than reanchor_beyond.
    palm = np.array((20.0, 260.0, -60.0))
    cmd, _ = follow(t, c, hand(palm_mm=tuple(palm)), 1, q)
    assert t.status.state == TRACKING and 'same origin' in t.status.reason, t.status.reason
    np.testing.assert_allclose(t._palm_ref, palm_ref)            # the mapping is kept
    np.testing.assert_allclose(t.status.target, tcp_ref + t._axes @ (palm - palm_ref) * 0.001 * t.p.scale,
                               atol=1e-6)
    # No step: the trajectory starts at rest from the current joints, within the limits.
    h, a = t.p.command_horizon, t.p.max_joint_accel
    assert np.max(np.abs(cmd.points[0][1] - q)) <= 0.5 * a * h * h + 1e-9
    assert np.max(np.abs(cmd.points[0][2])) <= a * h + 1e-9
    check_points(cmd, t.p.max_joint_speed, t.p.max_joint_accel)


@pytest.mark.parametrize('moved_mm, kept', [(0.0, True), (30.0, True), (60.0, False)])
def test_a_stall_while_the_arm_lags_re_anchors_only_when_the_hand_moved_meanwhile(moved_mm, kept):
    # At the real robot's 0.05 rad/s the arm lags the hand by more than reanchor_beyond:
    # that lag, not the hand's motion, re-anchored a short stall, and the arm then stopped
    # that far short of where the hand put it for the rest of the session.
    t, c = armed_with_origin()
    q = HOME.copy()
    palm = np.array(PALM) + [0.0, 0.0, -80.0]                 # 0.2 m of target forward
    _, q = follow(t, c, hand(palm_mm=tuple(palm)), 40, q)
    palm_ref, tcp_ref = t._palm_ref.copy(), t._tcp_ref.copy()
    holds = [x for x in stall(t, c, 0.3, q=q) if sent(x)]
    assert len(holds) == 1 and t.status.state == HOLDING
    q = holds[0].points[-1][1]
    want = tcp_ref + t._axes @ (palm - palm_ref) * 0.001 * t.p.scale
    assert np.linalg.norm(want - kin.fk(q)[:3, 3]) > 1.5 * t.p.reanchor_beyond      # it lags
    back = palm + [moved_mm, 0.0, 0.0]          # 2.5 x: 0, 75 and 150 mm of target sideways
    follow(t, c, hand(palm_mm=tuple(back)), 1, q)
    assert t.status.state == TRACKING
    if kept:
        assert 'same origin' in t.status.reason, t.status.reason
        np.testing.assert_allclose(t._palm_ref, palm_ref)
        np.testing.assert_allclose(t.status.target, tcp_ref + t._axes @ (back - palm_ref) * 0.001 * t.p.scale,
                                   atol=1e-9)
    else:
        # The motion unseen is dropped, the lag is not: the target is where the hand's last
        # message put it (re-anchored on the hold's rest, the arm stayed 0.2 m short).
        assert 'origin re-anchored' in t.status.reason, t.status.reason
        np.testing.assert_allclose(t._tcp_ref, tcp_ref)
        np.testing.assert_allclose(t.status.target, want, atol=1e-9)


def test_a_re_anchor_while_the_hold_still_brakes_goes_on_to_the_last_target_without_a_step():
    # The hold brakes at the UR10's own limit: the re-anchor comes while it still moves.
    t, c = armed_with_origin(max_joint_speed=1.0, max_joint_accel=math.pi)
    q = HOME.copy()
    palm = np.array(PALM)
    for _ in range(80):                                       # 180 mm/s: the arm at speed
        palm = palm + [0.0, 0.0, -1.5]
        cmd, q = follow(t, c, hand(palm_mm=tuple(palm)), 1, q)
    last_target = np.array(t.status.target)
    assert np.abs(t._servo.state_at(c.t, q)[1]).max() > 0.5
    q = stall_following(t, c, q, 26)                          # a 0.21 s stall: the hold
    assert t.status.state == HOLDING and t._servo.moving
    q0, v0 = t._servo.state_at(c.t + 0.008, q)
    cmd, q = follow(t, c, hand(palm_mm=tuple(palm + [0.0, 100.0, 0.0])), 1, q)     # 0.25 m up
    assert 'origin re-anchored' in t.status.reason
    np.testing.assert_allclose(t.status.target, last_target, atol=1e-9)
    # the trajectory goes on from the braking state, within the tracking limits
    np.testing.assert_allclose(t._servo.state_at(cmd.stamp, q0)[1], v0, atol=1e-9)
    check_points(cmd, t.p.max_joint_speed, t.p.max_joint_accel)
    _, q = follow(t, c, hand(palm_mm=tuple(palm + [0.0, 100.0, 0.0])), 150, q)
    assert np.linalg.norm(kin.fk(q)[:3, 3] - last_target) < 1e-4


@pytest.mark.parametrize('orientation', ['fixed', 'yaw', 'full'])
def test_a_stall_mid_sweep_re_anchors_on_the_hands_unseen_motion_and_keeps_the_arms_lag(orientation):
    # The hand sweeps (and turns) on through a stall: re-anchored on where the hold came to
    # rest, the arm dropped its lag behind the hand (0.15 m, 0.5 rad here) with the motion
    # unseen, and stayed that far short of where the hand put it for the rest of the session.
    t, c = armed_with_origin(max_joint_speed=0.2, orientation=orientation)
    q = HOME.copy()
    turning = orientation != 'fixed'

    def at(s):                                  # the hand s seconds after the rock
        f = min(1.0, s / 0.8)
        return hand(palm_mm=tuple(np.array(PALM) + [120.0 * f, 0.0, 0.0]),
                    turn=0.8 * f if turning else 0.0,
                    rotate=0.3 * f if orientation == 'full' else 0.0)

    k = 0
    while k * 0.008 < 0.5:
        _, q = follow(t, c, at(k * 0.008), 1, q)
        k += 1
    last = (np.array(t.status.target), target_rotation(t))
    lag = np.linalg.norm(kin.fk(q)[:3, 3] - last[0])
    assert lag > 0.1, lag
    while k * 0.008 < 0.9:                      # silent while it sweeps on, then stops
        now = c.tick()
        t.on_joints(q)
        t.step(now)
        q = t._servo.state_at(now + 0.008, q)[0]
        k += 1
    assert t.status.state == HOLDING
    _, q = follow(t, c, at(k * 0.008), 1, q)
    assert 'origin re-anchored' in t.status.reason, t.status.reason
    np.testing.assert_allclose(t.status.target, last[0], atol=1e-9)
    assert kin.rotation_error(target_rotation(t), last[1]) < 1e-6
    _, q = follow(t, c, at(k * 0.008), 400, q)
    tool = kin.fk(q)
    assert np.linalg.norm(tool[:3, 3] - last[0]) < 1e-3
    assert kin.rotation_error(tool[:3, :3], last[1]) < 1e-3


def _braked(t, now, q):
    """The joints at rest braked from the plan's state at `now` at the tracking's
    acceleration, every joint over the slowest one's time."""
    qs, v = t._servo.state_at(now, q)
    return qs + v * (0.5 * float(np.max(np.abs(v) / t._servo.max_accel)))


@pytest.mark.parametrize('speed', [0.5, 1.0])
@pytest.mark.parametrize('mode', ['imitation', 'joystick'])
def test_an_origin_set_while_the_hold_brakes_is_where_tracking_can_stop(mode, speed):
    # The hold brakes at the UR10's pi rad/s^2, tracking at max_joint_accel: an origin
    # where the hold comes to rest (a rock on the return; joystick mode's re-anchor, its
    # dead zone's stop) was one the arm ran 56-77 mm past, and back to.
    t, c = armed_with_origin(mode=mode, max_joint_speed=speed, max_joint_accel=0.5)
    q = HOME.copy()
    palm = np.array(PALM)
    for k in range(75):                                       # 0.6 m of target sideways
        palm = np.array(PALM) + [400.0 * min(k * 0.008, 0.6), 0.0, 0.0]
        if mode == 'joystick':
            palm = np.array(PALM) + [100.0, 0.0, 0.0]         # pushed at full speed
        _, q = follow(t, c, hand(palm_mm=tuple(palm)), 1, q)
    q = stall_following(t, c, q, 26)                          # a 0.21 s stall: the hold
    assert t.status.state == HOLDING and t._servo.moving
    start = kin.fk(q)[:3, 3]
    rest = kin.fk(_braked(t, c.t + 0.008, q))[:3, 3]
    _, q = follow(t, c, hand(palm_mm=tuple(palm), rock=mode == 'imitation'), 1, q)
    assert t.status.reason.endswith('origin set' if mode == 'imitation' else 'origin re-anchored')
    origin = t._tcp_ref.copy()
    path = [kin.fk(q)[:3, 3]]
    for _ in range(250):
        _, q = follow(t, c, hand(palm_mm=tuple(palm)), 1, q)
        path.append(kin.fk(q)[:3, 3])
    way = (origin - start) / np.linalg.norm(origin - start)
    past = max(float((p - origin) @ way) for p in path)
    assert past < 0.003, past                                  # no run past and back
    assert np.linalg.norm(path[-1] - origin) < 1e-4
    np.testing.assert_allclose(origin, rest, atol=1e-9)


def test_a_rock_shown_while_the_arm_moves_sets_the_origin_where_it_comes_to_rest():
    # Taken at the pose the moving arm passed, the origin was one it ran past (12 mm here)
    # and then drove back to, with the hand still.
    t, c = armed_with_origin(max_joint_speed=1.0, max_joint_accel=math.pi)
    q = HOME.copy()
    goal = np.array(PALM) + [120.0, 0.0, 0.0]                 # 0.3 m of target sideways
    for k in range(31):                                        # there in 0.25 s, then still
        palm = np.array(PALM) + (goal - PALM) * min(1.0, k / 31.0)
        _, q = follow(t, c, hand(palm_mm=tuple(palm)), 1, q)
    for k in range(38):                                        # still, the arm catches up
        _, q = follow(t, c, hand(palm_mm=tuple(goal)), 1, q)
    assert np.abs(t._servo.state_at(c.t, q)[1]).max() > 0.3    # ... at speed
    path = [kin.fk(q)[:3, 3]]
    for k in range(7):                                         # a rock held 56 ms
        rest = kin.fk(_braked(t, c.t + 0.008, q))[:3, 3]
        _, q = follow(t, c, hand(palm_mm=tuple(goal), rock=True), 1, q)
        np.testing.assert_allclose(t._tcp_ref, rest, atol=1e-9)
        path.append(kin.fk(q)[:3, 3])
    origin = t._tcp_ref.copy()
    for k in range(150):
        _, q = follow(t, c, hand(palm_mm=tuple(goal)), 1, q)
        path.append(kin.fk(q)[:3, 3])
    way = (origin - path[0]) / np.linalg.norm(origin - path[0])
    past = max(float((p - origin) @ way) for p in path)
    assert past < 0.003, past                                  # no run past and back
    assert np.linalg.norm(path[-1] - origin) < 1e-4


def _palm_for(t, target):
    """The palm (mm) whose mapping puts the TCP target at `target`."""
    return np.array(PALM) + np.linalg.solve(t._axes, np.asarray(target) - t._tcp_ref) / (0.001 * t.p.scale)


def _sweep(t, c, q, a, b, periods, then=0):
    """The hand from where it maps to a to where it maps to b in `periods`, held there
    `then` more; the joints follow the plan (stamped states). (lowest TCP z, largest tool
    tilt, q)."""
    pa, pb = _palm_for(t, a), _palm_for(t, b)
    zmin, tilt = math.inf, 0.0
    for k in range(periods + then):
        palm = pa + (pb - pa) * min(1.0, (k + 1) / periods)
        now = c.tick()
        t.on_hand(hand(palm_mm=tuple(palm), stamp=now), now)
        t.on_joints(q, now)
        cmd = t.step(now)
        q = t._servo.state_at(now + 0.008, q)[0]
        for _, qp, _ in cmd.points or ():          # what the controller is sent
            zmin = min(zmin, kin.fk(qp)[2, 3])
        pose = kin.fk(q)
        zmin, tilt = min(zmin, pose[2, 3]), max(tilt, kin.tilt_and_yaw(pose[:3, :3])[0])
    return zmin, tilt, q


@pytest.mark.parametrize('accel, periods', [(math.pi, 62), (0.5, 150), (0.3, 150)])
def test_a_hand_faster_than_the_joints_is_caught_up_along_its_path_above_the_table(accel, periods):
    # Each joint ran toward the far goal at its own saturated speed: the hand slid along the
    # table 3 cm above it (480 mm/s), and the TCP went 18 cm under the table top, tilted.
    # With the acceleration far below the speed the goals, each within a period, ran away
    # from the servo: 13 cm under the table at 0.5 rad/s^2.
    t, c = armed_with_origin(max_joint_speed=1.0, max_joint_accel=accel)
    a, b = (0.45, 0.16, 0.03), (1.05, 0.16, 0.03)
    _, _, q = _sweep(t, c, HOME.copy(), kin.fk(HOME)[:3, 3], a, 300, then=600)
    np.testing.assert_allclose(kin.fk(q)[:3, 3], a, atol=1e-3)
    zmin, tilt, q = _sweep(t, c, q, a, b, periods, then=1200)
    assert t.status.state == TRACKING and t.status.ik_failures == 0
    assert zmin > (0.015 if accel == math.pi else 0.005) and tilt < 0.05, (zmin, tilt)   # the box floor: 0
    np.testing.assert_allclose(kin.fk(q)[:3, 3], b, atol=1e-3)


def _past_the_box(t, c, palm_at, periods):
    """Drive `t` with the palm at palm_at(k) for each 8 ms period k, the joints where the
    servo's plan puts them; (how far the planned path, every ms, went past the box, m;
    the joints at the end)."""
    lo, hi = np.array(t.p.workspace_min), np.array(t.p.workspace_max)
    q, out = HOME.copy(), 0.0
    for k in range(periods):
        now = c.tick()
        t.on_hand(hand(palm_mm=tuple(palm_at(k)), stamp=now), now)
        t.on_joints(q)
        t.step(now)
        for dt in np.arange(1, 9) * 0.001:             # the path the controller runs
            p = t._servo.planned_at(now + dt)
            if p is not None:
                tcp = kin.fk(p)[:3, 3]
                out = max(out, float(np.max(np.maximum(lo - tcp, tcp - hi))))
        q = t._servo.state_at(now + 0.008, q)[0]
    return out, q


@pytest.mark.parametrize('mode, direction, mm_s', [
    ('imitation', (0.0, 1.0, 0.0), 100.0),          # up to the box's top: 78 mm above it
    ('imitation', (0.0, -1.0, 0.0), 100.0),         # down to the table top: 16 mm under it
    ('imitation', (0.0, -1.0, 0.0), 200.0),         # 34 mm
    ('imitation', (0.0, 0.0, 1.0), 200.0),          # toward the near face: 70 mm past it
    ('joystick', (0.0, 1.0, 0.0), 150.0)])          # a push up: 79 mm (mm: beyond the origin)
def test_a_target_stopped_at_a_face_of_the_box_is_not_overrun(mode, direction, mm_s):
    # At the simulation's limits, a hand moving on past a face: the clamp stopped the
    # target dead there, and the servo, its joints near max_joint_speed, braked past it.
    t, c = armed_with_origin(mode=mode, max_joint_speed=1.0, max_joint_accel=math.pi)
    if mode == 'imitation':
        def palm_at(k):
            return np.array(PALM) + np.array(direction) * min(mm_s * 0.008 * k, 400.0)
    else:
        def palm_at(k):
            return np.array(PALM) + np.array(direction) * mm_s * min(1.0, k / 25)
    out, q = _past_the_box(t, c, palm_at, int((400.0 / mm_s + 2.0) / 0.008))
    lo, hi = np.array(t.p.workspace_min), np.array(t.p.workspace_max)
    assert t.status.state == TRACKING
    assert out < 0.0025, out                         # (the servo's lag off the line: 1.8 mm)
    assert np.max(np.maximum(lo - kin.fk(q)[:3, 3], kin.fk(q)[:3, 3] - hi)) > -1e-3   # at the face


@pytest.mark.parametrize('mm_s, accel', [(15.6, 0.5), (12.0, 1.0), (15.6, math.pi)])
def test_a_slow_hand_at_a_face_is_not_overrun_at_a_low_acceleration(mm_s, accel):
    # The face counted only from 40 mm/s of the target toward it: the top reached at 39 mm/s
    # (the hand's 15.6 at scale 2.5) with max_joint_accel 0.5 ran 17.6 mm above it.
    t, c = armed_with_origin(max_joint_speed=1.0, max_joint_accel=accel)
    out, _ = _past_the_box(t, c, lambda k: np.array(PALM) + np.array((0.0, 1.0, 0.0)) * min(
        mm_s * 0.008 * k, 400.0), int((400.0 / mm_s + 2.0) / 0.008))
    assert out < 0.001, out


@pytest.mark.parametrize('deg, mm_s', [(30.0, 250.0), (45.0, 300.0), (20.0, 200.0)])
def test_a_fast_hand_coming_obliquely_into_the_table_is_not_overrun(deg, mm_s):
    # At the simulation's limits, a hand moving down at deg off vertical into the table and
    # staying there: with the face cap judged from the target's last step alone, the goal,
    # still catching up with a target already on the table top and sliding along it, slowed
    # down within a period once the target stopped; the servo ran 32 mm (30 deg, 250 mm/s)
    # and 28 mm (45 deg, 300 mm/s) under the table.
    t, c = armed_with_origin(max_joint_speed=1.0, max_joint_accel=math.pi)
    # the simulated controller, which starts each trajectory from its own desired state
    jtc = TrajectoryFollower(HOME, kin.MAX_JOINT_SPEED, kin.JOINT_LOWER, kin.JOINT_UPPER)
    a = math.radians(deg)
    way = 240.0 / math.cos(a)
    q, under = HOME.copy(), 0.0
    for k in range(int(way / mm_s / 0.008) + 250):
        palm = np.array(PALM) + np.array([-math.sin(a), -math.cos(a), 0.0]) * min(mm_s * 0.008 * k, way)
        for dt in np.arange(1, 9) * 0.001:             # the path it runs, every ms
            under = max(under, -float(kin.fk(jtc.sample(c.t + dt)[0])[2, 3]))
        now = c.tick()
        t.on_hand(hand(palm_mm=tuple(palm), stamp=now), now)
        q, qd = jtc.sample(now)
        t.on_joints(q.copy(), now, qd.copy())
        cmd = t.step(now)
        if cmd.points is not None:
            jtc.command(now, cmd.points, cmd.stamp)
    assert t.status.state == TRACKING
    assert under < 0.0035, under
    np.testing.assert_allclose(kin.fk(q)[:3, 3], t.status.target, atol=1e-3)


def slide_lag(gap_mm, noisy):
    """A hand (the shipped filters, the simulation's limits) lowered until the target is
    gap_mm above the table, then sliding sideways at up to 94 mm/s: the executed TCP's rms
    lag (mm) behind the target without the noise along the slide, and how far (mm) it
    went under the table."""
    t = ArmTeleop(ArmTeleopParams(max_joint_speed=1.0, max_joint_accel=math.pi))
    c = Clock()
    t.on_joints(HOME)
    drive(t, c, hand(thumb_up=True), periods=HOLD_PERIODS)
    drive(t, c, hand(rock=True))
    rng = np.random.default_rng(7)
    phases = rng.uniform(0.0, 2.0 * math.pi, 3)
    down = (kin.fk(HOME)[2, 3] * 1000.0 - gap_mm) / t.p.scale
    q, lags, under = HOME.copy(), [], 0.0
    for k in range(int(3.5 / 0.008)):
        s = k * 0.008
        clean = np.array(PALM) - np.array([0.0, down * 0.5 * (1.0 - math.cos(math.pi * min(1.0, s / 1.5))), 0.0])
        clean[0] += 60.0 * math.sin(2.0 * math.pi * max(0.0, s - 1.5) / 4.0)
        palm = clean
        if noisy:       # the bench's hand: a 9 Hz tremor and Gaussian noise, mm
            palm = clean + 0.5 * np.sin(2.0 * math.pi * 9.0 * s + phases) + rng.normal(0.0, 0.3, 3)
        now = c.tick()
        t.on_hand(hand(palm_mm=tuple(palm), stamp=now), now)
        t.on_joints(q)
        t.step(now)
        q = t._servo.state_at(now + 0.008, q)[0]
        tcp = kin.fk(q)[:3, 3]
        under = max(under, -1000.0 * tcp[2])
        if s > 1.7:
            goal = t._tcp_ref + t._axes @ (clean - t._palm_ref) * 0.001 * t.p.scale
            lags.append(np.linalg.norm((tcp - goal)[:2]))
    assert t.status.state == TRACKING
    return 1000.0 * math.sqrt(float(np.mean(np.square(lags)))), under


@pytest.mark.parametrize('gap_mm', [1.0, 3.0])
def test_a_noisy_hand_sliding_just_above_the_table_lags_as_far_above_it(gap_mm):
    # The hand's noise made the target's last step point at the table in most periods: the
    # face cap slowed the whole goal, the slide lagging 10.5 mm rms instead of 4.1.
    lag, under = slide_lag(gap_mm, True)
    far, _ = slide_lag(100.0, True)
    assert lag == pytest.approx(far, abs=0.2), (lag, far)
    assert under < 4.0, under


def test_a_far_catch_up_after_a_joint_state_stall_is_stepped_not_refused_as_another_configuration():
    # The base had to turn 1.57 rad (> MAX_GOAL_JUMP) to where the hand went during the stall:
    # 'only another arm configuration reaches', held for good, 125 IK failures a second.
    t, c = armed_with_origin(max_joint_speed=1.0, max_joint_accel=math.pi)
    a, b = (0.6, -0.6, 0.3), (0.6, 0.6, 0.3)
    _, _, q = _sweep(t, c, HOME.copy(), kin.fk(HOME)[:3, 3], a, 300, then=200)
    pa, pb = _palm_for(t, a), _palm_for(t, b)
    for k in range(188):                                  # 1.5 s without joint states
        now = c.tick()
        t.on_hand(hand(palm_mm=tuple(pa + (pb - pa) * min(1.0, (k + 1) / 94)), stamp=now), now)
        if k == 0:
            t.on_joints(q, now)
        t.step(now)
    assert 'no joint states' in t.status.reason
    zmin, tilt, q = _sweep(t, c, q, b, b, 1, then=500)   # states back, the hand still
    assert t.status.state == TRACKING and t.status.ik_failures == 0, t.status.reason
    np.testing.assert_allclose(kin.fk(q)[:3, 3], b, atol=1e-3)
    assert zmin > 0.28 and tilt < 0.05, (zmin, tilt)


def test_a_thumbs_up_is_held_only_while_it_is_seen():
    t = ArmTeleop()
    c = Clock()
    t.on_joints(HOME)
    drive(t, c, hand(thumb_up=True))                          # a glimpse,
    stall(t, c, 0.5)                                          # a silence,
    drive(t, c, hand(thumb_up=True))                          # another glimpse: not held
    assert t.status.state == DISARMED and 'hold' in t.status.reason
    drive(t, c, hand(thumb_up=True), periods=HOLD_PERIODS)
    assert t.status.state == ARMED
    stall(t, c, t.p.disarm_after + 0.05)                      # the watchdog disarms
    assert t.status.state == DISARMED
    drive(t, c, hand(thumb_up=True))                          # one frame does not re-arm
    assert t.status.state == DISARMED
    drive(t, c, hand(thumb_up=True), periods=HOLD_PERIODS)
    assert t.status.state == ARMED


def test_a_thumbs_up_flag_on_during_the_fist_does_not_count_toward_the_hold():
    # Both flags on in the same frames (a sender's hysteresis at a transition, bindings):
    # the first frame without the fist armed at once, and a pinch then acted.
    t, c = armed_with_origin()
    drive(t, c, hand(fist=True, thumb_up=True), periods=HOLD_PERIODS + 85)
    assert t.status.state == DISARMED and t.status.reason == 'fist'
    cmd = drive(t, c, hand(thumb_up=True))
    assert t.status.state == DISARMED and 'hold' in t.status.reason
    cmd = drive(t, c, hand(pinch=True, pinch_value=0.6))
    assert t.status.state == DISARMED and cmd.gripper is None
    drive(t, c, hand(thumb_up=True), periods=HOLD_PERIODS - 2)     # 0.30 s after the fist
    assert t.status.state == DISARMED
    drive(t, c, hand(thumb_up=True), periods=2)
    assert t.status.state == ARMED


def _moving_with_the_robot_lagging(lag):
    """2.4 s of a hand sweeping back and forth at 100 mm/s; the robot's joints are where the
    plan put them `lag` s before (None: it stopped at home). (teleop, [state per period])"""
    t, c = armed_with_origin(max_joint_speed=1.0, max_joint_accel=math.pi)
    q, planned, states, palm = HOME.copy(), [], [], np.array(PALM)
    for k in range(300):
        palm = palm + np.array([0.0, 0.3, -0.8]) * (1 if (k // 150) % 2 == 0 else -1)
        now = c.tick()
        h = hand(palm_mm=tuple(palm), stamp=now)
        t.on_hand(h, now)
        t.on_joints(q, now)
        cmd = t.step(now)
        states.append((t.status.state, t.status.reason, cmd))
        p = t._servo.planned_at(now)
        planned.append((now, q.copy() if p is None else p))
        if lag is not None:
            q = [x for when, x in planned if when <= now - lag + 1e-9][-1] if now - lag >= planned[0][0] else q
    return t, states


def test_a_robot_that_stops_following_its_commands_disarms_without_a_command():
    # A protective stop while joint states keep coming: the plan ran away from the robot
    # (0.85 rad in 2 s), and the first command it took again would have asked for all of it.
    t, states = _moving_with_the_robot_lagging(None)
    first = next(i for i, (state, _, _) in enumerate(states) if state == DISARMED)
    assert 'does not follow its commands' in states[first][1]
    assert states[first][2].points is None and states[first][2].q is None
    assert not any(sent(cmd) for _, _, cmd in states[first:])
    # Off by the plan's 0.6 s at 1 rad/s (+ 0.02), then for 0.25 s more at most.
    off = float(states[first][1].split(' rad from')[0].split()[-1])
    assert OFF_PLAN_LAG_S * 1.0 < off <= (OFF_PLAN_LAG_S + OFF_PLAN_S + 0.01) * 1.0 + 0.02
    assert t._servo.planned_at(0.0) is None          # plans start from the measured joints


@pytest.mark.parametrize('lag', [0.0, 0.2, 0.5])
def test_a_robot_following_late_is_not_taken_for_one_that_stopped(lag):
    # A simulator under load lags its commands by up to 0.5 s before it counts afresh.
    _, states = _moving_with_the_robot_lagging(lag)
    assert all(state == TRACKING for state, _, _ in states), {r for _, r, _ in states}


def test_stall_while_armed_without_origin_resumes_armed():
    t = ArmTeleop()
    c = Clock()
    t.on_joints(HOME)
    drive(t, c, hand(thumb_up=True), periods=HOLD_PERIODS)
    assert t.status.state == ARMED
    stall(t, c, 0.4)
    assert t.status.state == HOLDING
    cmd = drive(t, c, hand(palm_mm=(60.0, 250.0, 0.0)))
    assert t.status.state == ARMED and cmd.q is None and not t.status.origin_set
    drive(t, c, hand(rock=True))
    assert t.status.state == TRACKING


def test_loss_longer_than_disarm_after_disarms_and_needs_a_new_thumbs_up():
    t, c = armed_with_origin()
    stall(t, c, t.p.disarm_after + 0.05)
    assert t.status.state == DISARMED and 'watchdog' in t.status.reason
    for _ in range(20):
        cmd = drive(t, c, hand(palm_mm=(80.0, 260.0, -40.0), pinch=True, pinch_value=0.6))
        assert not sent(cmd) and t.status.state == DISARMED
    drive(t, c, hand(thumb_up=True), periods=HOLD_PERIODS)
    cmd = drive(t, c, hand(palm_mm=(80.0, 260.0, -40.0)))
    assert t.status.state == ARMED and cmd.q is None          # a new rock is needed too


@pytest.mark.parametrize('returning, reason', [(dict(present=False), 'hand left the sensor'),
                                               (dict(fist=True), 'fist')])
def test_lost_hand_or_fist_after_a_stall_disarms(returning, reason):
    t, c = armed_with_origin()
    stall(t, c, 0.4)
    assert t.status.state == HOLDING
    cmd = drive(t, c, hand(**returning))
    assert t.status.state == DISARMED and t.status.reason == reason
    assert not sent(cmd)                        # already held by the stall
    cmd = drive(t, c, hand(palm_mm=(80.0, 260.0, -40.0)), periods=10)
    assert not sent(cmd) and t.status.state == DISARMED


def test_stale_input_never_moves_the_robot():
    # A source that stalls and then bursts its backlog (stamps continue, arriving late):
    # the backlog is refused, so it neither resumes nor moves the arm.
    t, c = armed_with_origin()
    drive(t, c, hand(palm_mm=(0.0, 210.0, 0.0)), periods=5)
    t0 = c.t
    cmds = stall(t, c, 0.6)
    assert sum(sent(x) for x in cmds) == 1                   # the hold, nothing else
    rejected = t.status.rejected_inputs
    for k in range(30):         # captured in the stall's first 0.3 s: > max_input_age late
        h = hand(palm_mm=(150.0, 400.0, -150.0), rock=k % 2 == 0)
        h.stamp = t0 + 0.01 * k
        now = c.tick(0.0005)
        assert t.on_hand(h, now) is not None                 # late: refused
        assert not sent(t.step(now))
    assert t.status.rejected_inputs == rejected + 30 and t.status.state == HOLDING
    cmds = stall(t, c, 0.5)
    assert t.status.state == DISARMED and not any(sent(x) for x in cmds)


def test_a_new_input_connection_judges_lateness_afresh():
    # A baseline taken while this node's clock lagged (sim time) makes every later message
    # look late by a constant: refused until the connection is re-made and judged afresh.
    t, c = armed_with_origin()
    base = c.t

    def at(stamp, now):
        h = hand(palm_mm=(0.0, 210.0, 0.0))
        h.stamp = base + stamp
        return t.on_hand(h, base + now)
    assert at(0.6, 0.0) is None             # received "before" it was stamped: clock lagging
    assert all(at(0.61 + 0.01 * k, 0.612 + 0.01 * k).startswith('late') for k in range(3))
    t.new_input_connection()
    assert not any(at(0.65 + 0.01 * k, 0.652 + 0.01 * k) for k in range(3))
    assert at(0.70, 1.2).startswith('late')  # held up on top of the new baseline: refused


def test_disarm_after_must_be_at_least_input_timeout():
    with pytest.raises(ValueError, match='disarm_after'):
        ArmTeleopParams.from_dict({'input_timeout': 0.5, 'disarm_after': 0.3})
    with pytest.raises(ValueError, match='disarm_after'):
        ArmTeleopParams.from_dict({'disarm_after': 11.0})
    p = ArmTeleopParams.from_dict({'input_timeout': 0.5, 'disarm_after': 0.5})
    assert p.disarm_after == 0.5          # equal: every stall disarms, as before


def test_hand_leaving_disarms():
    t, c = armed_with_origin()
    drive(t, c, hand(present=False))
    assert t.status.state == DISARMED and not t.status.origin_set


def test_unreachable_target_holds_then_recovers():
    t, c = armed_with_origin(scale=10.0, workspace_min=(-3, -3, -3), workspace_max=(3, 3, 3))
    cmd = drive(t, c, hand(palm_mm=(0.0, 200.0, -250.0)))   # 2.5 m forward: out of reach
    assert t.status.state == HOLDING and t.status.ik_failures == 1
    np.testing.assert_array_equal(cmd.q, HOME)
    cmd = drive(t, c, hand(palm_mm=(0.0, 200.0, -250.0)))
    assert cmd.q is None                                    # hold is sent once
    cmd = drive(t, c, hand(palm_mm=(0.0, 205.0, 0.0)))
    assert t.status.state == TRACKING and cmd.q is not None


def test_a_hold_starts_a_command_lead_after_it_is_planned_too():
    t, c = armed_with_origin(command_lead=0.01)
    cmd = drive(t, c, hand(palm_mm=(30.0, 200.0, 0.0)))
    assert cmd.stamp == pytest.approx(c.t + 0.01)
    sent, held = [], False
    for _ in range(40):                              # 0.32 s without hand input: a hold
        now = c.tick()
        t.on_joints(t._q)
        cmd = t.step(now)
        if cmd.points:
            sent.append((now, cmd.stamp))
            held = held or t.status.state == HOLDING
    assert t.status.state == HOLDING and held
    assert all(stamp == pytest.approx(now + 0.01) for now, stamp in sent)


def test_the_other_arm_configuration_is_refused_after_a_hold_too():
    # The pan 0.05 rad from its +2pi limit: a target a few cm on needs the pan past the
    # limit, so the nearest solution is another configuration. It was refused for one
    # period only: after the hold there was no last goal to compare with, and the next
    # period swung the joints 2.7 rad (and the TCP out of the workspace) to reach it.
    q0 = HOME.copy()
    q0[0] = 2 * math.pi - 0.05
    t = ArmTeleop(ArmTeleopParams(filter_min_cutoff_hz=0.0, max_joint_speed=1.0))
    c = Clock()
    t.on_joints(q0)
    drive(t, c, hand(thumb_up=True), periods=HOLD_PERIODS)
    drive(t, c, hand(rock=True))
    assert t.status.state == TRACKING
    q, reasons, moves = q0.copy(), set(), 0
    for k in range(160):
        cmd = drive(t, c, hand(palm_mm=(-min(40.0, 0.5 * k), 200.0, 0.0)), q=q)
        if cmd.q is not None:
            assert float(np.abs(cmd.q - q).max()) < 0.1, (k, cmd.q, q)
            moves += t.status.state == TRACKING
            q = cmd.q.copy()
        reasons.add(t.status.reason)
    # it tracked toward the limit first, then held short of the other configuration
    assert moves >= 5 and q[0] > q0[0] and t.status.state == HOLDING and abs(q[0] - q0[0]) < 0.1
    assert any(r.startswith('only another arm configuration reaches') for r in reasons)
    assert 'target reachable again' not in reasons


@pytest.mark.parametrize('bad, why', [
    (dict(palm_mm=(math.nan, 200.0, 0.0)), 'not a trackable hand'),
    (dict(palm_mm=(0.0, math.inf, 0.0)), 'not a trackable hand'),
    (dict(palm_mm=(1e9, 0.0, 0.0)), 'not a trackable hand'),
    (dict(pinch_value=math.nan), 'pinch value nan is not finite')])
def test_bad_input_is_rejected_and_counted(bad, why):
    t, c = armed_with_origin()
    before = t.status.target
    assert len(before) == 3                      # a target to compare with (set at the rock)
    now = c.tick()
    assert why in t.on_hand(hand(stamp=now, **bad), now)
    assert t.status.rejected_inputs == 1
    t.step(now)
    assert t.status.target == before


def test_out_of_order_messages_are_dropped():
    t, c = armed_with_origin()
    before = t.status.target
    now = c.tick()
    # the rock arrived 8 ms ago; a hand stamped 1 s earlier (far up) is older than it
    why = t.on_hand(hand(stamp=now - 1.0, palm_mm=(0.0, 300.0, 0.0)), now)
    assert why.startswith('out of order: 0.99')
    assert t.status.rejected_inputs == 1
    t.step(now)
    assert t.status.target == before             # the dropped hand moved nothing


@pytest.mark.parametrize('stamp', [math.nan, math.inf, -math.inf])
def test_non_finite_stamp_is_rejected_and_keeps_the_order_check(stamp):
    t, c = armed_with_origin()
    now = c.tick()
    last = now
    assert t.on_hand(hand(stamp=last), now) is None
    assert 'not finite' in t.on_hand(hand(stamp=stamp), c.tick(0.001))
    assert t.status.rejected_inputs == 1
    # NaN taken as the last stamp would let an older message through
    assert t.on_hand(hand(stamp=last - 0.05), c.tick(0.001)).startswith('out of order')
    assert t.status.rejected_inputs == 2


def test_proportional_gripper_follows_pinch_value_and_sends_changes_only():
    t, c = armed_with_origin(gripper_mode='proportional')
    assert drive(t, c, hand(pinch=True, pinch_value=0.3)).gripper == pytest.approx(0.3)
    assert drive(t, c, hand(pinch=True, pinch_value=0.302)).gripper is None
    assert drive(t, c, hand(pinch=False)).gripper == 0.0


def _pinch_far_away(t, c, periods, q=HOME):
    """Pinch with the hand 100 mm from the origin while the robot reports q: the
    gripper commands sent, one per period."""
    far = (PALM[0] + 100.0, PALM[1], PALM[2])
    return [drive(t, c, hand(palm_mm=far, pinch=True), q=q) for _ in range(periods)]


def test_a_grasp_waits_until_the_tool_is_where_the_hand_put_it():
    t, c = armed_with_origin()
    # The robot has not moved yet (still catching up): the grasp waits.
    cmds = _pinch_far_away(t, c, 60)
    assert [cmd.gripper for cmd in cmds] == [None] * 60 and cmds[-1].q is not None
    # It gets there: the grasp goes in that period, once.
    there = target_q(t)
    cmds = _pinch_far_away(t, c, 3, q=there)
    assert [cmd.gripper for cmd in cmds] == [pytest.approx(0.43), None, None]
    # Letting go waits the same way for the tool.
    cmds = [drive(t, c, hand(palm_mm=PALM), q=there) for _ in range(3)]
    assert [cmd.gripper for cmd in cmds] == [None] * 3
    assert drive(t, c, hand(palm_mm=PALM), q=HOME).gripper == 0.0


def test_the_grasps_wait_starts_again_after_a_stall():
    t, c = armed_with_origin()
    near = (PALM[0] + 50.0, PALM[1], PALM[2])         # within reanchor_beyond: caught up
    for _ in range(100):                               # 0.8 s of waiting for the tool
        assert drive(t, c, hand(palm_mm=near, pinch=True), q=HOME).gripper is None
    for _ in range(40):                                # 0.32 s without hand input: held
        t.step(c.tick())
    assert t.status.state == HOLDING
    sent = [drive(t, c, hand(palm_mm=near, pinch=True), q=HOME).gripper for _ in range(150)]
    assert t.status.state == TRACKING and 'same origin' in t.status.reason
    # Not at once for the time already spent waiting before the stall: a full wait.
    first = next(k for k, g in enumerate(sent) if g is not None)
    assert abs(first - 1.0 / 0.008) <= 1


@pytest.mark.parametrize('wait_s', [1.0, 0.0])
def test_a_grasp_waits_no_longer_than_gripper_wait_s(wait_s):
    t, c = armed_with_origin(gripper_wait_s=wait_s)
    sent = [k for k, cmd in enumerate(_pinch_far_away(t, c, 200)) if cmd.gripper is not None]
    # The robot never gets there (held, stalled or out of reach): the grasp goes anyway.
    assert len(sent) == 1 and abs(sent[0] - wait_s / 0.008) <= 1      # 8 ms periods


@pytest.mark.parametrize('bad', [dict(mode='fly'), dict(gripper_mode='maybe'),
                                 dict(axis_map=((1, 0), (0, 1))), dict(max_joint_speed=0),
                                 dict(workspace_min=(1, 1, 1), workspace_max=(0, 0, 0))])
def test_bad_parameters_are_refused(bad):
    with pytest.raises(ValueError):
        ArmTeleopParams(**bad).validate()


@pytest.mark.parametrize('name, value', [('input_timeout', 0.01), ('joint_timeout', 0.005)])
def test_a_watchdog_shorter_than_a_message_interval_is_refused_by_name(name, value):
    # input_timeout 0.005 s made every gap between 120 Hz frames a stall (the arm held and
    # resumed each frame).
    with pytest.raises(ValueError, match=name + r'.*>= 0\.05\b'):
        ArmTeleopParams.from_dict({name: value})


def test_an_unknown_parameter_is_refused_by_name():
    with pytest.raises(ValueError, match='unknown arm teleop parameters: speed'):
        ArmTeleopParams.from_dict({'speed': 1})


finite = st.one_of(st.floats(-1e12, 1e12), st.floats(allow_nan=True, allow_infinity=True))


@settings(max_examples=3000, deadline=None)
@given(palm=st.tuples(finite, finite, finite), pinch_value=finite,
       flags=st.tuples(st.booleans(), st.booleans(), st.booleans(), st.booleans(), st.booleans()),
       mode=st.sampled_from(['imitation', 'joystick']))
@pytest.mark.slow
def test_fuzzed_input_never_leaves_the_limits(palm, pinch_value, flags, mode):
    t, c = armed_with_origin(mode=mode)
    present, fist, thumb, pinch, rock = flags
    now = c.tick()
    t.on_hand(ArmInput(present=present, palm_mm=palm, fist=fist, thumb_up=thumb, pinch=pinch,
                        pinch_value=pinch_value, rock=rock, stamp=now), now)
    cmd = t.step(now)
    if cmd.q is not None:
        assert np.all(np.isfinite(cmd.q))
        assert np.all(cmd.q <= kin.JOINT_UPPER) and np.all(cmd.q >= kin.JOINT_LOWER)
        check_points(cmd, t.p.max_joint_speed, kin.MAX_JOINT_ACCEL[0])
        lo, hi = np.array(t.p.workspace_min) - 1e-6, np.array(t.p.workspace_max) + 1e-6
        # the goal, and every point the controller is sent on the way to it
        for q in [cmd.q] + [q for _, q, _ in cmd.points]:
            pose = kin.fk(q)
            assert np.all(pose[:3, 3] >= lo) and np.all(pose[:3, 3] <= hi)
            assert kin.tilt_and_yaw(pose[:3, :3])[0] <= t.p.max_tool_tilt + 1e-6
    if cmd.gripper is not None:
        assert 0.0 <= cmd.gripper <= 0.8


# -- orientation modes --------------------------------------------------------------------
def _rotated(t, c, **angles):
    return drive(t, c, hand(**angles))


@pytest.mark.parametrize('side_sign', [1.0, -1.0])
def test_yaw_mode_turns_the_tool_about_the_vertical_with_the_hand(side_sign):
    # Both hands use the same code: only the angle's sign differs between the two runs.
    t, c = armed_with_origin(orientation='yaw', orientation_scale=1.0)
    _rotated(t, c, turn=-0.5 * side_sign, rotate=0.3, swing=0.2)
    tilt, yaw = kin.tilt_and_yaw(target_rotation(t))
    # Leap y maps to base z; a hand turning right (+turn) turns the tool clockwise.
    assert yaw == pytest.approx(0.5 * side_sign, abs=1e-9)
    assert tilt == pytest.approx(0.0, abs=1e-9)      # roll and pitch ignored


@pytest.mark.parametrize('turn, kept', [(1.5, False), (0.1, True)])
def test_a_hand_back_from_a_stall_turned_far_re_anchors_the_origin(turn, kept):
    # Only its position was weighed: a hand back turned 1.5 rad with the palm in place kept
    # the origin, and the tool target turned 1.5 rad in one period.
    t, c = armed_with_origin(orientation='yaw', orientation_scale=1.0)
    drive(t, c, hand(), periods=5)
    before = np.array(t.status.target_rotation)
    stall(t, c, 0.48)
    assert t.status.state == HOLDING
    drive(t, c, hand(turn=turn))
    assert t.status.reason.endswith('same origin, 0.000 m to catch up' if kept
                                    else 'origin re-anchored'), t.status.reason
    jump = kin.rotation_error(before, np.array(t.status.target_rotation))
    assert jump == pytest.approx(turn if kept else 0.0, abs=1e-6)


def test_reanchor_beyonds_doc_names_all_that_re_anchors():
    # It said "only when the hand moved the target further than this": a hand still in
    # joystick mode, or one that turned the tool's target in the yaw or full mode, also
    # re-anchors (both tested above).
    doc = TELEOP_PARAMS['reanchor_beyond'].doc
    assert 'more than %g rad' % REANCHOR_TURN_RAD in doc and 'always in joystick mode' in doc


@pytest.mark.parametrize('orientation', ['yaw', 'full'])
def test_max_tool_turn_stays_measured_from_the_yaw_at_the_rock_across_re_anchors(orientation):
    # Each re-anchoring stall re-centred the clamp on the tool's yaw then: three stalls
    # with the hand turned on past it turned the tool 2 rad from its yaw at the rock.
    t, c = armed_with_origin(orientation=orientation, orientation_scale=1.0, max_tool_turn=0.5,
                             max_joint_speed=1.0, max_joint_accel=math.pi)
    q = HOME.copy()
    yaw_rock = kin.tilt_and_yaw(kin.fk(q)[:3, :3])[1]
    palm, turn = np.array(PALM), 0.0
    for k in range(3):
        for _ in range(80):                    # the hand turns 0.8 rad on, the tool to the clamp
            turn += 0.01
            _, q = follow(t, c, hand(palm_mm=tuple(palm), turn=turn), 1, q)
        _, q = follow(t, c, hand(palm_mm=tuple(palm), turn=turn), 150, q)
        yaw = kin.tilt_and_yaw(kin.fk(q)[:3, :3])[1]
        assert abs(wrap_angle(yaw - yaw_rock)) == pytest.approx(0.5, abs=2e-3), (k, yaw - yaw_rock)
        held = [x for x in stall(t, c, 0.5, q=q) if sent(x)]
        q = held[0].points[-1][1]
        palm = palm + [50.0 if k % 2 == 0 else -50.0, 0.0, 0.0]    # 0.125 m of target
        _, q = follow(t, c, hand(palm_mm=tuple(palm), turn=turn), 1, q)
        assert 'origin re-anchored' in t.status.reason, t.status.reason
        # Nothing jumps: the tool's target is where the hold put it.
        assert kin.rotation_error(target_rotation(t), kin.fk(held[0].points[-1][1])[:3, :3]) < 1e-6
    # The hand's turn maps as it did at the rock (no turn was unseen): 0.3 rad is 0.3 rad.
    _, q = follow(t, c, hand(palm_mm=tuple(palm), turn=0.3), 300, q)
    yaw = kin.tilt_and_yaw(kin.fk(q)[:3, :3])[1]
    assert abs(wrap_angle(yaw - yaw_rock)) == pytest.approx(0.3, abs=2e-3)


@pytest.mark.parametrize('mode', ['imitation', 'joystick'])
@pytest.mark.parametrize('orientation', ['yaw', 'full'])
@pytest.mark.parametrize('max_turn', [math.pi, math.pi - 0.01])
def test_a_re_anchor_with_the_tool_held_at_a_max_tool_turn_of_pi_keeps_the_clamps_side(
        mode, orientation, max_turn):
    # At pi, the held tool's turn measured nearest 0 came out on the other side of the
    # clamp: the tool then turned on past it with the hand, and never back.
    t, c = armed_with_origin(mode=mode, orientation=orientation, orientation_scale=1.0,
                             max_tool_turn=max_turn, max_joint_speed=1.0, max_joint_accel=math.pi)
    q = HOME.copy()
    yaw_rock = kin.tilt_and_yaw(kin.fk(q)[:3, :3])[1]
    palm, turns = np.array(PALM), [0.0]

    def turn_to(turn, periods, q):
        for _ in range(periods):
            _, q = follow(t, c, hand(palm_mm=tuple(palm), turn=turn), 1, q)
            yaw = kin.tilt_and_yaw(kin.fk(q)[:3, :3])[1] - yaw_rock
            turns.append(turns[-1] + wrap_angle(yaw - turns[-1]))
        return q

    hand_turn = 0.0
    while hand_turn < max_turn + 0.2:           # the hand turns past the clamp
        hand_turn = min(max_turn + 0.2, hand_turn + 0.01)
        q = turn_to(hand_turn, 1, q)
    q = turn_to(hand_turn, 300, q)
    assert abs(turns[-1]) == pytest.approx(max_turn, abs=2e-3)
    held = [x for x in stall(t, c, 0.33, q=q) if sent(x)]
    q = held[0].points[-1][1]
    if mode == 'imitation':
        palm = palm + [60.0, 0.0, 0.0]          # 0.15 m of target: a re-anchor
    q = turn_to(hand_turn, 1, q)
    assert 'origin re-anchored' in t.status.reason, t.status.reason
    for k in range(80):                         # the hand turns on: the tool stays at the clamp
        q = turn_to(hand_turn + 0.01 * (k + 1), 1, q)
    q = turn_to(hand_turn + 0.8, 150, q)
    assert abs(turns[-1]) <= max_turn + 2e-3, turns[-1]
    q = turn_to(hand_turn - 0.4, 300, q)        # and back: it turns back
    assert abs(turns[-1]) < max_turn - 0.15, turns[-1]


@pytest.mark.parametrize('older_by, disarmed', [(5.0, True), (0.5, True), (-0.3, False)])
def test_a_stream_back_from_a_stall_at_older_stamps_disarms(older_by, disarmed):
    # A bag played again after a 0.32 s silence: its hand was taken as the same session's,
    # and the arm tracked on from the old origin without a thumbs-up.
    from leap_teleop.control.input_check import InputStream
    s = InputStream(max_age=0.25, gap=0.2)
    assert s.check(10.0, 10.0) is None and not s.rewound
    assert s.check(9.0, 10.5) is None and s.rewound                 # after a silence, older
    assert s.check(9.01, 10.51) is None and not s.rewound
    t, c = armed_with_origin()
    drive(t, c, hand(palm_mm=(10.0, 200.0, 0.0)), periods=5)
    last = c.t
    for _ in range(40):                                   # 0.32 s of silence: a hold
        t.on_joints(t._q, c.tick())
        t.step(c.t)
    assert t.status.state == HOLDING
    now = c.tick()
    h = hand(palm_mm=(10.0, 200.0, 0.0))
    h.stamp = last - older_by if older_by > 0 else now
    assert t.on_hand(h, now) is None
    t.on_joints(t._q, now)
    t.step(now)
    assert (t.status.state == DISARMED) == disarmed, t.status.reason
    if disarmed:
        assert t.status.reason.startswith('the hand input began again at older stamps')


def test_full_mode_follows_the_palm_through_the_axis_map_and_scale():
    t, c = armed_with_origin(orientation='full', orientation_scale=0.5)
    cmd = _rotated(t, c, swing=0.4)                  # pitch up about Leap x
    # Leap x maps to base -y: the tool turns by -0.2 rad about base y, from pointing down.
    expected = kin.rotation_from_vector([0.0, -0.2, 0.0]) @ kin.fk(HOME)[:3, :3]
    np.testing.assert_allclose(target_rotation(t), expected, atol=1e-9)
    np.testing.assert_allclose(t.status.target, kin.fk(HOME)[:3, 3], atol=1e-9)
    # the goal turns toward it about the same axis, in place
    np.testing.assert_allclose(kin.fk(cmd.q)[:3, 3], kin.fk(HOME)[:3, 3], atol=1e-9)
    turned = kin.rotation_vector(kin.fk(cmd.q)[:3, :3] @ kin.fk(HOME)[:3, :3].T)
    assert -0.2 < turned[1] < 0.0 and abs(turned[0]) < 1e-9 and abs(turned[2]) < 1e-9


def test_full_mode_clamps_tilt_and_turn_like_the_workspace():
    t, c = armed_with_origin(orientation='full', max_tool_tilt=0.3, max_tool_turn=0.4)
    cmd = _rotated(t, c, swing=1.2, turn=-1.0)
    tilt, yaw = kin.tilt_and_yaw(np.asarray(t.status.target_rotation))
    assert tilt == pytest.approx(0.3, abs=1e-9) and yaw == pytest.approx(0.4, abs=1e-9)
    tilt, yaw = kin.tilt_and_yaw(kin.fk(target_q(t))[:3, :3])
    assert tilt == pytest.approx(0.3, abs=1e-9) and yaw == pytest.approx(0.4, abs=1e-9)
    tilt, yaw = kin.tilt_and_yaw(kin.fk(cmd.q)[:3, :3])         # a step toward it
    assert 0.0 < tilt < 0.3 and 0.0 < yaw < 0.4


@pytest.mark.parametrize('axis', [(0.0, 0.0, 1.0), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (1.0, 0.0, 1.0)],
                         ids=['palm up', 'fingers up and back', 'turned back', 'rolled and pitched'])
@pytest.mark.parametrize('scale', [1.0, 0.5, 3.0])
def test_full_mode_follows_a_hand_turned_past_half_a_turn_without_a_jump(axis, scale):
    # The hand turns steadily from the rock to 3.4 rad about one axis, lingers around pi,
    # and comes back, with the angles the sender measures (they jump where the palm turns
    # up or the fingers pass the vertical). The filtered, clamped tool target moves on in
    # small steps, on the side it went over, with no hold.
    t = ArmTeleop(ArmTeleopParams(orientation='full', orientation_scale=scale,
                                  filter_min_cutoff_hz=0.0, rotation_min_cutoff_hz=1.0))
    c = Clock()
    t.on_joints(HOME)
    drive(t, c, hand(thumb_up=True), periods=HOLD_PERIODS)
    drive(t, c, hand(rock=True))
    axis = np.asarray(axis) / np.linalg.norm(axis)
    neutral = (np.array([0.0, -1.0, 0.0]), np.array([0.0, 0.0, -1.0]))
    angles = list(np.linspace(0.0, 3.4, 140)) + [3.05, 3.25] * 4 + list(np.linspace(3.4, 0.0, 140))
    last, worst = None, 0.0
    for angle in angles:
        R = kin.rotation_from_vector(axis * angle)
        rotate, turn, swing = (wrap_angle(a) for a in hand_angles(R @ neutral[0], R @ neutral[1]))
        drive(t, c, hand(rotate=rotate, turn=turn, swing=swing), periods=3)
        target = np.asarray(t.status.target_rotation)
        if last is not None:
            worst = max(worst, kin.rotation_error(last, target))
        last = target
        assert t.status.state == TRACKING, t.status.reason
    assert worst < 0.06 * max(1.0, scale / 2) and t.status.ik_failures == 0
    np.testing.assert_allclose(last, kin.fk(HOME)[:3, :3], atol=0.05)


def test_a_live_scale_applies_to_the_motion_from_then_on_and_moves_nothing_by_itself():
    t, c = armed_with_origin(scale=2.5)
    drive(t, c, hand(palm_mm=(100.0, 200.0, 0.0)), periods=50)     # held 10 cm out
    before = np.array(t.status.target)
    t.retune({'scale': 5.0})
    drive(t, c, hand(palm_mm=(100.0, 200.0, 0.0)))
    np.testing.assert_allclose(t.status.target, before, atol=1e-9)  # it was 0.25 m away
    drive(t, c, hand(palm_mm=(110.0, 200.0, 0.0)))                  # 10 mm more: 5 cm
    assert np.linalg.norm(np.array(t.status.target) - before) == pytest.approx(0.05, abs=1e-9)
    assert t.status.state == TRACKING


@pytest.mark.parametrize('orientation', ['yaw', 'full'])
def test_a_live_orientation_scale_turns_nothing_by_itself(orientation):
    t, c = armed_with_origin(orientation=orientation)
    drive(t, c, hand(turn=-0.6), periods=50)
    before = np.array(t.status.target_rotation)
    t.retune({'orientation_scale': 2.0})
    drive(t, c, hand(turn=-0.6))
    assert kin.rotation_error(before, np.array(t.status.target_rotation)) < 1e-9  # was 0.6 rad
    drive(t, c, hand(turn=-0.7))                                     # 0.1 rad more: 0.2
    turned = kin.tilt_and_yaw(np.array(t.status.target_rotation))[1] - kin.tilt_and_yaw(before)[1]
    assert turned == pytest.approx(0.2, abs=1e-6)
    t.retune({'orientation_scale': 1.0})
    drive(t, c, hand())                                              # the hand back to the rock
    np.testing.assert_allclose(t.status.target_rotation, kin.fk(HOME)[:3, :3], atol=0.25)


def test_orientation_is_captured_at_the_rock():
    t, c = armed_with_origin(orientation='yaw', max_joint_speed=1.0, max_joint_accel=3.0)
    drive(t, c, hand(turn=-0.6), periods=250)        # 2 s: the servo gets there
    drive(t, c, hand(turn=-0.6, rock=True))          # new origin with the hand turned
    cmd = drive(t, c, hand(turn=-0.6))
    # The tool keeps the yaw it had at the rock; the hand's turn counts from there.
    assert kin.tilt_and_yaw(kin.fk(cmd.q)[:3, :3])[1] == pytest.approx(0.6, abs=1e-6)
    drive(t, c, hand(turn=-0.8))
    assert kin.tilt_and_yaw(target_rotation(t))[1] == pytest.approx(0.8, abs=1e-6)


def test_fixed_mode_ignores_the_hand_rotation():
    t, c = armed_with_origin()
    cmd = _rotated(t, c, turn=0.7, rotate=0.5, swing=0.3)
    np.testing.assert_allclose(kin.fk(cmd.q)[:3, :3], kin.tool_down(), atol=1e-9)


def test_wrist_ranges_limit_the_ik():
    # wrist 3 may not turn past +-0.3 rad: a 0.5 rad tool yaw has no solution -> hold.
    t, c = armed_with_origin(orientation='yaw', wrist_lower=(-6.28, -6.28, -0.3),
                             wrist_upper=(6.28, 6.28, 0.3))
    _rotated(t, c, turn=-0.5)
    assert t.status.state == HOLDING


def test_non_angle_rotation_is_rejected():
    t, c = armed_with_origin(orientation='full')
    now = c.tick()
    assert 'is not an angle' in t.on_hand(hand(turn=float('nan'), stamp=now), now)
    assert t.status.rejected_inputs == 1


def test_the_diagnostics_report_warns_while_holding():
    teleop = ArmTeleop()
    level, summary, values = teleop.diagnostics()
    assert level == 'ok' and summary == 'disarmed: waiting for thumbs-up'
    assert dict(values) == {'origin set': False, 'rejected inputs': 0, 'IK failures': 0}
    teleop.status.state, teleop.status.reason = HOLDING, 'input stalled'
    assert teleop.diagnostics()[:2] == ('warn', 'holding: input stalled')


def test_a_joystick_push_out_of_reach_does_not_wind_the_target_up():
    # The target integrated on while the IK failed: after 5 s of pushing out of reach the
    # arm followed a pull-back only 1.9 s later.
    t, c = armed_with_origin(mode='joystick', max_tcp_speed=0.25, max_joint_speed=1.0,
                             max_joint_accel=math.pi)
    q, held_at = HOME.copy(), None
    for _ in range(625):
        _, q = follow(t, c, hand(palm_mm=(-200.0, 400.0, -200.0)), 1, q)
        if held_at is None and t.status.state == HOLDING:
            held_at = np.array(t.status.target)
    assert t.status.state == HOLDING and t.status.ik_failures > 0
    assert np.linalg.norm(np.array(t.status.target) - held_at) < 0.01
    _, q = follow(t, c, hand(palm_mm=(200.0, 0.0, 200.0)), 2, q)
    assert t.status.state == TRACKING


def test_joystick_target_stays_near_a_slow_arm_and_the_dead_zone_stops_it():
    # The target integrated from itself ran 0.24 m ahead of a 0.05 rad/s arm in a 2 s push;
    # back in the dead zone the arm drove on to it for 5 s.
    t, c = armed_with_origin(mode='joystick')
    q = HOME.copy()
    for _ in range(250):                                   # 100 mm beyond the origin for 2 s
        _, q = follow(t, c, hand(palm_mm=(0.0, 200.0, -100.0)), 1, q)
        lead = np.linalg.norm(np.array(t.status.target) - kin.fk(q)[:3, 3])
        assert lead <= t.p.max_tcp_speed * 0.1 + 0.01, lead
    released = kin.fk(q)[:3, 3]
    assert np.linalg.norm(released - kin.fk(HOME)[:3, 3]) > 0.03       # it did move
    _, q = follow(t, c, hand(), 375, q)                    # 3 s in the dead zone
    assert t.status.state == TRACKING
    assert np.linalg.norm(kin.fk(q)[:3, 3] - released) < 0.005
    assert not t._servo.moving or np.abs(t._servo.state_at(c.t, q)[1]).max() < 1e-9


@pytest.mark.parametrize('lead', [0.0, 0.05])
def test_a_joystick_target_is_not_dragged_along_by_an_arm_that_ran_past_it(lead):
    # A push straight up at the simulation's limits: the target stops at the box's top, the
    # arm brakes past it, drifting in x, and the target, re-based on the arm, slid 438 mm
    # along the top at up to 0.71 m/s (the TCP at 0.75, 185 mm out of the box).
    t, c = armed_with_origin(mode='joystick', max_joint_speed=1.0, max_joint_accel=math.pi,
                             servo_lead=lead)
    q, last = HOME.copy(), np.array(t.status.target)
    start = last.copy()
    for k in range(500):
        _, q = follow(t, c, hand(palm_mm=(0.0, 200.0 + 150.0 * min(1.0, k / 25), 0.0)), 1, q)
        target = np.array(t.status.target)
        assert np.linalg.norm(target - last) <= t.p.max_tcp_speed * 0.008 + 1e-9
        np.testing.assert_allclose(target[:2], start[:2], atol=1e-9)       # straight up
        last = target
    assert target[2] == pytest.approx(t.p.workspace_max[2])
    np.testing.assert_allclose(kin.fk(q)[:3, 3], target, atol=1e-3)


@pytest.mark.parametrize('fields', [dict(palm_mm=(10.0, 200.0)), dict(palm_mm=(10.0, 200.0, 0.0, 5.0)),
                                    dict(palm_mm=(1.0, 'x', 3.0)), dict(pinch_value=None),
                                    dict(turn='0.1'), dict(stamp=None)])
def test_hand_fields_of_the_wrong_shape_or_type_are_refused_not_raised(fields):
    # Reachable through the Python API only (ROS messages have typed fields): a palm of two
    # values was taken and raised in step(), which ends the control loop.
    t, c = armed_with_origin()
    before = t.status.rejected_inputs
    now = c.tick()
    assert t.on_hand(hand(**dict({'stamp': now}, **fields)), now) in (
        'hand fields are not numbers', 'palm position %s is not a trackable hand' % (fields.get('palm_mm'),))
    assert t.status.rejected_inputs == before + 1
    t.on_joints(t._q)
    t.step(now)
    assert t.status.state == TRACKING


def test_a_robot_moved_while_disarmed_is_not_taken_for_one_that_stopped_when_re_armed():
    # The old hold's plan (a fist while moving) was compared with a robot moved by hand
    # since: the fresh thumbs-up was disarmed again as 'does not follow its commands'.
    t, c = armed_with_origin()
    q = HOME.copy()
    _, q = follow(t, c, hand(palm_mm=(0.0, 260.0, -60.0)), 60, q)
    _, q = follow(t, c, hand(fist=True), 1, q)
    assert t.status.state == DISARMED
    for _ in range(250):                                  # the robot brakes along the hold
        now = c.tick()
        planned = t._servo.planned_at(now)
        q = q if planned is None else planned
        t.on_hand(hand(stamp=now), now)
        t.on_joints(q, now)
        t.step(now)
    moved = q + [0.3, -0.2, 0.2, 0.0, 0.0, 0.0]
    for _ in range(HOLD_PERIODS + 60):
        now = c.tick()
        t.on_hand(hand(thumb_up=True, stamp=now), now)
        t.on_joints(moved, now)
        t.step(now)
    assert t.status.state == ARMED, t.status.reason


def test_a_speed_limit_lowered_live_is_not_taken_for_a_robot_that_stopped():
    # A robot following 0.2 s late (under the 0.5 s allowed) while max_joint_speed drops
    # from 1 to 0.05 rad/s: judged by the new limit at once, its lag tripped the guard.
    t, c = armed_with_origin(max_joint_speed=1.0, max_joint_accel=math.pi)
    q, planned, palm, states = HOME.copy(), [], np.array(PALM), set()
    for k in range(300):
        if k == 140:
            t.retune({'max_joint_speed': 0.05})
        palm = palm + np.array([0.0, 0.3, -0.8]) * (1 if (k // 150) % 2 == 0 else -1)
        now = c.tick()
        t.on_hand(hand(palm_mm=tuple(palm), stamp=now), now)
        t.on_joints(q, now)
        t.step(now)
        states.add(t.status.state)
        p = t._servo.planned_at(now)
        planned.append((now, q.copy() if p is None else p))
        q = [x for when, x in planned if when <= now - 0.2 + 1e-9][-1] if now - 0.2 >= planned[0][0] else q
    assert states == {TRACKING}, t.status.reason


def test_joystick_out_of_reach_right_after_a_joint_state_stall_holds_without_raising():
    # The stall had dropped the target; the anti-wind-up fallback restored None and the
    # holding message raised, ending the control loop.
    t, c = armed_with_origin(mode='joystick', max_tcp_speed=0.5, max_joint_speed=2.0,
                             max_joint_accel=math.pi, joystick_gain=5.0)
    q = HOME.copy()

    def period(joints=True):
        now = c.tick()
        t.on_hand(hand(palm_mm=(-200.0, 400.0, -200.0), stamp=now), now)
        if joints:
            t.on_joints(q, now)
        t.step(now)
        return t._servo.state_at(now + 0.008, q)[0]
    for _ in range(400):
        q = period()
    assert t.status.state == HOLDING
    for _ in range(70):                                   # joint states stall, the push goes on
        period(joints=False)
    assert 'no joint states' in t.status.reason
    for _ in range(5):
        q = period()                                      # back: no exception
    assert t.status.state in (HOLDING, TRACKING)


@pytest.mark.parametrize('palm', [None, 5.0, ()])
def test_a_palm_that_is_no_vector_is_refused(palm):
    t, c = armed_with_origin()
    now = c.tick()
    assert 'is not a trackable hand' in t.on_hand(hand(palm_mm=palm, stamp=now), now)


def test_joint_states_back_without_a_receipt_time_after_a_stall_do_not_raise():
    # on_joints(q) without `now` after stamped states, during a joint stall: step() raised
    # TypeError computing how long the states had been away
    t, c = armed_with_origin()
    now = c.tick()
    t.on_joints(HOME, now)
    for _ in range(80):                                   # 0.64 s without joint states
        now = c.tick()
        t.on_hand(hand(stamp=now), now)
        t.step(now)
    assert 'no joint states' in t.status.reason
    t.on_joints(HOME)
    now = c.tick()
    t.on_hand(hand(stamp=now), now)
    t.step(now)
    assert t.status.state == TRACKING and 'back' in t.status.reason, t.status.reason


def test_a_fast_hand_turn_in_yaw_mode_is_caught_up_not_held_as_another_configuration():
    # The wrist lagged the turn; the target's IK nearest that lagging goal took the flipped
    # shoulder (its largest joint move the smaller), refused for good as another configuration.
    t, c = armed_with_origin(orientation='yaw', max_joint_speed=1.0, max_joint_accel=math.pi)
    q = HOME.copy()
    for k in range(500):                                   # slowly to one turn limit
        _, q = follow(t, c, hand(turn=1.6 * min(1.0, (k + 1) / 250)), 1, q)
    states = set()
    for k in range(560):                                   # to the other in 0.5 s, then still
        _, q = follow(t, c, hand(turn=1.6 - 3.2 * min(1.0, (k + 1) / 62)), 1, q)
        states.add(t.status.state)
    assert states == {TRACKING} and t.status.ik_failures == 0, t.status.reason
    assert kin.rotation_error(kin.fk(q)[:3, :3], target_rotation(t)) < 0.01


def test_an_acceleration_lowered_live_mid_catch_up_does_not_overrun_the_target():
    # The servo braked at the new, lower limit at once: each joint ran v^2/2a past its goal,
    # the TCP 0.23 m past the target and 0.58 m off the line.
    t, c = armed_with_origin(max_joint_speed=1.0, max_joint_accel=math.pi)
    a, b = np.array([0.45, 0.16, 0.3]), np.array([1.05, 0.16, 0.3])
    _, _, q = _sweep(t, c, HOME.copy(), kin.fk(HOME)[:3, 3], a, 300, then=200)
    pb = _palm_for(t, b)
    start, furthest = kin.fk(q)[:3, 3], 0.0
    for k in range(1200):
        if k == 56:                                       # 0.45 s into the catch-up
            t.retune({'max_joint_accel': 0.3})
        _, q = follow(t, c, hand(palm_mm=tuple(pb)), 1, q)
        x = kin.fk(q)[:3, 3]
        furthest = max(furthest, float(np.dot(x - start, b - start) / np.dot(b - start, b - start)))
    assert furthest < 1.01, furthest                       # 6 mm past the target at most
    np.testing.assert_allclose(kin.fk(q)[:3, 3], b, atol=2e-3)
    assert np.allclose(t._servo.max_accel, 0.3)            # and the lower limit applies at rest


@pytest.mark.parametrize('at_period, speed, lowered', [(62, 1.0, 0.2), (100, 1.0, 0.2), (62, 2.0, 1.0),
                                                      (38, 1.0, 1.57)])
def test_an_acceleration_lowered_live_mid_sweep_does_not_run_past_its_end(at_period, speed, lowered):
    # During the ramp down the joints kept the sweep's speed (and could gain more at the
    # ramped limit); when it ended, braking at the new limit ran 0.4 m past the sweep's end
    # and 0.3 m out of the workspace. Now none speeds up beyond the new limit and none
    # moves toward its goal faster than it can stop there at it.
    # (A mild lowering at a fast speed limit: released after the ramp's second, the cap's
    # lag caught up with the goal's speed on top ran 0.1-0.18 m past; it stays while it
    # holds a joint back.)
    t, c = armed_with_origin(max_joint_speed=speed, max_joint_accel=math.pi)
    a = kin.fk(HOME)[:3, 3]
    b = a + np.array([-0.3, 0.0, 0.0])
    pa, pb = _palm_for(t, a), _palm_for(t, b)
    q, furthest, lo = HOME.copy(), 0.0, np.array(t.p.workspace_min)
    for k in range(1500):                                  # 300 mm in 2 s, then held
        if k == at_period:
            t.retune({'max_joint_accel': lowered})
        palm = pa + (pb - pa) * min(1.0, (k + 1) / 250)
        _, q = follow(t, c, hand(palm_mm=tuple(palm)), 1, q)
        x = kin.fk(q)[:3, 3]
        furthest = max(furthest, float(np.dot(x - a, b - a) / np.dot(b - a, b - a)))
        assert np.all(x >= lo - 1e-3), (k, x)               # inside the workspace
    assert furthest < 1.02, furthest                        # 6 mm past the end at most
    np.testing.assert_allclose(kin.fk(q)[:3, 3], b, atol=2e-3)


def test_a_wrist_lagging_a_turn_by_half_a_turn_turns_the_tool_the_hands_way():
    # At the real robot's 0.05 rad/s the wrist fell more than pi behind a quick turn from one
    # tool-turn limit to the other; the solution nearest the lagging goal turned the tool
    # 3.08 rad the other way round, through the far side, outside max_tool_turn.
    t, c = armed_with_origin(orientation='yaw')
    q = HOME.copy()
    for k in range(5000):                                  # slowly to one turn limit
        _, q = follow(t, c, hand(turn=1.6 * min(1.0, (k + 1) / 2500)), 1, q)
    start, seen = q[5], []
    for k in range(11000):                                 # to the other in 1 s, then still
        _, q = follow(t, c, hand(turn=1.6 - 3.2 * min(1.0, (k + 1) / 125)), 1, q)
        seen.append(q[5] - start)
    assert t.status.state == TRACKING and t.status.ik_failures == 0, t.status.reason
    assert max(seen) < 0.01 and min(seen) == pytest.approx(-3.2, abs=0.01)   # the hand's way only


def test_an_acceleration_lowered_live_applies_within_a_second_while_the_hand_keeps_moving():
    # Deferred until the joints could stop quickly, it never applied under a circling hand.
    t, c = armed_with_origin(max_joint_speed=1.0, max_joint_accel=math.pi)
    q = HOME.copy()
    for k in range(500):
        if k == 125:
            t.retune({'max_joint_accel': 0.5})
        elif 125 < k < 255 and k % 12 == 0:               # other retunes do not restart it
            t.retune({'servo_gain': 10.0 + (k % 24) / 12})
        a = 2 * math.pi * 0.5 * k * 0.008
        _, q = follow(t, c, hand(palm_mm=(40 * math.cos(a), 200.0, 40 * math.sin(a))), 1, q)
        if k == 255:                                      # 1.04 s after
            assert np.allclose(t._servo.max_accel, 0.5)


@pytest.mark.parametrize('speed, accel', [(1.0, math.pi), (0.05, 0.5)])
def test_a_sideways_sweep_with_a_full_turn_keeps_the_tcp_on_its_line(speed, accel):
    # A wrist lagging the turn once stepped the whole arm along a joint-space line: the base
    # swung the TCP in an arc, 0.24 m off the line and 5 cm under the table (sim limits).
    t, c = armed_with_origin(orientation='yaw', max_joint_speed=speed, max_joint_accel=accel)
    a, b = np.array([0.9, -0.8, 0.03]), np.array([0.9, 0.8, 0.03])
    pa, pb = _palm_for(t, a), _palm_for(t, b)
    q = HOME.copy()
    for k in range(int(40 / speed) * 125):                 # to a, turned to one limit, slowly
        s = min(1.0, (k + 1) / (20 / speed * 125))
        _, q = follow(t, c, hand(palm_mm=tuple(pa), turn=-1.6 * s), 1, q)
    np.testing.assert_allclose(kin.fk(q)[:3, 3], a, atol=2e-3)
    off, zmin = 0.0, math.inf
    for k in range(int(120 / speed * 1.0) + 1250):        # to b and the other limit in 0.5 s
        s = min(1.0, (k + 1) / 62)
        _, q = follow(t, c, hand(palm_mm=tuple(pa + (pb - pa) * s), turn=-1.6 + 3.2 * s), 1, q)
        x = kin.fk(q)[:3, 3]
        off, zmin = max(off, float(np.linalg.norm((x - a)[[0, 2]]))), min(zmin, float(x[2]))
    assert off < 0.02 and zmin > 0.02, (off, zmin)
    assert t.status.state == TRACKING and t.status.ik_failures == 0, t.status.reason


def test_after_a_joint_state_stall_the_tool_turns_the_hands_way():
    # The hand turned +1.6 -> -1.6 rad during a 0.6 s joint-state stall: after it the
    # target's IK was taken nearest the lagging wrist, a turn away: +4.68 rad, the wrong way.
    t, c = armed_with_origin(orientation='yaw', max_tool_turn=1.6)   # the real arm's limits
    q, start = HOME.copy(), HOME[5]
    seen = []
    for k in range(16500):                                # slowly to +1.6, then a quick turn
        now = c.tick()
        turn = 1.6 * min(1.0, (k + 1) / 3750) if k < 7500 else 1.6 - 3.2 * min(1.0, (k - 7499) / 62)
        t.on_hand(hand(turn=turn, stamp=now), now)
        if not 7500 <= k < 7575:                          # joint states stall for 0.6 s
            t.on_joints(q, now)
        t.step(now)
        q = t._servo.state_at(now + 0.008, q)[0]
        seen.append(q[5] - start)
    assert t.status.state == TRACKING and t.status.ik_failures == 0
    assert max(np.abs(seen)) < 1.65 and seen[-1] == pytest.approx(-1.6, abs=0.01)


def test_after_an_ik_hold_the_tool_turns_the_hands_way():
    # The last reachable target's IK seeded the target's after an out-of-reach hold during
    # which the hand turned: wrist 3 headed for +4.68 rad, past max_tool_turn, not -1.6.
    t, c = armed_with_origin(orientation='yaw')
    q, start = HOME.copy(), HOME[5]
    home = np.array(PALM)
    corner = np.array([1.45, 1.2, -0.3])                 # beyond the box's corner
    far = home + np.linalg.solve(t._axes, corner - t._tcp_ref) / (0.001 * t.p.scale)
    for k in range(62):                                   # a quick turn, the wrist lagging
        _, q = follow(t, c, hand(turn=1.6 * (k + 1) / 62), 1, q)
    for k in range(25):
        _, q = follow(t, c, hand(turn=1.6, palm_mm=tuple(home + (k + 1) / 25 * (far - home))), 1, q)
    assert t.status.state == HOLDING
    for k in range(125):                                  # turning the other way, out of reach
        _, q = follow(t, c, hand(turn=1.6 - 3.2 * (k + 1) / 125, palm_mm=tuple(far)), 1, q)
    for k in range(25):
        _, q = follow(t, c, hand(turn=-1.6, palm_mm=tuple(far + (k + 1) / 25 * (home - far))), 1, q)
    seen = []
    for _ in range(10000):
        _, q = follow(t, c, hand(turn=-1.6), 1, q)
        seen.append(q[5] - start)
    assert max(np.abs(seen)) < 1.65 and seen[-1] == pytest.approx(-1.6, abs=0.01)
