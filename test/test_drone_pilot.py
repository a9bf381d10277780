"""DronePilot logic: paper mode = Algorithm 1, tilt mapping, gestures, watchdog, queue."""
import math

import numpy as np
import pytest

from leap_teleop.drone.pilot import (
    PILOT_PARAMS,
    TAKEOFF_CONFIRM_S,
    Command,
    CommandQueue,
    DronePilot,
    PilotInput,
    PilotParams,
    leap_angles,
    shaped,
)

FLAT = dict(normal=(0.0, -1.0, 0.0), direction=(0.0, 0.0, -1.0))


def hand(palm, normal=(0.0, -1.0, 0.0), direction=(0.0, 0.0, -1.0), present=True):
    return PilotInput(present, tuple(palm), tuple(normal), tuple(direction))


_MONO = [1000.0]


def drain(pilot):
    """Everything queued, popped at ever later (monotonic) times so pacing never holds."""
    out = []
    while True:
        _MONO[0] += 1.0
        cmd, _ = pilot.pop(_MONO[0])
        if cmd is None:
            return out
        out.append(cmd)


def twists(cmds):
    return [c.twist for c in cmds if c.kind == 'twist']


def kinds(cmds):
    return [c.kind for c in cmds]


def airborne(config, state=3, t_flying=0.0):
    """A pilot engaged on a centred hand (navdata landed, unfold) whose drone then
    reports `state` at 1 m, at time t_flying."""
    pilot = DronePilot(config)
    pilot.on_navdata(2, 0, 0.0)
    pilot.on_hand(hand((0.0, 0.2, 0.0)), 0.0)
    pilot.on_gesture('unfold', True, 0.0)
    pilot.on_navdata(state, 1000, t_flying)
    return pilot


# -- paper mode: Algorithm 1 on hand-computed inputs -------------------------------------
def test_leap_angles_match_the_sdk_definitions():
    p, r, y = leap_angles((math.sin(math.radians(30)), -math.cos(math.radians(30)), 0.0),
                          (0.0, math.sin(math.radians(40)), -math.cos(math.radians(40))))
    assert (p, r, y) == pytest.approx((40.0, 30.0, 0.0))


def test_paper_mode_reproduces_algorithm_1():
    pilot = DronePilot(PilotParams(mode='paper'))
    pilot.on_navdata(4, 1000, 0.0)
    tilted_n = (0.5, -math.sqrt(3) / 2, 0.0)                            # roll 30 deg
    tilted_d = (0.0, math.sin(math.radians(40)), -math.cos(math.radians(40)))   # pitch 40
    # Pitch 40 but roll only 20: no capture, nothing sent.
    pilot.on_hand(hand((0.03, 0.2, 0.06), (math.sin(math.radians(20)),
                                           -math.cos(math.radians(20)), 0), tilted_d), 0.0)
    # Roll 30 but pitch -40 (signed test, as written): still nothing.
    pilot.on_hand(hand((0.03, 0.2, 0.06), tilted_n, (0, -tilted_d[1], tilted_d[2])), 0.01)
    assert drain(pilot) == []
    # Both exceed 25 deg: init_x = palm z = 60 mm, init_y = palm x = 30 mm.
    pilot.on_hand(hand((0.030, 0.200, 0.060), tilted_n, tilted_d), 0.02)
    (t,) = twists(drain(pilot))
    assert t == pytest.approx((0.0, 0.0, -math.sqrt(3) / 2, 60.0, 30.0, 0.0))
    # Flat hand at (-120, 250, -240) mm: no re-capture.
    # linear.x = -(-240 - 60)/3000 = 0.1; linear.y = -(-120 - 30)/3000 = 0.05;
    # linear.z = normal y = -1; angular = (init_x, init_y, 0).
    pilot.on_hand(hand((-0.120, 0.250, -0.240)), 0.03)
    (t,) = twists(drain(pilot))
    assert t == pytest.approx((0.1, 0.05, -1.0, 60.0, 30.0, 0.0))
    # Palm to the right and toward the user: backward and right.
    pilot.on_hand(hand((0.330, 0.2, 0.360)), 0.04)
    (t,) = twists(drain(pilot))
    assert t == pytest.approx((-0.1, -0.1, -1.0, 60.0, 30.0, 0.0))


# -- tilt mode --------------------------------------------------------------------------
def test_shaped_dead_zone_and_full_scale():
    assert shaped(0.02, 0.03, 0.1) == 0.0
    assert shaped(0.08, 0.03, 0.1) == pytest.approx(0.5)
    assert shaped(-0.08, 0.03, 0.1) == pytest.approx(-0.5)
    assert shaped(0.5, 0.03, 0.1) == 1.0
    assert shaped(0.5, 0.03, 0.1, cap=0.4) == 0.4


def test_tilt_mode_maps_offsets_from_the_reference():
    pilot = DronePilot(PilotParams())
    pilot.on_navdata(2, 0, 0.0)
    pilot.on_hand(hand((0.0, 0.2, 0.0)), 0.0)
    assert drain(pilot) == []                       # not engaged: nothing
    pilot.on_gesture('unfold', True, 0.0)
    assert kinds(drain(pilot)) == ['takeoff']
    pilot.on_navdata(4, 1000, 0.0)
    yaw = math.radians(-40)                            # hand turned left by 40 deg
    t = []
    for i, h in enumerate([hand((0.01, 0.21, -0.01)),          # inside the dead zone: hover
                           hand((-0.08, 0.2, -0.08)),          # away + left by 80 mm
                           hand((0.0, 0.28, 0.5)),             # up 80 mm, far toward the user
                           hand((0.0, 0.2, 0.0), direction=(math.sin(yaw), 0, -math.cos(yaw)))]):
        pilot.on_hand(h, 0.1 * (i + 1))
        t += twists(drain(pilot))
    assert t[0] == (0.0,) * 6
    assert t[1] == pytest.approx((0.5, 0.5, 0.0, 0.0, 0.0, 0.0))
    assert t[2] == pytest.approx((-1.0, 0.0, 0.5, 0.0, 0.0, 0.0))
    assert t[3] == pytest.approx((0.0, 0.0, 0.0, 0.0, 0.0, 25.0 / 45.0))
    assert len(t) == 4                                 # one twist per hand sample, no more


def oriented(R, palm=(0.0, 0.2, 0.0), t=0.0):
    """A hand turned by rotation R (3x3, Leap axes) from flat and pointing away."""
    R = np.asarray(R)
    return PilotInput(True, palm, tuple(R @ [0.0, -1.0, 0.0]), tuple(R @ [0.0, 0.0, -1.0]), t)


def rotation(axis, deg):
    from leap_teleop.ur10.kinematics import rotation_from_vector
    return rotation_from_vector(np.asarray(axis, dtype=float) * math.radians(deg))


def yaw_commands(pilot, hands):
    out = []
    for k, h in enumerate(hands):
        now = 0.1 + 0.01 * k
        pilot.on_navdata(3, 1000, now)
        pilot.on_hand(h, now)
        out += [tw[5] for tw in twists(drain(pilot))]
    return out


@pytest.mark.parametrize('axis', [(1.0, 0.0, 0.0), (0.0, 0.0, 1.0)], ids=['raised', 'rolled'])
def test_raising_or_rolling_the_hand_turns_nothing_even_past_upright(axis):
    # Fingers raised through vertical and past it (a "stop" hand), or the palm rolled up to
    # nearly upside down, with sideways tracking jitter of +-0.6 deg: the Leap yaw of the
    # direction swung across +-180 there and the drone spun at full rate either way.
    pilot = airborne(PilotParams())
    hands = [oriented(rotation((0.0, 1.0, 0.0), 0.6 * (-1) ** k) @ rotation(axis, deg))
             for k, deg in enumerate(np.linspace(0.0, 170.0, 171))]
    assert yaw_commands(pilot, hands) == [0.0] * len(hands)


@pytest.mark.parametrize('raised, rolled', [(30, 60), (30, 90), (45, 90), (45, 135), (30, 170),
                                            (50, -120)])
