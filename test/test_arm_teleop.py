"""Arm teleop logic: protocol, modes, limits, watchdog, bad input (no ROS)."""
import math

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from leap_teleop.teleop.arm import (ARMED, DISARMED, HOLDING, TRACKING, ArmTeleop,
                                    ArmTeleopParams, HandInput)
from leap_teleop.ur10 import kinematics as kin

HOME = kin.HOME_Q.copy()
PALM = (0.0, 200.0, 0.0)


class Clock:
    def __init__(self):
        self.t = 100.0

    def tick(self, dt=0.008):
        self.t += dt
        return self.t


def hand(**kw):
    kw.setdefault('present', True)
    kw.setdefault('palm_mm', PALM)
    return HandInput(**kw)


def drive(teleop, clock, h, periods=1, q=None):
    """Feed the same hand for some control periods; the arm 'teleports' to each target."""
    cmd = None
    for _ in range(periods):
        now = clock.tick()
        h.stamp = now
        teleop.on_hand(h, now)
        teleop.on_joints(q if q is not None else teleop._q)
        cmd = teleop.step(now)
    return cmd


def armed_with_origin(mode='imitation', **params):
    t = ArmTeleop(ArmTeleopParams(mode=mode, filter_cutoff_hz=0.0, **params))
    c = Clock()
    t.on_joints(HOME)
    drive(t, c, hand(thumb_up=True))
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
    drive(t, c, hand(thumb_up=True))
    cmd = drive(t, c, hand(palm_mm=(50, 250, 0), pinch=True, pinch_value=0.5))
    assert t.status.state == ARMED and cmd.q is None     # no origin yet: gripper only
    assert cmd.gripper == pytest.approx(0.43)


def test_imitation_maps_palm_offset_through_axis_map_and_scale():
    t, c = armed_with_origin(scale=2.0)
    tcp_ref = kin.fk(HOME)[:3, 3]
    cmd = drive(t, c, hand(palm_mm=(0.0, 250.0, -40.0)))   # up 50 mm, away from user 40 mm
    expected = tcp_ref + np.array([0.08, 0.0, 0.1])        # base x = -leap z, z = leap y
    np.testing.assert_allclose(kin.fk(cmd.q)[:3, 3], expected, atol=1e-9)
    np.testing.assert_allclose(kin.fk(cmd.q)[:3, :3], kin.tool_down(), atol=1e-9)


def test_trajectory_duration_respects_the_joint_speed_limit():
    t, c = armed_with_origin(max_joint_speed=0.05)
    cmd = drive(t, c, hand(palm_mm=(60.0, 200.0, 0.0)))
    dq = np.max(np.abs(cmd.q - HOME))
    assert dq > 0.01
    assert cmd.duration == pytest.approx(dq / 0.05)


def test_target_is_clamped_to_the_workspace_box():
    t, c = armed_with_origin(scale=3.0, workspace_min=(0.3, -0.5, 0.05),
                             workspace_max=(1.0, 0.5, 0.6))
    drive(t, c, hand(palm_mm=(0.0, 800.0, 0.0)))           # +1.8 m up
    assert t.status.target[2] == pytest.approx(0.6)
    drive(t, c, hand(palm_mm=(0.0, -500.0, 0.0)))          # far below the table
    assert t.status.target[2] == pytest.approx(0.05)


def test_joystick_dead_zone_moves_nothing_and_excess_moves_at_capped_speed():
    t, c = armed_with_origin(mode='joystick', deadzone_mm=30.0, max_tcp_speed=0.1)
    start = np.array(t.status.target or kin.fk(HOME)[:3, 3])
    for _ in range(50):
        drive(t, c, hand(palm_mm=(20.0, 210.0, 0.0)))      # 22 mm from the origin
    np.testing.assert_allclose(t.status.target, kin.fk(HOME)[:3, 3], atol=1e-12)
    for _ in range(125):                                   # 1 s far beyond the dead zone
        drive(t, c, hand(palm_mm=(0.0, 200.0, -300.0)))
    moved = np.array(t.status.target) - kin.fk(HOME)[:3, 3]
    assert moved[0] == pytest.approx(0.1, rel=0.02)        # forward at the 0.1 m/s cap
    assert abs(moved[1]) < 1e-9 and abs(moved[2]) < 1e-9
    del start


