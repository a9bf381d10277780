"""DroneSimRunner and its helpers: what the ardrone_sim node runs, without a master."""
import math
import os

import numpy as np
import pybullet as pb
import pytest

from leap_teleop.drone import cameras
from leap_teleop.drone.sim import HOVERING, TAKING_OFF
from leap_teleop.drone.sim_runner import (
    RUNNER_PARAMS,
    DroneFrames,
    DroneSimRunner,
    calibration_error,
    check_combinations,
    sensor_readings,
    static_frames,
)
from leap_teleop.params import check_params

# needs a ROS master, a simulator, a subprocess or a build: not in make check
pytestmark = pytest.mark.integration


def params(**values):
    return check_params(RUNNER_PARAMS, values)


@pytest.fixture
def runner():
    r = DroneSimRunner(params(tf_prefix='/uav/'), use_sim_time=True)
    yield r
    r.close()


def test_frames_carry_the_tf_prefix_as_the_driver_does():
    f = DroneFrames('/drone1/', 'ardrone_base_link', 'odom')
    assert (f.base, f.odom) == ('drone1/ardrone_base_link', 'drone1/odom')
    assert f.cameras == {'front': 'drone1/ardrone_base_frontcam',
                         'bottom': 'drone1/ardrone_base_bottomcam'}
    plain = DroneFrames('', 'base', 'odom')
    assert (plain.base, plain.odom, plain.cameras['front']) == ('base', 'odom',
                                                                'ardrone_base_frontcam')


def test_optical_frames_look_where_the_cameras_render():
    """z along the view, y down in the image: the renderer's forward and up vectors."""
    frames = DroneFrames('', 'base', 'odom')
    out = static_frames(frames)
    assert [(parent, child) for parent, child, _, _ in out] == [
        ('base', 'ardrone_base_frontcam'), ('base', 'ardrone_base_bottomcam')]
    for (_, _, xyz, quat), spec in zip(out, (cameras.FRONT, cameras.BOTTOM)):
        R = np.array(pb.getMatrixFromQuaternion(quat)).reshape(3, 3)
        np.testing.assert_allclose(R[:, 2], spec.forward, atol=1e-12)
        np.testing.assert_allclose(-R[:, 1], spec.up, atol=1e-12)
        assert xyz == tuple(spec.mount)


def test_world_frame_adds_a_fixed_odom_origin():
    frames = DroneFrames('d2', 'base', 'odom')
    world = static_frames(frames, 'world', [1, 2.5, 0])[0]
    assert world == ('world', 'd2/odom', (1.0, 2.5, 0.0), (0.0, 0.0, 0.0, 1.0))
    assert len(static_frames(frames, '', [1, 2.5, 0])) == 2


def test_sensor_readings_turn_with_the_heading_and_fall_with_altitude():
    north = sensor_readings({'rotZ': 0.0}, 0.0)
    assert (north['magX'], north['magY'], north['magZ']) == (200, 0, -400)
    east = sensor_readings({'rotZ': 90.0}, 10.0)
    assert (east['magX'], east['magY']) == (0, -200)
    assert north['pressure'] - east['pressure'] == 120 and north['temp'] == 25


def test_calibration_must_have_the_cameras_size():
    assert calibration_error('front', 640, 360) == ''
    assert calibration_error('bottom', 640, 360) == 'bottom camera is 320x240, got 640x360'
    K, R, P = [500.0, 0, 320, 0, 500.0, 180, 0, 0, 1], [1.0, 0, 0, 0, 1, 0, 0, 0, 1], [0.0] * 12
    assert calibration_error('front', 640, 360, K, [0.0] * 5, R, P, 'plumb_bob') == ''
    # garbage was taken and published again on camera_info
    assert calibration_error('front', 640, 360, [math.nan] * 9) == 'K must be 9 finite numbers'
    assert calibration_error('front', 640, 360, [0.0] * 9).startswith('K: the focal lengths')
    assert calibration_error('front', 640, 360, K, [0.0] * 1000).startswith('D must be at most')
    assert calibration_error('front', 640, 360, K, (), R, P, 'x' * 100000).startswith(
        'distortion_model is 100000 characters')


@pytest.mark.parametrize('model, n, error', [
    ('plumb_bob', 5, ''), ('plumb_bob', 0, ''), ('rational_polynomial', 8, ''),
    ('equidistant', 4, ''), ('', 14, ''), ('my_model', 12, ''),
    ('plumb_bob', 3, 'D has 3 numbers: plumb_bob takes 5 (or none)'),
    ('plumb_bob', 8, 'D has 8 numbers: plumb_bob takes 5 (or none)'),
    ('equidistant', 7, 'D has 7 numbers: equidistant takes 4 (or none)'),
    ('rational_polynomial', 13, 'D has 13 numbers: rational_polynomial takes 8 (or none)'),
    ('no_such_model', 2, 'D has 2 numbers: a distortion model takes 0, 4, 5, 8, 12, 14')])
def test_a_calibration_s_distortion_has_a_model_s_length(model, n, error):
    # Any length up to 14 was taken and published again on camera_info, where a
    # rectifying consumer (OpenCV: 4, 5, 8, 12 or 14) failed on it.
    K = [500.0, 0, 320, 0, 500.0, 180, 0, 0, 1]
    assert calibration_error('front', 640, 360, K, [0.01] * n, None, None, model) == error