def test_a_hand_raised_and_rolled_with_its_fingers_ahead_turns_nothing(raised, rolled):
    # Raised, then rolled about its fingers (forearm pronation): the fingers still point
    # straight ahead, yet the twist of the whole rotation about the vertical yawed the
    # drone (45 deg up, palm sideways: 0.67 of full rate; more roll: full rate).
    pilot = airborne(PilotParams())
    path = [rotation((1.0, 0.0, 0.0), deg) for deg in range(0, raised + 1)]
    sign = 1 if rolled > 0 else -1
    path += [path[-1] @ rotation((0.0, 0.0, 1.0), sign * deg) for deg in range(0, abs(rolled) + 1)]
    # Then turned left by 40 deg about the vertical: the same command as a flat hand's.
    turned = [rotation((0.0, 1.0, 0.0), deg) @ path[-1] for deg in range(1, 41)]
    commands = yaw_commands(pilot, [oriented(R) for R in path + turned])
    assert commands[:len(path)] == [0.0] * len(path)
    assert commands[-1] == pytest.approx(25.0 / 45.0)


@pytest.mark.parametrize('raised', [0, 40, 135], ids=['flat', 'raised', 'past_upright'])
def test_a_turn_too_fast_to_follow_is_read_the_right_way_and_the_neutral_kept(raised):
    # A 5 fps camera, or a stall in a Leap stream: the fingers turn 60..120 deg between two
    # frames. Read by the half turn, a right turn of 95 deg read as a left one of 85, and
    # every reading after followed it: the hand held straight ahead again yawed the drone at
    # full rate. Raised (40 deg) or past upright (135 deg), the same turn about the vertical.
    lift = rotation((1.0, 0.0, 0.0), raised)
    path = [rotation((1.0, 0.0, 0.0), deg) for deg in range(0, raised + 1)]   # raised slowly
    pilot = airborne(PilotParams())
    drain(pilot)

    def turned(deg):                    # the Leap yaw counts a right turn (+x) positive
        return rotation((0.0, 1.0, 0.0), -deg) @ lift
    swing = [turned(0), turned(-60), turned(40)] + [turned(40)] * 10 \
        + [turned(40 - 2 * k) for k in range(21)] + [turned(0)] * 10
    commands = yaw_commands(pilot, [oriented(R) for R in path + swing])[len(path):]
    assert commands[1] == pytest.approx(1.0)           # -60: left at full rate
    assert commands[2] == pytest.approx(-25.0 / 45.0)  # +40: right, as a slow turn gives
    assert commands[-1] == 0.0                         # straight ahead: the neutral again
    # One step of 130 deg (level both times: not the fingers passing vertical) too.
    pilot = airborne(PilotParams())
    drain(pilot)
    commands = yaw_commands(pilot, [oriented(R) for R in path + [turned(-65), turned(65), turned(0)]])
    assert commands[-3:] == [pytest.approx(1.0), pytest.approx(-1.0), 0.0]


def hand_pose(turn=0.0, raised=0.0, rolled=0.0):
    """Rolled about the fingers, raised (fingers up), then turned right about the vertical."""
    return (rotation((0.0, 1.0, 0.0), -turn) @ rotation((1.0, 0.0, 0.0), raised)
            @ rotation((0.0, 0.0, 1.0), rolled))


@pytest.mark.parametrize('turn, raised', [(70, 30), (-90, 40), (65, 0)])
def test_a_fast_turn_from_upright_is_read_by_the_hand_s_own_turn(turn, raised):
    # Fingers near vertical have no heading of their own, so a step from there to level
    # fingers cannot be followed by their heading: the hand's turn about the vertical between
    # the two frames tells it. (Reset there instead, the neutral moved: the hand back at
    # its unfold pose yawed at full rate.)
    pilot = airborne(PilotParams())
    drain(pilot)
    up = [hand_pose(raised=deg) for deg in range(0, 81)]                     # nearly upright
    flick = [hand_pose(turn, raised)] * 3
    back = [hand_pose(turn * (1 - k / 40), raised + (80 - raised) * k / 40) for k in range(41)]
    down = [hand_pose(raised=80 - deg) for deg in range(81)] + [hand_pose()] * 5
    commands = yaw_commands(pilot, [oriented(R) for R in up + flick + back + down])
    assert commands[len(up)] == pytest.approx(-1.0 if turn > 0 else 1.0)     # right: yaw right
    assert commands[-1] == 0.0 and max(abs(c) for c in commands[-len(down):]) < 0.2


@pytest.mark.parametrize('turn', [100, -100, 150])
def test_a_turn_too_fast_to_follow_right_after_the_unfold_is_read_the_right_way(turn):
    # The frame after the capture had no reading before it to judge a step by: a 100 deg
    # turn there read half a turn off, full rate the wrong way, on after the hand came back.
    pilot = airborne(PilotParams())
    drain(pilot)
    back = [hand_pose(turn * (1 - k / 20)) for k in range(21)] + [hand_pose()] * 3
    commands = yaw_commands(pilot, [oriented(R) for R in [hand_pose(turn)] * 3 + back])
    assert commands[0] == pytest.approx(-1.0 if turn > 0 else 1.0)
    assert commands[-1] == 0.0


@pytest.mark.parametrize('path', [
    [('raised', 85), ('rolled', 120), ('raised', 0), ('rolled', 0)],
    [('raised', 85), ('rolled', 100), ('raised', 0), ('rolled', 0)],
    [('rolled', 150), ('raised', 130), ('rolled', 0), ('raised', 0)],
    [('rolled', 90), ('raised', 130), ('rolled', 0), ('raised', 0)],
    [('raised', 130), ('rolled', 150), ('raised', 0), ('rolled', 0)],
], ids=['upright_roll120', 'upright_roll100', 'palm_up_over_the_top', 'palm_side_over_the_top',
        'over_the_top_roll'])
def test_a_hand_back_at_its_unfold_pose_turns_nothing_whatever_path_it_took(path):
    # Slow closed loops of raises and rolls (an upright hand rolled turns the drone) left
    # the heading read along the way a half or whole turn off: back at the unfold pose, the
    # drone yawed at full rate.
    pilot = airborne(PilotParams())
    drain(pilot)
    pose, hands = {'raised': 0.0, 'rolled': 0.0}, []
    for axis, goal in path:
        start = pose[axis]
        for k in range(1, 61):                 # 1 deg a frame or so: 60 deg/s at 60 fps
            pose[axis] = start + (goal - start) * k / 60
            hands.append(oriented(hand_pose(raised=pose['raised'], rolled=pose['rolled'])))
    commands = yaw_commands(pilot, hands + [oriented(hand_pose())] * 5)
    assert commands[-5:] == [0.0] * 5, commands[-70:]


@pytest.mark.parametrize('raised, rolled', [(50, 60), (60, 120)])
def test_an_unfold_shown_steep_and_rolled_reads_the_palm_s_turn_smoothly_when_raised(raised, rolled):
    # Near vertical the heading is the palm's, legitimately far from the rotation's twist:
    # taken nearest that twist, raising such a hand from its unfold pose flipped the yaw
    # from full left to right within half a degree.
    pilot = DronePilot(PilotParams())
    pilot.on_navdata(2, 0, 0.0)
    pilot.on_hand(oriented(hand_pose(raised=raised, rolled=rolled)), 0.0)
    pilot.on_gesture('unfold', True, 0.0)
    pilot.on_navdata(4, 1000, 0.0)
    drain(pilot)
    steps = [hand_pose(raised=raised + k / 2, rolled=rolled) for k in range(2 * (80 - raised) + 1)]
    commands = yaw_commands(pilot, [oriented(R) for R in steps])
    assert max(abs(b - a) for a, b in zip(commands, commands[1:])) < 0.1, commands
    assert abs(commands[-1]) > 0.8          # upright, rolled: the palm's turn


@pytest.mark.parametrize('stall', [False, True])
def test_a_hand_raised_past_upright_between_two_frames_turns_nothing(stall):
    # A slow camera, or a stall in a Leap stream over the top of a raise: the fingers go from
    # 55 deg up to 125 (pointing back) between two frames, a half turn of their heading that
    # read as a turn at full rate, on after the hand was flat again.
    pilot = airborne(PilotParams())
    drain(pilot)
    raise_ = [hand_pose(raised=deg) for deg in range(0, 56, 5)]
    over = [hand_pose(raised=125)] * 10 + [hand_pose(turn=3, raised=125)] * 5
    lower = [hand_pose(turn=-3, raised=125 - 5 * k) for k in range(26)] + [hand_pose()] * 5
    hands = [oriented(R) for R in raise_ + over + lower]
    if stall:       # no orientation on the frames between: the same two readings
        hands[len(raise_):len(raise_)] = [PilotInput(True, (0.0, 0.2, 0.0), (0.0, 0.0, -1.0),
                                                     (0.0, 0.0, -1.0))] * 3
    commands = yaw_commands(pilot, hands)
    assert commands == [0.0] * len(commands), commands


