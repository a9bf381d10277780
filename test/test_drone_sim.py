"""ArDroneSim: the driver's cmd_vel semantics, states, flips, limits, battery."""
import math

import pytest

from leap_teleop.drone import sim as ds
from leap_teleop.drone.sim import ArDroneSim

# needs a ROS master, a simulator, a subprocess or a build: not in make check
pytestmark = pytest.mark.integration


@pytest.fixture
def warnings():
    return []


@pytest.fixture
def drone(warnings):
    d = ArDroneSim(warn=lambda key, text: warnings.append((key, text)))
    yield d
    d.close()


def fly(d, timeout=8.0):
    assert d.takeoff()
    t0 = d.time
    while d.state != ds.HOVERING and d.time - t0 < timeout:
        d.step()
    assert d.state == ds.HOVERING
    d.advance(1.0)
    return d


def states(d):
    return [s for _, s in d.events]


def test_takeoff_climbs_to_about_1m_and_hovers(drone):
    assert drone.state == ds.LANDED and drone.altitude == pytest.approx(0.0, abs=0.01)
    fly(drone)
    assert states(drone) == [ds.TAKING_OFF, ds.HOVERING]
    assert drone.altitude == pytest.approx(1.0, abs=0.1)
    nav = drone.navdata()
    assert nav['state'] == ds.HOVERING and abs(nav['altd'] - 1000) < 100
    assert nav['az'] == pytest.approx(1.0, abs=0.05)       # specific force in g


@pytest.mark.parametrize('values', [{'takeoff_altitude': 0.03}, {'takeoff_altitude': 0.08},
                                    {'altitude_max': 90.0}])
def test_a_takeoff_that_would_end_below_the_floor_is_refused(values):
    # 0.03 m: 'hovering' at 1 mm on the floor; up to altitude_min + 0.03 m: held below it
    with pytest.raises(ValueError, match='at least altitude_min'):
        ArDroneSim(values)


def test_a_takeoff_to_the_lowest_level_taken_hovers_above_the_floor():
    d = ArDroneSim({'takeoff_altitude': 0.1}, warn=lambda key, text: None)
    try:
        fly(d)
        d.advance(2.0)
        assert d.state == ds.HOVERING and d.navdata()['altd'] >= d.p.altitude_min + 20
    finally:
        d.close()


def test_land_sequence_and_motors_off(drone):
    fly(drone)
    assert drone.land()
    drone.advance(6.0)
    assert states(drone) == [ds.TAKING_OFF, ds.HOVERING, ds.LANDING, ds.LANDED]
    assert drone.altitude < 0.02 and max(drone.motors) == 0.0


def test_commands_that_make_no_sense_are_ignored_with_a_warning(drone, warnings):
    assert not drone.land()                       # landed already
    assert not drone.flight_animation(19, 0)      # not flying
    drone.set_cmd_vel(0.5, 0, 0, 0, 0, 0)        # landed: held, nothing moves yet
    drone.advance(0.5)
    assert drone.state == ds.LANDED and drone.altitude < 0.01
    drone.set_cmd_vel()                           # the driver holds the last command
    fly(drone)
    assert not drone.takeoff()                    # already flying
    assert {k for k, _ in warnings} >= {'land', 'anim', 'cmd_vel_landed', 'takeoff'}
    assert not drone.set_cmd_vel(float('nan'))    # non-finite: rejected, state kept
    assert drone.state == ds.HOVERING


def test_hover_holds_altitude_within_5cm_for_10s(drone):
    fly(drone)
    drone.set_cmd_vel(0, 0, 0, 0, 0, 0)
    a0, x0 = drone.altitude, drone.pos[:2]
    worst = 0.0
    for _ in range(int(10.0 / drone.dt)):
        drone.step()
        worst = max(worst, abs(drone.altitude - a0))
    assert worst < 0.05
    assert math.dist(drone.pos[:2], x0) < 0.05       # auto-hover holds position too
    assert drone.state == ds.HOVERING


def test_linear_x_half_tilts_to_half_euler_angle_max_within_0_3s(drone):
    fly(drone)
    target = 0.5 * drone.p.euler_angle_max
    drone.set_cmd_vel(0.5, 0, 0, 0, 0, 0)
    drone.advance(0.3)
    assert drone.pitch == pytest.approx(target, rel=0.1)     # nose down = +pitch
    assert drone.navdata()['rotY'] == pytest.approx(math.degrees(target), rel=0.1)
    drone.advance(1.5)
    assert drone.vel[0] > 0.5 and drone.state == ds.FLYING
    assert abs(drone.altitude - 1.0) < 0.1                   # tilting does not sink