def test_readings_say_each_state_change_once(runner):
    first = runner.read()
    assert first.new_state == 'landed' and runner.read().new_state == ''
    assert {'magX', 'pressure', 'temp', 'altd', 'state'} <= set(first.nav)
    assert runner.frames.base == 'uav/ardrone_base_link'
    runner.call(runner.sim.takeoff)
    runner.sim.step()
    reading = runner.read()
    assert reading.nav['state'] == TAKING_OFF and reading.new_state == 'taking off'


def test_driver_commands_answer_with_what_to_log(runner):
    assert runner.toggle_camera() == 'video channel 1' and runner.sim.camera_channel == 1
    assert runner.set_camera_channel(2) == 'video channel 0'
    assert runner.set_led_animation(3, 2.0, 4) == 'LED animation BLINK_ORANGE at 2.0 Hz for 4 s'
    assert runner.set_led_animation(99, 2.0, 4) == ''          # refused: the sim warns
    assert runner.flat_trim() == 'flat trim done'
    assert runner.set_record(True) == 'video recording on' and runner.sim.recording
    assert runner.flight_animation(16, 0) == ''


def test_run_steps_a_looprate_tick_per_publish_until_stopped():
    r = DroneSimRunner(params(realtime_factor=0.0, looprate=50.0), use_sim_time=True)
    try:
        assert r.steps == 4 and r.pace_warning is None         # 200 Hz physics / 50 Hz
        r.call(r.sim.takeoff)
        times = []
        r.run(lambda: times.append(r.read().time), lambda: len(times) >= 250)
        assert times[0] == pytest.approx(0.02) and times[-1] == pytest.approx(5.0)
        assert r.read().nav['state'] == HOVERING
    finally:
        r.close()


def test_as_fast_as_possible_without_sim_time_runs_in_real_time():
    r = DroneSimRunner(params(realtime_factor=0.0), use_sim_time=False)
    try:
        assert r.factor == 1.0 and 'without /use_sim_time' in r.pace_warning
    finally:
        r.close()


def test_snapshot_is_written_where_asked_and_named_by_sim_time(tmp_path):
    r = DroneSimRunner(params(snapshot_dir=str(tmp_path / 'shots'), snapshot_size=[64, 48]),
                       use_sim_time=True)
    try:
        r.sim.advance(0.5)
        path = r.snapshot()
        assert path == str(tmp_path / 'shots' / 'ardrone_0000.500.png')
        with open(path, 'rb') as f:
            assert f.read(8) == b'\x89PNG\r\n\x1a\n'
    finally:
        r.close()


def test_a_failed_snapshot_leaves_no_empty_file(tmp_path):
    # The name is reserved as an empty file before the picture is drawn: a picture that
    # could not be drawn left that empty .png behind.
    r = DroneSimRunner(params(snapshot_dir=str(tmp_path), snapshot_size=[64, 48]), use_sim_time=True)

    def fails(*_args):
        raise RuntimeError('the renderer process died')
    try:
        r.snapshots.take = fails
        with pytest.raises(RuntimeError):
            r.snapshot()
        assert os.listdir(str(tmp_path)) == []
    finally:
        r.close()


@pytest.mark.parametrize('values, message', [
    ({'altitude_min': 2000.0, 'altitude_max': 1000.0}, '~altitude_min 2000 mm must be below'),
    ({'base_frame': 'odom'}, "~base_frame and ~odom_frame are both 'odom'"),
    ({'world_frame': 'odom'}, "~world_frame 'odom' is the drone's own frame"),
    ({'world_frame': 'uav/odom', 'tf_prefix': 'uav'}, "~world_frame 'uav/odom' is the drone's"),
    # published at 100 Hz and 200 Hz
    ({'looprate': 80.0, 'physics_rate': 200.0}, r'~looprate 80 Hz must be ~physics_rate 200 Hz'),
    ({'looprate': 1000.0, 'physics_rate': 200.0}, r'~looprate 1000 Hz must be'),
    # a takeoff ending below the floor kept in flight, or at once on the ground
    ({'takeoff_altitude': 0.08}, r'~takeoff_altitude 0.08 m: allowed 0.1 \.\. 10 m with '
                                 r'~altitude_min 50 mm'),
    ({'takeoff_altitude': 0.3, 'altitude_min': 300.0}, r'~takeoff_altitude 0.3 m: allowed 0.35'),
    ({'altitude_max': 80.0}, r'~altitude_max 80 mm: a takeoff levels off at the ceiling, which '
                             r'must be at least 100 mm'),
])
def test_parameters_that_cannot_go_together_are_refused(values, message):
    # each was taken: an empty flight band, a transform from a frame to itself
    with pytest.raises(ValueError, match=message):
        check_combinations(params(**values))


def test_parameters_that_go_together_are_taken():
    check_combinations(params())
    # the sim levels off at the ceiling; drones behind prefixes share one world frame
    check_combinations(params(takeoff_altitude=1.0, altitude_max=800.0))
    check_combinations(params(world_frame='odom', tf_prefix='drone1'))
    check_combinations(params(looprate=200.0 / 3.0, physics_rate=200.0))
    check_combinations(params(looprate=5.0, physics_rate=2000.0))
    check_combinations(params(takeoff_altitude=0.12, altitude_min=70.0))   # just: 0.07 + 0.05
    check_combinations(params(takeoff_altitude=0.05, altitude_min=0.0, altitude_max=50.0))


def test_a_takeoff_altitude_at_the_floor_is_refused_alone():
    # 0.03 m ended the takeoff at once: 'hovering' on the floor, motors at hover thrust
    with pytest.raises(ValueError, match=r'~takeoff_altitude = 0\.03: .*>= 0\.05'):
        params(takeoff_altitude=0.03)