@pytest.mark.parametrize('rolled', [100, 150, -150])
def test_a_palm_rolled_up_and_turned_a_little_turns_a_little(rolled):
    # Rolled past 90 deg the axis across the palm points back, half a turn from the fingers:
    # the tie read a whole turn, and a 6 deg turn yawed at full rate the wrong way, on after
    # the hand was flat and straight ahead again.
    for turn, want in ((-6, 0.0), (6, 0.0), (20, -5.0 / 45.0), (-20, 5.0 / 45.0)):
        pilot = airborne(PilotParams())
        drain(pilot)
        roll = [hand_pose(rolled=rolled * k / 30) for k in range(31)]
        turning = [hand_pose(turn=turn * k / 10, rolled=rolled) for k in range(11)]
        back = [hand_pose(turn=turn * (1 - k / 10), rolled=rolled * (1 - k / 10)) for k in range(11)]
        commands = yaw_commands(pilot, [oriented(R) for R in roll + turning + back])
        assert commands[len(roll) + len(turning) - 1] == pytest.approx(want), (turn, commands)
        assert commands[-1] == 0.0


def test_an_unfold_shown_upright_steers_by_the_turn_from_it():
    pilot = DronePilot(PilotParams())
    pilot.on_navdata(2, 0, 0.0)
    upright = rotation((0.0, 1.0, 0.0), 0.5) @ rotation((1.0, 0.0, 0.0), 90.5)
    pilot.on_hand(oriented(upright), 0.0)
    pilot.on_gesture('unfold', True, 0.0)
    flat_left = rotation((0.0, 1.0, 0.0), 40.0)            # flat, turned left by 40 deg
    commands = yaw_commands(pilot, [oriented(np.eye(3)), oriented(flat_left),
                                    oriented(flat_left @ upright)])
    # Lowered flat: no turn (the unfold's yaw was +-135 deg of noise); 40 deg: the same
    # command as from a flat unfold; raised again, still turned: the same.
    assert commands == pytest.approx([0.0, 25.0 / 45.0, 25.0 / 45.0], abs=0.02)


@pytest.mark.parametrize('raised', [103, 105, 108])
def test_an_unfold_shown_just_past_upright_and_held_still_turns_nothing(raised):
    # Fingers 13-18 deg past vertical: the same pose read as 28-75 deg of turn from itself
    # (its heading taken from the fingers', which are ambiguous by a half turn there).
    pilot = DronePilot(PilotParams())
    pilot.on_navdata(2, 0, 0.0)
    held = rotation((1.0, 0.0, 0.0), raised)
    pilot.on_hand(oriented(held), 0.0)
    pilot.on_gesture('unfold', True, 0.0)
    lowered = [rotation((1.0, 0.0, 0.0), deg) for deg in range(raised, -1, -1)]
    assert yaw_commands(pilot, [oriented(held)] * 50 + [oriented(R) for R in lowered]) == pytest.approx(
        [0.0] * (50 + len(lowered)))


def test_a_frame_without_an_orientation_keeps_the_side_of_a_turn_past_90_deg():
    # One frame whose normal lies along its direction reset the turn: the next frame read
    # a level hand turned 120 deg a half turn off, and the drone yawed full rate the other way.
    pilot = airborne(PilotParams())
    turned = [oriented(rotation((0.0, 1.0, 0.0), deg)) for deg in range(0, 121)]
    odd = PilotInput(True, (0.0, 0.2, 0.0), (0.0, 0.0, -1.0), (0.0, 0.0, -1.0), 0.0)
    commands = yaw_commands(pilot, turned + [odd] + [turned[-1]] * 5)
    assert commands[len(turned) - 1] == pytest.approx(1.0) and commands[-1] == pytest.approx(1.0)


def test_a_hand_turned_half_round_keeps_its_side():
    pilot = airborne(PilotParams())
    commands = yaw_commands(pilot, [oriented(rotation((0.0, 1.0, 0.0), deg))
                                    for deg in list(range(0, 200, 5)) + list(range(200, -1, -5))])
    assert max(commands) == pytest.approx(1.0) and min(commands) == 0.0


@pytest.mark.parametrize('then', ['fold', 'hand_lost'])
def test_a_fold_or_a_lost_hand_withdraws_a_takeoff_not_yet_sent(then):
    # Both events handled before the worker popped the takeoff (one burst after a stall):
    # the takeoff went out all the same, against the fold.
    pilot = DronePilot(PilotParams())
    pilot.on_navdata(2, 0, 0.0)
    pilot.on_hand(hand((0.0, 0.2, 0.0)), 0.0)
    pilot.on_gesture('unfold', True, 0.01)
    pilot.on_gesture(then, True, 0.02)
    out = kinds(drain(pilot))
    assert 'takeoff' not in out and 'land' not in out, out


def took_off(at):
    """A pilot whose unfold at `at` (navdata landed, a centred hand) sent its takeoff."""
    pilot = DronePilot(PilotParams())
    pilot.on_navdata(2, 0, 0.0)
    pilot.on_hand(hand((0.0, 0.2, 0.0)), 0.0)
    pilot.on_gesture('unfold', True, at)
    assert kinds(drain(pilot)) == ['takeoff']
    return pilot


def test_a_fold_before_navdata_reports_the_takeoff_lands():
    pilot = took_off(0.01)                 # sent
    pilot.on_gesture('fold', True, 0.02)                      # navdata still says landed
    assert kinds(drain(pilot)) == ['land']
    pilot.on_navdata(2, 0, 0.5)                               # landed since: a fold lands nothing
    pilot.on_gesture('fold', True, 0.51)
    assert kinds(drain(pilot)) == []


def test_a_fold_lands_a_takeoff_that_navdata_made_before_it_still_shows_landed():
    # Navdata comes every 20 ms: one produced before the driver acted on the takeoff
    # still says landed, and a fold after it sent nothing while the drone took off.
    pilot = took_off(0.005)
    pilot.on_navdata(2, 0, 0.01)
    pilot.on_gesture('fold', True, 0.05)
    assert kinds(drain(pilot)) == ['land']


def test_a_fold_lands_a_sent_takeoff_when_a_second_one_is_withdrawn():
    pilot = took_off(0.01)                 # sent
    pilot.on_gesture('unfold', True, 0.02)                    # queued, not sent
    pilot.on_gesture('fold', True, 0.03)
    assert kinds(drain(pilot)) == ['land']


@pytest.mark.parametrize('landed_for, lands', [(6.0, True), (TAKEOFF_CONFIRM_S + 1.0, False)])
def test_a_takeoff_navdata_shows_landed_for_long_is_forgotten(landed_for, lands):
    # Held by the node up to ~takeoff_hold (5 s) before its driver listens, a takeoff may
    # reach the drone late: a fold 6 s on still lands it. Landed for longer, the firmware
    # refused it (a low battery): a later fold has nothing to land.
    pilot = took_off(0.01)
    for i in range(1, int(landed_for / 0.02) + 1):
        pilot.on_navdata(2, 0, 0.02 * i)
        pilot.on_hand(hand((0.0, 0.2, 0.0)), 0.02 * i)
    pilot.on_gesture('fold', True, landed_for + 0.01)
    assert kinds(drain(pilot)) == (['land'] if lands else [])


@pytest.mark.parametrize('sink, flips', [(0.0, True), (0.1, True), (0.7, False)])
def test_no_flip_while_the_drone_sinks_through_the_height_a_flip_needs(sink, flips):
    # A flip asked 0.9 m up while sinking at full rate (0.7 m/s) struck the floor: the
    # altitude alone allowed it.
    cfg = PilotParams(flip_min_altitude=0.6, flip_type=19)
    pilot = airborne(cfg, state=3)
    for i in range(26):                                   # 0.5 s of navdata at 50 Hz
        t = 0.02 * i
        pilot.on_navdata(3, 1000.0 * (1.3 - sink * t), t)
        pilot.on_hand(hand((0.0, 0.2, 0.0)), t)
    drain(pilot)
    assert pilot.sink_rate() == pytest.approx(sink, abs=1e-6)
    pilot.on_gesture('circle_cw', True, 0.5, HAND_CIRCLE)
    assert ('flip' in kinds(drain(pilot))) == flips
    assert pilot.flip_still_wanted(0.49, 0.5) == flips