def test_linear_y_left_and_clamping(drone):
    fly(drone)
    drone.set_cmd_vel(0, 5.0, 0, 0, 0, 0)            # clamped to 1: full left tilt
    assert drone.cmd[1] == 1.0
    drone.advance(0.5)
    assert drone.roll == pytest.approx(-drone.p.euler_angle_max, rel=0.1)  # left side down
    drone.advance(1.0)
    assert drone.vel[1] > 0.5


def test_climb_rate_and_altitude_max(drone):
    drone.p.altitude_max = 1800.0
    fly(drone)
    drone.set_cmd_vel(0, 0, 0.5, 0, 0, 0)
    drone.advance(0.5)
    assert drone.vel[2] == pytest.approx(0.5 * drone.p.control_vz_max / 1000, rel=0.1)
    drone.set_cmd_vel(0, 0, 1.0, 0, 0, 0)
    drone.advance(5.0)
    assert drone.altitude == pytest.approx(1.8, abs=0.05)   # stops at altitude_max
    drone.set_cmd_vel(0, 0, -1.0, 0, 0, 0)
    drone.advance(6.0)
    assert drone.altitude == pytest.approx(drone.p.altitude_min / 1000, abs=0.03)
    assert drone.state == ds.FLYING                          # altitude_min is not a landing


def test_yaw_rate_positive_is_left(drone):
    fly(drone)
    yaw0 = drone.yaw
    drone.set_cmd_vel(0, 0, 0, 0, 0, 0.5)
    drone.advance(1.0)
    assert drone.omega[2] == pytest.approx(0.5 * drone.p.control_yaw, rel=0.1)
    assert drone.yaw > yaw0                                 # counter-clockwise


def test_angular_xy_nonzero_disables_auto_hover(drone):
    fly(drone)
    drone.set_cmd_vel(1.0, 0, 0, 0, 0, 0)
    drone.advance(1.0)
    drone.set_cmd_vel(0, 0, 0, 0.1, 0.1, 0)      # no tilt, but no auto-hover: coasts
    drone.advance(1.0)
    assert drone.state == ds.FLYING and drone.vel[0] > 0.3
    drone.set_cmd_vel(0, 0, 0, 0, 0, 0)          # auto-hover brakes
    drone.advance(3.0)
    assert drone.state == ds.HOVERING and abs(drone.vel[0]) < 0.05


@pytest.mark.parametrize('kind', [ds.FLIP_AHEAD, ds.FLIP_BEHIND, ds.FLIP_LEFT, ds.FLIP_RIGHT])
def test_flip_turns_360_degrees_and_recovers(drone, kind):
    fly(drone)
    alt0 = drone.altitude
    assert drone.flight_animation(kind, 0)
    assert drone.state == ds.LOOPING
    axis, sign = ds.FLIP_AXES[kind]
    turned, inverted = 0.0, False
    t0 = drone.time
    while drone.state == ds.LOOPING and drone.time - t0 < 5.0:
        drone.step()
        turned += sign * drone.omega[axis] * drone.dt
        inverted = inverted or drone.R[8] < -0.9            # body z pointed down once
    assert drone.state != ds.LOOPING, 'flip never finished'
    assert math.degrees(turned) == pytest.approx(360.0, abs=15.0)
    assert inverted
    assert drone.last_flip_min_altitude < alt0 - 0.05          # it loses some height
    drone.advance(2.0)
    assert drone.state == ds.HOVERING
    assert abs(drone.roll) < 0.03 and abs(drone.pitch) < 0.03
    assert drone.altitude == pytest.approx(alt0, abs=0.1)
    assert drone.flip_count == 1


def test_a_flip_that_strikes_the_floor_cuts_the_motors_and_reset_recovers():
    # From 0.15 m the spin ends upside down on the floor: it looped there with two motors
    # at full for ever, and a land was answered true and never happened.
    d = ArDroneSim(warn=lambda key, text: None, params={'takeoff_altitude': 0.15})
    try:
        fly(d)
        assert d.flight_animation(ds.FLIP_RIGHT, 0)
        t0 = d.time
        while d.state == ds.LOOPING and d.time - t0 < ds.FLIP_CUTOFF_S + 1.0:
            d.step()
        assert d.state == ds.UNKNOWN and d.emergency
        assert d.time - t0 == pytest.approx(ds.FLIP_CUTOFF_S, abs=0.05)
        d.advance(1.0)
        nav = d.navdata()
        assert [nav['motor%d' % i] for i in range(1, 5)] == [0, 0, 0, 0]
        assert d.reset() and d.state == ds.LANDED
        assert not d.takeoff()                                  # upside down
    finally:
        d.close()