def test_fist_disarms_holds_and_later_pinch_moves_nothing():
    t, c = armed_with_origin()
    drive(t, c, hand(palm_mm=(40.0, 220.0, 0.0)))
    q_now = HOME + 0.01
    t.on_joints(q_now)
    cmd = drive(t, c, hand(fist=True), q=q_now)
    assert t.status.state == DISARMED and t.status.reason == 'fist'
    np.testing.assert_array_equal(cmd.q, q_now)             # hold where the arm is
    for _ in range(20):
        cmd = drive(t, c, hand(pinch=True, pinch_value=0.6, palm_mm=(90, 260, -50)), q=q_now)
        assert cmd.q is None and cmd.gripper is None


def test_watchdog_holds_and_disarms_when_input_stops():
    t, c = armed_with_origin()
    drive(t, c, hand(palm_mm=(40.0, 220.0, 0.0)))
    now = c.tick(0.1)                                       # within input_timeout: still on
    t.step(now)
    assert t.status.state == TRACKING, t.status
    now = c.tick(0.15)                                      # 0.25 s since the last input
    cmd = t.step(now)
    assert t.status.state == DISARMED and 'watchdog' in t.status.reason
    np.testing.assert_array_equal(cmd.q, t._q)


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


@pytest.mark.parametrize('bad', [
    dict(palm_mm=(math.nan, 200.0, 0.0)), dict(palm_mm=(0.0, math.inf, 0.0)),
    dict(palm_mm=(1e9, 0.0, 0.0)), dict(pinch_value=math.nan)])
def test_bad_input_is_rejected_and_counted(bad):
    t, c = armed_with_origin()
    before = t.status.target
    now = c.tick()
    assert t.on_hand(hand(stamp=now, **bad), now) is not None
    assert t.status.rejected_inputs == 1
    t.step(now)
    assert t.status.target == before


def test_out_of_order_messages_are_dropped():
    t, c = armed_with_origin()
    now = c.tick()
    assert t.on_hand(hand(stamp=now - 1.0), now) is not None


def test_proportional_gripper_follows_pinch_value_and_sends_changes_only():
    t, c = armed_with_origin(gripper_mode='proportional')
    assert drive(t, c, hand(pinch=True, pinch_value=0.3)).gripper == pytest.approx(0.3)
    assert drive(t, c, hand(pinch=True, pinch_value=0.302)).gripper is None
    assert drive(t, c, hand(pinch=False)).gripper == 0.0


@pytest.mark.parametrize('bad', [dict(mode='fly'), dict(gripper_mode='maybe'),
                                 dict(axis_map=((1, 0), (0, 1))), dict(max_joint_speed=0),
                                 dict(workspace_min=(1, 1, 1), workspace_max=(0, 0, 0))])
def test_bad_parameters_are_refused(bad):
    with pytest.raises(ValueError):
        ArmTeleopParams(**bad).validate()
    with pytest.raises(ValueError, match='unknown'):
        ArmTeleopParams.from_dict({'speed': 1})


finite = st.one_of(st.floats(-1e12, 1e12), st.floats(allow_nan=True, allow_infinity=True))


@settings(max_examples=3000, deadline=None)
@given(palm=st.tuples(finite, finite, finite), pinch_value=finite,
       flags=st.tuples(st.booleans(), st.booleans(), st.booleans(), st.booleans(), st.booleans()),
       mode=st.sampled_from(['imitation', 'joystick']))
def test_fuzzed_input_never_leaves_the_limits(palm, pinch_value, flags, mode):
    t, c = armed_with_origin(mode=mode)
    present, fist, thumb, pinch, rock = flags
    now = c.tick()
    t.on_hand(HandInput(present=present, palm_mm=palm, fist=fist, thumb_up=thumb, pinch=pinch,
                        pinch_value=pinch_value, rock=rock, stamp=now), now)
    cmd = t.step(now)
    if cmd.q is not None:
        assert np.all(np.isfinite(cmd.q))
        assert np.all(cmd.q <= kin.JOINT_UPPER) and np.all(cmd.q >= kin.JOINT_LOWER)
        assert cmd.duration >= np.max(np.abs(cmd.q - HOME)) / t.p.max_joint_speed - 1e-9
        tcp = kin.fk(cmd.q)[:3, 3]
        assert np.all(tcp >= np.array(t.p.workspace_min) - 1e-6)
        assert np.all(tcp <= np.array(t.p.workspace_max) + 1e-6)
    if cmd.gripper is not None:
        assert 0.0 <= cmd.gripper <= 0.8