def test_a_bound_hover_stops_the_drone_and_makes_the_hand_s_place_neutral():
    # The binding sent hand_lost: one zero twist, then the hand, still 40 mm forward and
    # within recapture_beyond of where it was, flew the drone on from the old reference.
    pilot = airborne(PilotParams(), state=3)
    drain(pilot)
    for i in range(10):
        pilot.on_navdata(3, 1000, 0.02 * i)
        pilot.on_hand(hand((0.0, 0.2, -0.04)), 0.02 * i)
    assert twists(drain(pilot))[-1][0] > 0.0                  # forward
    pilot.on_gesture('hover', True, 0.2)
    assert twists(drain(pilot)) == [(0.0,) * 6]
    for i in range(11, 20):
        pilot.on_navdata(3, 1000, 0.02 * i)
        pilot.on_hand(hand((0.0, 0.2, -0.04)), 0.02 * i)
    assert all(t == (0.0,) * 6 for t in twists(drain(pilot)))


def test_a_bound_hover_in_paper_mode_hovers_until_the_capture_pose_again():
    # The paper reference was kept: the next Hand message sent the twist from before the
    # hover (a flat palm sinking at full rate), so the hover lasted one cmd_vel.
    pilot = DronePilot(PilotParams(mode='paper', navdata_timeout=10.0))
    pilot.on_navdata(3, 1000, 0.0)
    tilted = dict(normal=(0.6, -0.8, 0.0), direction=(0.0, 0.6, -0.8))
    pilot.on_hand(PilotInput(True, (0.0, 0.2, 0.0), **tilted), 0.0)     # captures
    for i in range(1, 10):
        pilot.on_hand(hand((0.0, 0.2, -0.09)), 0.02 * i)
    assert twists(drain(pilot))[-1][2] == -1.0                          # flat: sinking
    pilot.on_gesture('hover', True, 0.19)
    assert twists(drain(pilot)) == [(0.0,) * 6]
    for i in range(10, 60):
        pilot.on_hand(hand((0.0, 0.2, -0.09)), 0.02 * i)
    assert drain(pilot) == [] and pilot.paper_ref is None
    pilot.on_hand(PilotInput(True, (0.0, 0.2, -0.09), **tilted), 1.2)  # the capture pose
    (t,) = twists(drain(pilot))
    assert t[:2] == (0.0, 0.0) and t[3:5] == pytest.approx((-90.0, 0.0))


def test_a_slow_start_with_no_navdata_and_no_hand_hovers_once_and_lands_nothing():
    # Started before its driver and sender: 'hand lost for 3.0 s: landing' to a drone
    # never seen. The state unknown, the hover is what is safe (as for navdata lost).
    cfg = PilotParams()
    warned = []
    pilot = DronePilot(cfg, warn=lambda key, text: warned.append(text))
    sent = []
    for i in range(int((cfg.land_after + 1.0) / 0.02)):
        pilot.watchdog(0.02 * i)
        sent += drain(pilot)
    assert sent and all(c.kind == 'twist' and c.twist == (0.0,) * 6 for c in sent), sent
    assert not any('landing' in text for text in warned), warned


def test_a_pilot_that_never_gets_a_hand_hovers_and_lands_a_flying_drone():
    # Restarted beside a flying drone with its sender down: not a word was sent before.
    cfg = PilotParams()
    pilot = DronePilot(cfg)
    sent = []
    for i in range(int((cfg.land_after + 1.0) / 0.02)):
        t = 0.02 * i
        pilot.on_navdata(3, 1000, t)
        pilot.watchdog(t)
        sent += [(t, c.kind, c.twist) for c in drain(pilot)]
    assert sent[0][1:] == ('twist', (0.0,) * 6) and sent[0][0] == 0.0
    lands = [t for t, kind, _ in sent if kind == 'land']
    assert len(lands) == 1 and abs(lands[0] - cfg.land_after) < 0.03, sent


@pytest.mark.parametrize('lost', ['hand', 'navdata'])
def test_the_clock_jumping_back_under_a_loss_still_lands(lost):
    # The /clock publisher restarts 1 s into a loss, and a Hand message (every 10 ms) sees
    # the new time before the watchdog: the loss's start stayed at the old time, and the
    # drone hovered without landing for as long as the jump (25 s and 55 s here).
    pilot = airborne(PilotParams())
    drain(pilot)
    gone = dict(hand=lambda t: pilot.on_hand(hand((0.0, 0.2, 0.0), present=False), t),
                navdata=lambda t: pilot.on_hand(hand((0.0, 0.2, 0.0)), t))[lost]
    landed_at = None
    for t in list(np.arange(1000.0, 1001.0, 0.01)) + list(np.arange(5.0, 30.0, 0.01)):
        if lost == 'hand':
            pilot.on_navdata(3, 1000, t)
        gone(t)
        pilot.watchdog(t)
        if landed_at is None and 'land' in kinds(drain(pilot)):
            landed_at = t
    assert landed_at is not None and 5.0 < landed_at <= 5.0 + 3.0 + 0.02, landed_at


@pytest.mark.parametrize('stamped', [True, False], ids=['stamped', 'unstamped'])
@pytest.mark.parametrize('absent_first', [False, True], ids=['hand_in_view', 'no_hand_first'])
@pytest.mark.parametrize('first', ['hand', 'watchdog'])
def test_a_session_played_again_hovers_and_needs_a_new_unfold(first, absent_first, stamped):
    # A bag looped with its clock: /clock (and the Hand stamps, if any) go back 40 s, and
    # the new pass shows the hand 100 mm forward of the old unfold. Whichever saw the jump
    # first, the pilot steered on from the old session's reference (linear.x 0.7, no
    # hover); so it did when the new pass began with frames of no hand (the sender sends
    # one per frame), or with unstamped messages.
    warned = []
    pilot = DronePilot(PilotParams(), warn=lambda key, text: warned.append(text))

    def at(z, t, present=True):
        return PilotInput(present, (0.0, 0.2, z), FLAT['normal'], FLAT['direction'], t if stamped else 0.0)
    pilot.on_navdata(2, 0, 10.0)
    pilot.on_hand(at(0.0, 10.0), 10.0)
    pilot.on_gesture('unfold', True, 10.0, stamp=10.0 if stamped else 0.0)
    for t in np.arange(10.01, 50.0, 0.01):
        pilot.on_navdata(3, 1000, t)
        pilot.on_hand(at(0.0, t), t)
        pilot.watchdog(t)
    drain(pilot)
    if first == 'watchdog':
        pilot.watchdog(10.0)
    start = 10.0
    if absent_first:
        for t in np.arange(10.0, 10.3, 0.01):
            pilot.on_navdata(3, 1000, t)
            pilot.on_hand(at(-0.1, t, present=False), t)
            pilot.watchdog(t + 0.001)
        start = 10.3
    for t in np.arange(start, start + 0.3, 0.01):
        pilot.on_navdata(3, 1000, t)
        pilot.on_hand(at(-0.1, t), t)
        pilot.watchdog(t + 0.001)
    sent = twists(drain(pilot))
    assert sent and all(tw == (0.0,) * 6 for tw in sent), sent
    assert not pilot.engaged and any('older stamps' in w for w in warned), warned
    assert not any('-' in w.split('no navdata for ')[-1][:1] for w in warned), warned
    t = start + 0.3
    pilot.on_gesture('unfold', True, t, stamp=t if stamped else 0.0)   # this session's own unfold
    pilot.on_hand(at(-0.2, t + 0.01), t + 0.01)
    assert twists(drain(pilot))[-1][0] > 0.0


@pytest.mark.parametrize('first', ['hand', 'watchdog'])
def test_a_clock_gone_back_under_stamps_that_did_not_is_a_loss_either_way(first):
    # /clock restarted under a live sender stamping by another clock: the same session, so
    # no new unfold, but a lost hand whoever sees it first: back 100 mm forward, the hand
    # is re-captured where it is. A Hand message seeing it first used to steer on from the
    # old reference (linear.x 0.7).
    pilot = airborne(PilotParams())
    for t in np.arange(100.0, 101.0, 0.01):
        pilot.on_navdata(3, 1000, t)
        pilot.on_hand(PilotInput(True, (0.0, 0.2, 0.0), FLAT['normal'], FLAT['direction'], 1e9 + t), t)
        pilot.watchdog(t)
    drain(pilot)
    if first == 'watchdog':
        pilot.watchdog(5.0)
    pilot.on_navdata(3, 1000, 5.0)
    pilot.on_hand(PilotInput(True, (0.0, 0.2, -0.1), FLAT['normal'], FLAT['direction'], 1e9 + 101.0), 5.0)
    assert twists(drain(pilot))[-1] == (0.0,) * 6 and pilot.engaged