def test_bad_animation_type_refused_other_types_accepted(drone, warnings):
    fly(drone)
    assert not drone.flight_animation(20, 0)
    assert not drone.flight_animation(-1, 0)
    assert any('not in 0..19' in text for _, text in warnings)
    assert drone.flight_animation(6, 2000)                   # turnaround: a full yaw turn
    yaw_turned = 0.0
    for _ in range(int(2.0 / drone.dt)):
        drone.step()
        yaw_turned += drone.omega[2] * drone.dt
    assert math.degrees(yaw_turned) == pytest.approx(360.0, abs=40.0)
    drone.advance(2.0)
    assert drone.state == ds.HOVERING


def test_reset_toggles_emergency(drone):
    fly(drone)
    drone.reset()
    assert drone.state == ds.UNKNOWN and drone.emergency
    drone.advance(1.5)
    assert drone.altitude < 0.05 and max(drone.motors) == 0.0   # motors off: it fell
    assert not drone.takeoff()
    drone.reset()
    assert drone.state == ds.LANDED and not drone.emergency
    assert drone.takeoff()


def test_a_land_during_a_flip_lands_once_it_has_caught_upright(drone):
    # Cut short upside down, the landing thrust drove it into the ground at 8 m/s, it then
    # read 'landed' on its back, and a takeoff from there never ended.
    fly(drone)
    assert drone.flight_animation(19, 0)
    while drone.R[8] > -0.3:                            # well past 90 deg
        drone.step()
    assert drone.land() and drone.state == ds.LOOPING  # taken, for after the flip
    fastest = 0.0
    for _ in range(int(6.0 / drone.dt)):
        drone.step()
        fastest = max(fastest, -drone.vel[2])
    assert states(drone)[-3:] == [ds.LOOPING, ds.LANDING, ds.LANDED]
    assert fastest < 2.5 and drone.R[8] > 0.99 and drone.flip_count == 1
    # A flip cut short by a battery landing takes the land asked in it along: the next
    # flip ended in a landing nobody asked for.
    fly(drone)
    assert drone.flight_animation(19, 0)
    drone.advance(0.3)
    assert drone.land() and drone.state == ds.LOOPING
    drone.battery = 0.0
    drone.advance(8.0)
    assert drone.state == ds.LANDED
    drone.battery = 100.0
    fly(drone)
    assert drone.flight_animation(19, 0)
    drone.advance(4.0)
    assert drone.state == ds.HOVERING and drone.flip_count == 3    # the battery's waited too


def test_an_empty_battery_during_a_flip_lands_once_it_has_caught_upright(drone):
    # The battery's landing cut the flip short upside down: down at 4.2 m/s, the hull
    # 9 cm into the floor (a land() asked then waited for the catch).
    import pybullet as pb
    fly(drone)
    assert drone.flight_animation(ds.FLIP_RIGHT, 0)
    while drone.R[8] > -0.3:                            # well past 90 deg
        drone.step()
    drone.battery = 0.0
    fastest, lowest = 0.0, 1.0
    for _ in range(int(6.0 / drone.dt)):
        drone.step()
        fastest = max(fastest, -drone.vel[2])
        lowest = min(lowest, pb.getAABB(drone.body, physicsClientId=drone.client)[0][2])
    assert states(drone)[-3:] == [ds.LOOPING, ds.LANDING, ds.LANDED]
    assert drone.flip_count == 1 and fastest < 2.5 and lowest > -0.01


def test_a_drone_on_its_back_does_not_take_off(drone, warnings):
    import pybullet as pb
    pb.resetBasePositionAndOrientation(drone.body, drone.pos, (1.0, 0.0, 0.0, 0.0),
                                       physicsClientId=drone.client)
    drone.advance(0.5)
    assert not drone.takeoff() and drone.state == ds.LANDED
    assert any('not upright' in text for _, text in warnings)


def test_leaving_an_emergency_in_the_air_is_landed_only_once_down(drone):
    fly(drone)
    drone.reset()
    drone.advance(0.1)                                  # falling, motors off
    drone.reset()
    assert not drone.emergency and drone.state == ds.UNKNOWN   # was 'landed' at 968 mm
    assert not drone.takeoff()
    drone.advance(2.0)
    assert drone.state == ds.LANDED and drone.altitude < 0.03 and drone.takeoff()


def test_a_hover_after_a_full_descent_holds_at_the_altitude_floor(drone):
    fly(drone)
    drone.set_cmd_vel(0, 0, -1.0, 0, 0, 0)
    drone.advance(4.0)                                  # overshoots the floor a little
    drone.set_cmd_vel()
    drone.advance(3.0)
    assert drone.state == ds.HOVERING
    assert drone.altitude == pytest.approx(drone.p.altitude_min / 1000, abs=0.005)   # was 38 mm