def test_a_takeoff_navdata_never_confirmed_still_lands_across_a_clock_jump():
    # The takeoff's time was moved to the jump's 'now' while the last navdata's stayed on
    # the old timeline: compared, the takeoff looked older than the navdata saying landed,
    # and a drone that may be flying got no hover and no land.
    pilot = DronePilot(PilotParams())
    pilot.on_navdata(2, 0, 100.0)
    pilot.on_hand(hand((0.0, 0.2, 0.0)), 100.0)
    pilot.on_gesture('unfold', True, 100.002)
    assert kinds(drain(pilot)) == ['takeoff']            # then navdata goes silent
    landed_at = None
    for t in list(np.arange(100.01, 100.5, 0.01)) + list(np.arange(5.0, 12.0, 0.01)):
        pilot.on_hand(hand((0.0, 0.2, 0.0)), t)
        pilot.watchdog(t)
        if landed_at is None and 'land' in kinds(drain(pilot)):
            landed_at = t
    assert landed_at is not None and 5.0 < landed_at <= 8.02, landed_at


def test_no_hand_twists_while_landed_or_taking_off():
    pilot = DronePilot(PilotParams())
    pilot.on_navdata(2, 0, 0.0)
    pilot.on_hand(hand((0.0, 0.2, 0.0)), 0.0)
    pilot.on_gesture('unfold', True, 0.0)
    drain(pilot)
    pilot.on_navdata(6, 300, 0.0)
    pilot.on_hand(hand((0.0, 0.2, -0.2)), 0.1)
    assert drain(pilot) == []


# -- gestures ---------------------------------------------------------------------------
HAND_CIRCLE = 0.035        # m, the radius of drone_flight.yaml's palm circle


def test_only_a_hand_sized_circle_flips():
    warnings = []
    pilot = DronePilot(PilotParams(flip_min_radius=0.025),
                       warn=lambda key, text: warnings.append(text))
    pilot.on_navdata(4, 1000, 0.0)
    pilot.on_hand(hand((0.0, 0.2, 0.0)), 0.0)            # a flip needs the hand in view
    for radius in (0.004, 0.0199, -0.05, math.nan, math.inf, None, 'wide', True):
        pilot.on_gesture('circle_cw', True, 0.0, radius)
    assert drain(pilot) == []
    assert len(warnings) == 8 and all('flip_min_radius' in w for w in warnings)
    pilot.on_gesture('circle_ccw', True, 0.0, 0.025)
    pilot.on_gesture('circle_ccw', True, 0.0, np.float32(0.03))    # a message's float32
    assert kinds(drain(pilot)) == ['flip', 'flip']
    pilot.on_navdata(2, 0, 0.0)                  # landed: it says so, whatever the radius
    pilot.on_gesture('circle_ccw', True, 0.0, 0.004)
    assert 'not flying' in warnings[-1]
    with pytest.raises(ValueError):
        PilotParams().update({'flip_min_radius': -0.01})


def test_gestures_respect_the_drone_state():
    pilot = DronePilot(PilotParams(flip_min_altitude=0.6, flip_type=18, flip_duration=0))
    pilot.on_navdata(4, 1000, 0.0)
    pilot.on_hand(hand((0.0, 0.2, 0.0)), 0.0)            # a takeoff needs the hand in view
    pilot.on_gesture('unfold', True, 0.0)                 # flying: no takeoff
    pilot.on_gesture('circle_cw', True, 0.0, HAND_CIRCLE)
    assert [(c.kind, c.anim) for c in drain(pilot)] == [('flip', (18, 0))]
    pilot.on_navdata(4, 400, 0.0)                              # too low for a flip
    pilot.on_gesture('circle_ccw', True, 0.0, HAND_CIRCLE)
    assert drain(pilot) == []
    pilot.on_navdata(9, 1000, 0.0)                             # looping: no second flip
    pilot.on_gesture('circle_ccw', True, 0.0, HAND_CIRCLE)
    assert drain(pilot) == []
    pilot.on_navdata(3, 1000, 0.0)
    pilot.on_gesture('fold', True, 0.0)
    assert kinds(drain(pilot)) == ['land']
    pilot.on_navdata(2, 0, 0.0)
    pilot.on_gesture('fold', True, 0.0)                   # landed: no land
    pilot.on_gesture('circle_cw', True, 0.0, HAND_CIRCLE)
    assert drain(pilot) == []
    pilot.on_gesture('unfold', True, 0.0)
    assert kinds(drain(pilot)) == ['takeoff']


# -- watchdog ---------------------------------------------------------------------------
def test_hand_absent_gives_one_zero_twist_then_land_after_timeout():
    pilot = airborne(PilotParams(land_after=3.0, navdata_timeout=10.0))   # navdata fresh
    pilot.on_hand(hand((0.0, 0.2, -0.2)), 0.1)
    assert twists(drain(pilot))[-1][0] == 1.0
    pilot.on_hand(hand((0, 0, 0), present=False), 0.2)
    pilot.on_hand(hand((0, 0, 0), present=False), 0.3)
    assert twists(drain(pilot)) == [(0.0,) * 6]           # once, not per frame
    pilot.watchdog(3.1)
    assert drain(pilot) == []
    pilot.watchdog(3.25)
    assert kinds(drain(pilot)) == ['land']
    pilot.watchdog(4.0)
    assert drain(pilot) == []                              # land only once


def test_a_landed_drone_gets_no_land_when_its_navdata_pauses_while_the_hand_is_gone():
    pilot = DronePilot(PilotParams(land_after=3.0, navdata_timeout=0.5))
    pilot.on_navdata(2, 0, 0.0)                            # landed
    pilot.on_hand(hand((0.0, 0.2, 0.0)), 0.1)
    pilot.on_hand(hand((0, 0, 0), present=False), 0.2)    # the hand goes
    drain(pilot)
    for k in range(3, 60):                                 # navdata pauses from 0.5 s
        pilot.watchdog(0.1 * k)
    assert 'land' not in kinds(drain(pilot))


def test_a_takeoff_then_lost_navdata_and_hand_still_lands():
    # the takeoff went out after the last navdata (which said landed): it may be flying
    pilot = DronePilot(PilotParams(land_after=3.0, navdata_timeout=0.5))
    pilot.on_navdata(2, 0, 0.0)
    pilot.on_hand(hand((0.0, 0.2, 0.0)), 0.1)
    pilot.on_gesture('unfold', True, 0.2)
    assert kinds(drain(pilot)) == ['takeoff']
    pilot.on_hand(hand((0, 0, 0), present=False), 0.3)
    for k in range(4, 40):
        pilot.watchdog(0.1 * k)
    out = kinds(drain(pilot))
    # hovered, then landed: for the lost hand and for the lost navdata, each once
    assert out == ['twist', 'land', 'twist', 'land'], out


def test_silence_counts_as_a_lost_hand():
    pilot = airborne(PilotParams(hand_timeout=0.15, land_after=3.0, navdata_timeout=10.0))
    pilot.on_hand(hand((0.0, 0.2, -0.2)), 0.1)
    drain(pilot)
    pilot.watchdog(0.2)
    assert drain(pilot) == []
    pilot.watchdog(0.26)
    assert twists(drain(pilot)) == [(0.0,) * 6]
    pilot.watchdog(3.0)
    assert drain(pilot) == []
    pilot.watchdog(3.26)
    assert kinds(drain(pilot)) == ['land']


def test_a_hand_read_before_navdata_went_stale_flies_nothing_after_the_hover():
    # A Hand callback reads the clock while navdata is still fresh, the worker's watchdog
    # then finds it stale and hovers, and only then does the callback take the lock: its
    # forward twist must not follow (nor replace, still queued) the hover.
    pilot = airborne(PilotParams(navdata_timeout=0.5, hand_timeout=0.15, land_after=3.0),
                     t_flying=1.0)
    pilot.on_hand(hand((0.0, 0.2, -0.2)), 1.45)
    assert twists(drain(pilot))[-1][0] == 1.0
    pilot.watchdog(1.51)                                  # navdata last at 1.0: stale
    pilot.on_hand(hand((0.0, 0.2, -0.2)), 1.49)           # read the clock before that
    assert twists(drain(pilot)) == [(0.0,) * 6]
    pilot.on_hand(hand((0.0, 0.2, -0.2)), 1.52)           # and later hands, as before
    assert drain(pilot) == []
    pilot.on_navdata(3, 1000, 1.6)                        # navdata back: flying again
    pilot.on_hand(hand((0.0, 0.2, -0.2)), 1.61)
    assert twists(drain(pilot))[-1][0] == 1.0


def test_reference_recaptured_when_the_hand_comes_back():
    pilot = airborne(PilotParams(navdata_timeout=10.0), state=4)
    pilot.on_hand(hand((0, 0, 0), present=False), 0.1)
    t = twists(drain(pilot))
    pilot.on_hand(hand((0.15, 0.25, 0.1)), 0.5)           # back somewhere else: no jump
    t += twists(drain(pilot))
    pilot.on_hand(hand((0.15, 0.25, 0.0)), 0.6)           # then 100 mm forward from there
    t += twists(drain(pilot))
    assert t[-2] == (0.0,) * 6 and t[-1][0] == pytest.approx(0.7)


# -- a stall holds (hovers), a loss disengages ------------------------------------------
def stamped(palm, t, present=True):
    return PilotInput(present, tuple(palm), FLAT['normal'], FLAT['direction'], stamp=t)


def silence(pilot, t0, t1, dt=0.02):
    """Watchdog periods with no Hand from t0 to t1; the commands they queued."""
    out, t = [], t0
    while t < t1 - 1e-9:
        t += dt
        pilot.watchdog(t)
        out += drain(pilot)
    return out


def flying_forward(config):
    pilot = airborne(config)
    for k in range(10):                                     # 100 mm forward, stamped
        pilot.on_hand(stamped((0.0, 0.2, -0.1), 0.1 + 0.01 * k), 0.1 + 0.01 * k)
    assert twists(drain(pilot))[-1][0] > 0.5
    return pilot, 0.19


def test_a_stall_shorter_than_disarm_after_hovers_then_steers_on_without_a_jump():
    pilot, t = flying_forward(PilotParams(navdata_timeout=10.0, disarm_after=1.0))
    out = silence(pilot, t, t + 0.6)                        # the sender stalls 0.6 s
    assert out and all(c.kind == 'twist' and c.twist == (0.0,) * 6 for c in out)
    t += 0.6
    # Back 150 mm to the side and 100 mm up: no new unfold, and no jump (re-captured).
    pilot.on_hand(stamped((0.15, 0.3, -0.1), t), t)
    assert twists(drain(pilot)) == [(0.0,) * 6]
    pilot.on_hand(stamped((0.15, 0.3, -0.2), t + 0.01), t + 0.01)   # then 100 mm forward
    tw = twists(drain(pilot))
    assert tw[-1][0] == pytest.approx(0.7) and tw[-1][1:] == (0.0,) * 5
    out = []                       # steered on past land_after (3 s) from the loss: no landing
    for k in range(1, 200):
        now = t + 0.01 + 0.02 * k
        pilot.on_hand(stamped((0.15, 0.3, -0.2), now), now)
        pilot.watchdog(now)
        out += drain(pilot)
    assert set(kinds(out)) == {'twist'} and twists(out)[-1][0] == pytest.approx(0.7)


def test_a_stream_back_from_a_stall_at_older_stamps_needs_a_new_unfold():
    # A bag played again after a 0.6 s silence: its hand steered on from the old session's
    # reference without an unfold.
    warned = []
    pilot, t = flying_forward(PilotParams(navdata_timeout=10.0, disarm_after=1.0))
    pilot._warn = lambda key, text: warned.append(key)
    silence(pilot, t, t + 0.6)
    t += 0.6
    pilot.on_hand(stamped((0.0, 0.2, -0.1), 0.05), t)              # stamped before the stall
    assert twists(drain(pilot)) in ([], [(0.0,) * 6]) and not pilot.engaged
    assert 'disengaged' in warned
    pilot.on_gesture('unfold', True, t + 0.01)
    pilot.on_hand(stamped((0.0, 0.2, -0.1), 0.06), t + 0.02)       # steers again once unfolded
    pilot.on_hand(stamped((0.0, 0.2, -0.2), 0.07), t + 0.03)
    assert pilot.engaged and twists(drain(pilot))[-1][0] == pytest.approx(0.7)


def test_a_hand_held_through_a_stall_keeps_its_reference():
    # Held 100 mm forward through a 0.6 s stall and back where it was lost: the forward
    # command resumes, and the unfold's neutral still hovers. Re-captured there, the old
    # neutral would have flown the drone backwards.
    pilot, t = flying_forward(PilotParams(navdata_timeout=10.0, disarm_after=1.0))
    t += 0.01
    pilot.on_hand(stamped((0.0, 0.2, -0.1), t), t)
    before = twists(drain(pilot))[-1]
    assert before[0] == pytest.approx(0.7)
    assert all(c.twist == (0.0,) * 6 for c in silence(pilot, t, t + 0.6))
    t += 0.6
    pilot.on_hand(stamped((0.0, 0.2, -0.1), t), t)
    assert twists(drain(pilot)) == [before]
    pilot.on_hand(stamped((0.0, 0.2, 0.0), t + 0.01), t + 0.01)        # the unfold's neutral
    assert twists(drain(pilot)) == [(0.0,) * 6]
    # recapture_beyond 0 re-captures on every return: the old behaviour
    pilot, t = flying_forward(PilotParams(navdata_timeout=10.0, recapture_beyond=0.0))
    silence(pilot, t, t + 0.6)
    pilot.on_hand(stamped((0.0, 0.2, -0.1), t + 0.6), t + 0.6)
    assert twists(drain(pilot)) == [(0.0,) * 6]


@pytest.mark.parametrize('turn, kept', [(5.0, True), (70.0, False)])
def test_a_hand_back_turned_where_it_was_lost_is_re_captured(turn, kept):
    # Back at the same spot turned 70 deg: the old reference gave full yaw at once.
    pilot, t = flying_forward(PilotParams(navdata_timeout=10.0, disarm_after=1.0))
    silence(pilot, t, t + 0.6)
    t += 0.6
    pilot.on_hand(oriented(rotation((0.0, 1.0, 0.0), turn), (0.0, 0.2, -0.1), t), t)
    first = twists(drain(pilot))[-1]
    if kept:                         # a small turn: the forward command goes on
        assert first[0] == pytest.approx(0.7) and first[5] == 0.0
    else:
        assert first == (0.0,) * 6


def test_an_unfold_that_came_while_the_hand_was_away_captures_when_it_comes_back():
    # Not engaged, the hand drops out briefly and the unfold arrives in the gap (its own
    # topic): there is no reference to keep, so the hand's return captures one, even
    # where the hand was lost.
    pilot = DronePilot(PilotParams(navdata_timeout=10.0))
    pilot.on_navdata(3, 1000, 0.0)
    pilot.on_hand(stamped((0.0, 0.2, -0.1), 0.0), 0.0)
    pilot.on_hand(stamped((0.0, 0.2, -0.1), 0.01, present=False), 0.01)
    pilot.on_gesture('unfold', True, 0.02)
    drain(pilot)
    pilot.on_hand(stamped((0.0, 0.2, -0.1), 0.1), 0.1)
    assert twists(drain(pilot)) == [(0.0,) * 6]
    pilot.on_hand(stamped((0.0, 0.2, -0.2), 0.11), 0.11)
    assert twists(drain(pilot))[-1][0] == pytest.approx(0.7)


@pytest.mark.parametrize('gone', ['silent', 'absent'])
def test_a_loss_longer_than_disarm_after_needs_a_new_unfold_then_lands_after_land_after(gone):
    warnings = []
    pilot, t = flying_forward(PilotParams(navdata_timeout=10.0, disarm_after=1.0,
                                          land_after=3.0))
    pilot._warn = lambda key, text: warnings.append(text)
    if gone == 'absent':
        pilot.on_hand(stamped((0.0, 0.0, 0.0), t, present=False), t)
    out = silence(pilot, t, t + 1.3)
    assert all(c.kind == 'twist' and c.twist == (0.0,) * 6 for c in out)
    assert any('steering off until a new unfold' in w for w in warnings)
    t += 1.3
    for k in range(20):                                     # back, 100 mm forward: hover on
        pilot.on_hand(stamped((0.0, 0.2, -0.2), t + 0.01 * k), t + 0.01 * k)
    assert all(tw == (0.0,) * 6 for tw in twists(drain(pilot)))
    # An unfold while flying steers again (no takeoff), from where the hand is.
    t += 0.2
    pilot.on_gesture('unfold', True, t)
    pilot.on_hand(stamped((0.0, 0.2, -0.2), t), t)
    out = drain(pilot)
    assert 'takeoff' not in kinds(out) and twists(out)[-1] == (0.0,) * 6
    pilot.on_hand(stamped((0.0, 0.2, -0.3), t + 0.01), t + 0.01)
    assert twists(drain(pilot))[-1][0] == pytest.approx(0.7)
    # A loss beyond land_after lands, as before.
    out = silence(pilot, t + 0.01, t + 3.5)
    assert kinds(out).count('land') == 1