def test_battery_drains_and_empty_battery_lands(drone):
    drone.p.battery_flight_time = 20.0
    fly(drone)
    b = drone.battery
    drone.advance(2.0)
    assert drone.battery == pytest.approx(b - 10.0, abs=2.0)
    drone.advance(30.0)
    assert drone.battery == 0.0 and drone.state == ds.LANDED
    assert not drone.takeoff()


def test_link_loss_landing_when_enabled_lands_a_quiet_hover_and_says_why(drone, warnings):
    # The simulator sees only the pilot's commands: a pilot hovering without sending (as
    # drone_pilot does with the hand lost) is taken for a lost link. That landing was
    # explained as 'link loss' alone, as if the link had broken.
    fly(drone)
    drone.p.link_timeout = 2.0
    drone.set_cmd_vel(0, 0, 0, 0, 0, 0)
    drone.advance(1.5)
    assert drone.state == ds.HOVERING
    drone.advance(5.0)
    assert drone.state == ds.LANDED
    said = [text for key, text in warnings if key == 'link']
    assert len(said) == 1 and 'link_timeout' in said[0] and 'hovering without sending' in said[0]
    assert '0 turns it off' in said[0]


@pytest.mark.parametrize('link_timeout', [1.0, 2.0])
def test_a_link_timeout_lands_neither_a_takeoff_nor_a_flip_nobody_steers(link_timeout):
    # A pilot sends no cmd_vel while its drone takes off (2 s) or flips (1.8 s): at the
    # firmware's 2 s or less every takeoff (below 1.8 s, every flip) became a landing.
    d = ArDroneSim({'link_timeout': link_timeout}, warn=lambda key, text: None)
    try:
        assert d.takeoff()                      # no command at all while taking off
        while d.state == ds.TAKING_OFF and d.time < 4.0:
            d.step()
        assert d.state == ds.HOVERING
        d.set_cmd_vel()
        d.advance(0.5)
        assert d.flight_animation(ds.FLIP_RIGHT, 0)
        d.advance(2.5)                          # nothing sent through the flip
        assert ds.LANDING not in states(d) and d.flip_count == 1
        d.advance(link_timeout + 0.5)           # silent on after it: lost
        assert states(d)[-1] == ds.LANDING
    finally:
        d.close()


def test_params_validated():
    with pytest.raises(ValueError):
        ArDroneSim({'altitude_min': 5000.0})
    with pytest.raises(ValueError):
        ArDroneSim({'no_such_param': 1})


def test_snapshot_png(drone, tmp_path):
    fly(drone)
    img = drone.snapshot(str(tmp_path / 'drone.png'), 160, 120)
    assert img.shape == (120, 160, 3) and (tmp_path / 'drone.png').stat().st_size > 500
    assert img.std() > 5        # not a blank frame


def test_state_events_are_bounded(drone):
    # Every reset toggles the state twice; the history keeps only the latest changes.
    for _ in range(ds.EVENTS_KEPT):
        drone.reset()
    assert len(drone.events) == ds.EVENTS_KEPT
    assert drone.events[-1][1] == ds.LANDED and drone.events[-2][1] == ds.UNKNOWN


def test_driver_commands_flat_trim_leds_record_camera(drone, warnings):
    assert drone.flat_trim() and drone.flat_trims == 1          # landed: done
    assert drone.set_led_animation(3, 2.0, 4) and drone.led_active
    assert drone.led_animation[0] == 'BLINK_ORANGE'
    drone.advance(4.1)
    assert not drone.led_active
    assert not drone.set_led_animation(14, 2.0, 1)              # no such animation
    drone.advance(2.1)                                          # past the warning's limit
    for freq in (-1.0, 0.0, 1e38, float('nan'), float('inf')):   # no such blinking
        assert not drone.set_led_animation(3, freq, 1)
    assert warnings[-1] == ('led', 'LED animation ignored: frequency -1.0 Hz is not in (0, 100]')
    assert drone.set_record(True) and drone.recording
    assert drone.set_record(False) and not drone.recording
    assert drone.camera_channel == ds.CAMERA_FRONT
    assert drone.toggle_camera() and drone.camera_channel == ds.CAMERA_BOTTOM
    assert drone.toggle_camera() and drone.camera_channel == ds.CAMERA_FRONT
    assert drone.set_camera_channel(3) and drone.camera_channel == ds.CAMERA_BOTTOM  # mod 2
    fly(drone)
    assert not drone.flat_trim() and drone.flat_trims == 1      # the firmware refuses aloft
    assert any(key == 'flattrim' for key, _ in warnings)