def test_stale_input_never_flies_the_drone():
    # A stream that stalls and then bursts its backlog (stamps continue, late): the
    # backlog is refused; the pilot keeps hovering and steers on only with fresh input.
    pilot, t = flying_forward(PilotParams(navdata_timeout=10.0, disarm_after=1.0))
    silence(pilot, t, t + 0.6)
    rejected = pilot.rejected_inputs
    for k in range(30):                          # captured in the stall's first 0.3 s
        pilot.on_hand(stamped((0.0, 0.4, -0.3), t + 0.01 * k), t + 0.6 + 0.0005 * k)
    assert pilot.rejected_inputs == rejected + 30
    assert drain(pilot) == []
    assert pilot.hand_present is False


def test_a_new_input_connection_judges_lateness_afresh():
    pilot = DronePilot(PilotParams(navdata_timeout=10.0))
    pilot.on_navdata(3, 1000, 0.0)
    pilot.on_hand(stamped((0.0, 0.2, 0.0), 0.6), 0.0)        # the clock lagged: a low baseline
    assert all(pilot.on_hand(stamped((0.0, 0.2, 0.0), 0.01 * k), 0.01 * k + 0.01)
               for k in range(1, 4))                          # then every message late
    pilot.new_input_connection()
    assert not any(pilot.on_hand(stamped((0.0, 0.2, 0.0), 0.05 + 0.01 * k), 0.06 + 0.01 * k)
                   for k in range(3))
    # held up on top of the new baseline: refused
    assert pilot.on_hand(stamped((0.0, 0.2, 0.0), 0.08), 0.6).startswith('late')


def test_paper_mode_loss_longer_than_disarm_after_needs_the_capture_pose_again():
    pilot = DronePilot(PilotParams(mode='paper', navdata_timeout=10.0, disarm_after=1.0))
    pilot.on_navdata(3, 1000, 0.0)
    tilted = dict(normal=(0.6, -0.8, 0.0), direction=(0.0, 0.6, -0.8))
    pilot.on_hand(PilotInput(True, (0.0, 0.2, 0.0), **tilted), 0.0)     # captures
    assert pilot.paper_ref is not None and twists(drain(pilot))
    silence(pilot, 0.0, 0.5)
    pilot.on_hand(hand((0.0, 0.2, -0.1)), 0.5)                         # short: steers on
    assert twists(drain(pilot))
    silence(pilot, 0.5, 2.0)
    pilot.on_hand(hand((0.0, 0.2, -0.1)), 2.0)                         # long: nothing
    assert pilot.paper_ref is None and drain(pilot) == []


# -- queue ------------------------------------------------------------------------------
def test_queue_is_bounded_and_keeps_discrete_commands():
    q = CommandQueue(3)
    q.push(Command('takeoff'))
    for i in range(5):                       # consecutive twists coalesce: latest wins
        q.push(Command('twist', (float(i),) + (0.0,) * 5))
    q.push(Command('land'))
    items = [q.popleft() for _ in range(len(q))]
    assert [c.kind for c in items] == ['takeoff', 'twist', 'land']
    # the land puts a hover in place of the unsent twist
    assert items[1].twist == (0.0,) * 6 and q.dropped == 5
    for kind in ('twist', 'flip', 'twist', 'land', 'twist'):
        q.push(Command(kind))                # full (3): the oldest twist goes first
    assert [c.kind for c in (q.popleft() for _ in range(len(q)))] == ['flip', 'land', 'twist']


def test_twists_are_paced_at_the_rate_but_not_a_stop_or_a_land():
    pilot = DronePilot(PilotParams(rate=50.0))
    steer = Command('twist', (0.5, 0.0, 0.0, 0.0, 0.0, 0.0))
    pilot.queue.push(steer)
    pilot.queue.push(Command('flip'))
    pilot.queue.push(steer)
    cmd, _ = pilot.pop(10.0)
    assert cmd.kind == 'twist'
    cmd, _ = pilot.pop(10.001)
    assert cmd.kind == 'flip'                                # discrete: not paced
    cmd, wait = pilot.pop(10.005)
    assert cmd is None and wait == pytest.approx(0.015)
    cmd, _ = pilot.pop(10.02)
    assert cmd is steer
    # The hover after steering goes at once (at 2 Hz it waited 0.49 s); a hover after a
    # hover keeps the pace.
    pilot.queue.push(Command('twist'))
    cmd, _ = pilot.pop(10.021)
    assert cmd.twist == (0.0,) * 6
    pilot.queue.push(Command('twist'))
    cmd, wait = pilot.pop(10.022)
    assert cmd is None and wait == pytest.approx(0.019)
    assert pilot.pop(10.041)[0].twist == (0.0,) * 6
    # A land puts a hover in place of the steering not sent yet: neither waits.
    pilot.queue.push(steer)
    pilot.queue.push(Command('land'))
    assert pilot.pop(10.042)[0].twist == (0.0,) * 6 and pilot.pop(10.043)[0].kind == 'land'


def test_bad_config_rejected():
    with pytest.raises(ValueError):
        PilotParams().update({'mode': 'joystick'})
    with pytest.raises(ValueError):
        PilotParams().update({'flip_type': 25})


@pytest.mark.parametrize('key, value', [('hand_timeout', 0.005), ('hand_timeout', 0.01),
                                        ('navdata_timeout', 0.01), ('navdata_timeout', 0.02)])
def test_timeouts_within_a_message_interval_are_refused(key, value):
    # Below the Hand (~10 ms) or navdata (20 ms) interval every gap between two messages
    # was a loss: cmd_vel went forward / hover / forward at the Hand rate.
    with pytest.raises(ValueError, match=key):
        PilotParams().update({key: value})


def test_the_shortest_timeouts_accepted_steer_steadily_between_messages():
    cfg = PilotParams().update({'hand_timeout': PILOT_PARAMS['hand_timeout'].ge,
                                'navdata_timeout': PILOT_PARAMS['navdata_timeout'].ge})
    warned = []
    pilot = airborne(cfg)
    pilot._warn = lambda key, text: warned.append(key)
    drain(pilot)
    sent = []
    for i in range(1, 101):         # Hand at 100 Hz, navdata at 50 Hz, the watchdog between
        t = 0.01 * i
        if i % 2 == 0:
            pilot.on_navdata(3, 1000, t)
        pilot.on_hand(hand((0.0, 0.2, -0.08)), t)
        pilot.watchdog(t + 0.009)
        sent += twists(drain(pilot))
    assert len(sent) == 100 and all(tw[0] > 0.0 for tw in sent) and warned == []


@pytest.mark.parametrize('mode', ['tilt', 'paper'])
def test_absurd_palm_positions_are_rejected_not_flown(mode):
    # Found by fuzzing: a finite but absurd palm (1.8e305 m) made paper mode's twist infinite.
    # Engaged first (tilt: unfold; paper: the capture pose), so an accepted palm would fly.
    if mode == 'tilt':
        pilot = airborne(PilotParams(mode=mode, navdata_timeout=10.0))
    else:
        pilot = DronePilot(PilotParams(mode=mode, navdata_timeout=10.0))
        pilot.on_navdata(3, 1000, 0.0)
        pilot.on_hand(PilotInput(True, (0.0, 0.2, 0.0), normal=(0.6, -0.8, 0.0),
                                 direction=(0.0, 0.6, -0.8)), 0.0)
    pilot.on_hand(hand((0.0, 0.2, -0.1)), 0.01)                        # steering forward
    before = twists(drain(pilot))[-1]
    assert before[0] > 0.0
    pilot.on_hand(PilotInput(True, palm=(1.797693134862316e+305, 0.0, 0.0)), 0.02)
    pilot.on_hand(PilotInput(True, palm=(0.0, 0.2, 0.0), normal=(0.0, -30.0, 0.0)), 0.03)
    assert pilot.rejected_inputs == 2
    after = twists(drain(pilot))
    assert all(math.isfinite(v) for tw in after for v in tw)
    assert all(tw == before for tw in after)                # the absurd palms moved nothing


def test_fingertip_sized_circles_never_flip_a_flying_drone():
    # A pointing index draws circles of 10-24 mm (the recognizer's fingertip circles; the
    # loops fingertips make by themselves on the recordings were 4-20 mm): none flips, a
    # hand-sized circle (>= flip_min_radius, 25 mm) does.
    radii = [0.004, 0.010, 0.0125, 0.016, 0.020, 0.0245, 0.025, 0.035, 0.080]
    circles = [('circle_cw' if i % 2 else 'circle_ccw', r) for i, r in enumerate(radii)]

    def flips(config):
        pilot = DronePilot(config)
        pilot.on_navdata(4, 1500, 0.0)
        pilot.on_hand(hand((0.0, 0.2, 0.0)), 0.0)
        for gesture, radius in circles:
            pilot.on_gesture(gesture, True, 0.0, radius)
            pilot.on_navdata(4, 1500, 0.0)       # the flip is over before the next circle
        return kinds(drain(pilot)).count('flip')
    assert flips(PilotParams()) == 3
    assert flips(PilotParams(flip_min_radius=0.0)) == len(circles)     # what the gate stops


def test_the_diagnostics_report_says_what_the_worker_and_pilot_see():
    from leap_teleop.control.service_call import ServiceCall
    from leap_teleop.drone.pilot import PilotWorker
    now = [0.0]
    pilot = DronePilot(PilotParams(navdata_timeout=0.5, hand_timeout=0.15))
    worker = PilotWorker(pilot, lambda cmd: None, ServiceCall(lambda *a: True, 0.5, 'flip'),
                         lambda: now[0], mono=lambda: 1e6 + now[0])
    level, summary, values = worker.diagnostics(0.0)
    assert (level, summary) == ('ok', 'hand not seen yet, drone state None')
    assert dict(values)['navdata'] == 'fresh' and dict(values)['flip calls ok'] == 0
    pilot.on_navdata(3, 1000, 0.2)
    pilot.on_hand(hand((0.0, 0.2, 0.0)), 0.2)
    assert worker.diagnostics(0.2)[:2] == ('ok', 'hand tracked, drone state 3')
    pilot.on_hand(hand((0.0, 0.2, 0.0), present=False), 0.3)
    now[0] = 0.3
    worker.step()
    assert worker.diagnostics(0.3)[:2] == ('warn', 'hand lost, drone state 3')
    now[0] = 1.0
    worker.step()                                 # navdata 0.8 s old: stale
    level, summary, values = worker.diagnostics(1.2)
    assert level == 'warn' and summary.startswith('no navdata for 1.0 s (hand lost')
    assert dict(values)['navdata'] == 'stale'
    pilot.watchdog = lambda t: 1 / 0              # a fault in the worker's step
    worker.step()
    level, summary, values = worker.diagnostics(1.0)
    assert level == 'error' and summary.startswith('worker fault: ZeroDivisionError')
    assert dict(values)['worker faults'] == 1


def test_a_hand_arriving_while_the_worker_reads_its_clock_is_not_a_clock_jump():
    # The race a loaded machine hits: the worker reads the clock, a hand callback (its own
    # thread, a later reading) gets in before the watchdog runs. Read outside the lock,
    # that reading looked like the clock going back: hover, hand lost, reference moved.
    import threading

    from leap_teleop.control.service_call import ServiceCall
    from leap_teleop.drone.pilot import PilotWorker
    warned = []
    pilot = DronePilot(PilotParams(), warn=lambda key, text: warned.append(key))
    pilot.on_navdata(2, 0, 0.0)
    pilot.on_hand(hand((0.0, 0.2, 0.0)), 0.0)
    pilot.on_gesture('unfold', True, 0.0)
    pilot.on_navdata(3, 1000, 0.01)

    def clock():
        callback = threading.Thread(target=pilot.on_hand, args=(hand((0.0, 0.2, 0.05)), 0.031))
        callback.start()
        callback.join(0.3)               # blocked on the pilot's lock: the watchdog goes first
        return 0.03

    worker = PilotWorker(pilot, lambda cmd: None, ServiceCall(lambda *a: True, 0.5, 'flip'), clock)
    worker.step()
    assert 'clock' not in warned and pilot.hand_present and pilot.engaged, warned
    assert pilot.reference[0] == (0.0, 0.2, 0.0)          # the unfold's, not re-captured


def test_the_worker_runs_until_stopped_and_paces_twists_at_the_rate():
    import time

    from leap_teleop.control.service_call import ServiceCall
    from leap_teleop.drone.pilot import PilotWorker
    pilot = airborne(PilotParams(rate=20.0))
    sent = []

    def send(cmd):
        sent.append((time.monotonic(), cmd.kind, cmd.twist))
        if len(sent) == 2:                          # the next hand, right after a twist
            pilot.on_hand(hand((0.0, 0.2, 0.1)), 0.03)

    worker = PilotWorker(pilot, send, ServiceCall(lambda *a: True, 0.5, 'flip'), lambda: 0.05)
    pilot.on_hand(hand((0.0, 0.2, -0.1)), 0.02)
    start = time.monotonic()
    worker.run(lambda: len(sent) >= 3 or time.monotonic() - start > 2.0)
    assert [k for _, k, _ in sent] == ['takeoff', 'twist', 'twist', 'twist'], sent
    assert sent[2][0] - sent[1][0] >= 1 / 20.0 - 0.005        # the second twist waited its slot
    # Stopped while flying backwards: the last word is a hover (the driver holds the last).
    assert sent[2][2][0] < -0.5 and sent[3][2] == (0.0,) * 6, sent


# -- what a normal session logs -----------------------------------------------------------
def run_ticks(pilot, t0, t1, navdata=None, hands=False, dt=0.02):
    """Watchdog ticks from t0 to t1; navdata (state, altitude mm) and a centred hand at
    each tick when given."""
    for i in range(int(round((t1 - t0) / dt))):
        t = t0 + i * dt
        if navdata is not None:
            pilot.on_navdata(*navdata, t)
        if hands:
            pilot.on_hand(PilotInput(True, (0.0, 0.2, 0.0), stamp=t), t)
        pilot.watchdog(t)
        drain(pilot)


def test_a_normal_start_and_end_on_the_ground_say_nothing():
    # Every start warned 'no navdata yet: drone state unknown, hovering' and 'navdata
    # arrived after 0.11 s', and the end of a session 'no Hand message for 0.15 s:
    # hovering', all while the drone sat landed.
    warned = []
    pilot = DronePilot(PilotParams(), warn=lambda key, text: warned.append(text))
    run_ticks(pilot, 0.0, 0.12)                               # the driver not up yet
    run_ticks(pilot, 0.12, 2.0, navdata=(2, 0), hands=True)   # a session on the ground
    run_ticks(pilot, 2.0, 3.0, navdata=(2, 0))                # the hands stop
    assert warned == []


def test_navdata_late_past_its_timeout_at_start_is_one_warning_and_its_arrival_another():
    warned = []
    cfg = PilotParams()
    pilot = DronePilot(cfg, warn=lambda key, text: warned.append(text))
    run_ticks(pilot, 0.0, cfg.navdata_timeout + 0.1)
    assert warned == ['no navdata yet: drone state unknown, hovering']
    run_ticks(pilot, 1.0, 1.1, navdata=(2, 0))
    assert warned[1:] == ['navdata arrived after 1.00 s']


def test_losses_in_flight_still_say_hovering_and_navdata_lost_on_the_ground_says_landed():
    warned = []
    pilot = airborne(PilotParams())
    pilot._warn = lambda key, text: warned.append(text)
    run_ticks(pilot, 0.0, 1.0, navdata=(3, 1000), hands=True)
    run_ticks(pilot, 1.0, 1.3, navdata=(3, 1000))
    assert [w for w in warned if w.startswith('no Hand message')] == [
        'no Hand message for 0.16 s: hovering']
    run_ticks(pilot, 1.3, 2.0)
    assert warned[-1] == 'no navdata for 0.52 s: drone state unknown, hovering'
    warned.clear()
    landed = DronePilot(PilotParams(), warn=lambda key, text: warned.append(text))
    run_ticks(landed, 0.0, 1.0, navdata=(2, 0))
    run_ticks(landed, 1.0, 1.6)
    assert warned == ['no navdata for 0.52 s: drone state unknown, last seen landed']
