"""The simulated drone as the ardrone_sim node runs it, without ROS: its ~parameters, the
lock around the physics, stepping at ~looprate paced to the wall clock, the cameras and
snapshots drawn from a copied pose, the TF frame names, and what navdata reports beyond
the flight state (magnetometer, pressure, temperature)."""
import math
import threading
from dataclasses import dataclass

import pybullet as pb

from leap_teleop.drone import cameras
from leap_teleop.drone.sim import (
    CAMERA_FRONT,
    STATE_NAMES,
    TAKEOFF_ABOVE_FLOOR,
    ArDroneSim,
    DroneParams,
    animation_duration_error,
)
from leap_teleop.params import Param
from leap_teleop.sim_runtime import (
    MAX_LAG_S,
    RealtimePacer,
    SendGate,
    pace_factor,
    release_snapshot_path,
    snapshot_path,
)

_D = DroneParams()
# Default camera rates: what 2 shared cores render (in the camera process) while the
# flight keeps real time; measured by bench_drone's sim.drone_rtf_cameras.
FRONT_RATE, BOTTOM_RATE = 5.0, 5.0
# A snapshot fails after this long (the first one also starts its renderer process and
# builds the scene there).
SNAPSHOT_TIMEOUT = 30.0
RUNNER_PARAMS = {
    'euler_angle_max': Param(_D.euler_angle_max, 'max tilt for linear.x/y = 1 (driver)',
                             unit='rad', gt=0.0, le=0.52),
    'control_vz_max': Param(_D.control_vz_max, 'climb rate for linear.z = 1 (driver)',
                            unit='mm/s', gt=0.0, le=2000.0),
    'control_yaw': Param(_D.control_yaw, 'yaw rate for angular.z = 1 (driver)',
                         unit='rad/s', gt=0.0, le=6.11),
    'altitude_max': Param(_D.altitude_max, 'altitude ceiling (driver)', unit='mm',
                          gt=0.0, le=100000.0),
    'altitude_min': Param(_D.altitude_min, 'altitude floor while flying (driver)',
                          unit='mm', ge=0.0, le=100000.0),
    'looprate': Param(50.0, 'navdata / imu / odometry / TF rate (driver)', unit='Hz',
                      ge=5.0, le=1000.0),
    'takeoff_altitude': Param(_D.takeoff_altitude, 'where a takeoff levels off (at least '
                                                   '~altitude_min + %g m)' % TAKEOFF_ABOVE_FLOOR,
                              unit='m', ge=TAKEOFF_ABOVE_FLOOR, le=10.0),
    'physics_rate': Param(_D.physics_rate, 'physics and onboard controller rate', unit='Hz',
                          ge=50.0, le=2000.0),
    'battery_flight_time': Param(_D.battery_flight_time, 'hover time on a full battery',
                                 unit='s', gt=0.0, le=100000.0),
    'link_timeout': Param(_D.link_timeout, 'no command this long -> land (firmware link '
                                           'loss; time taking off or flipping does not '
                                           'count; a pilot hovering without sending, as '
                                           'drone_pilot does with the hand lost or in paper '
                                           'mode, is taken for a lost link); 0 = off, as with '
                                           'a live driver', unit='s', ge=0.0, le=60.0),
    'gui': Param(False, 'open the PyBullet GUI window'),
    'realtime_factor': Param(1.0, 'sim speed vs wall time; 0 = as fast as possible (other '
                                  'than 1 only with /use_sim_time)', ge=0.0, le=100.0),
    'snapshot_dir': Param('', 'where ardrone/snapshot writes PNGs (default ROS_HOME or /tmp)'),
    'snapshot_size': Param([640, 480], 'snapshot width, height', unit='px', length=2,
                           ge=16, le=4096),
    'base_frame': Param('ardrone_base_link', 'drone body frame', empty_ok=False),
    'odom_frame': Param('odom', 'odometry frame', empty_ok=False),
    'start_xy': Param([0.0, 0.0], 'start position in odom', unit='m', length=2,
                      ge=-1000.0, le=1000.0),
    # Each publish serialises the whole path on the physics loop: 3 ms per 2000 poses.
    'path_length': Param(2000, 'poses kept in ardrone/path (oldest dropped)', ge=2,
                         le=10000),
    'path_min_step': Param(0.02, 'moved this far before the path gets a new pose', unit='m',
                           ge=0.0, le=100.0),
    'path_rate': Param(5.0, 'ardrone/path publish rate (only when it changed); 0 = off',
                       unit='Hz', ge=0.0, le=100.0),
    'markers': Param(True, 'publish the drone body markers on ardrone/markers (latched)'),
    'world_frame': Param('', 'if set, publish a static TF world_frame -> odom_frame '
                             '(so RViz can show the hands next to the drone)'),
    'odom_in_world': Param([1.0, 0.0, 0.0], 'odom_frame origin in world_frame', unit='m',
                           length=3, ge=-1000.0, le=1000.0),
    # Cameras and the driver's options.
    'front_rate': Param(FRONT_RATE, 'ardrone/front/image_raw rate (wall clock); 0 = off',
                        unit='Hz', ge=0.0, le=30.0),
    'bottom_rate': Param(BOTTOM_RATE, 'ardrone/bottom/image_raw rate (wall clock); 0 = off',
                         unit='Hz', ge=0.0, le=30.0),
    'camera_channel': Param(0, 'camera on ardrone/image_raw at start: 0 front, 1 bottom',
                            choices=(0, 1)),
    'enable_navdata_altitude': Param(False, 'publish ardrone/navdata_altitude (driver option)'),
    'tf_prefix': Param('', 'prefix of every TF frame published (driver param), e.g. drone1'),
}
# The ~params that are the simulated firmware's own (DroneParams fields).
SIM_KEYS = ('euler_angle_max', 'control_vz_max', 'control_yaw', 'altitude_max',
            'altitude_min', 'takeoff_altitude', 'physics_rate', 'battery_flight_time',
            'link_timeout')
# Optical frames (z along the view, x right, y down in the image) as roll, pitch, yaw in
# the body frame, mounted where cameras.FRONT / cameras.BOTTOM render from.
OPTICAL_RPY = {'front': (-math.pi / 2, 0.0, -math.pi / 2),
               'bottom': (math.pi, 0.0, -math.pi / 2)}


class DroneFrames:
    """The TF frame names, each behind ~tf_prefix as with the driver (so drones side by
    side keep their frames apart)."""

    def __init__(self, tf_prefix, base, odom):
        self.prefix = tf_prefix.strip('/')
        self.base, self.odom = self.name(base), self.name(odom)
        self.cameras = {'front': self.name('ardrone_base_frontcam'),
                        'bottom': self.name('ardrone_base_bottomcam')}

    def name(self, frame):
        return '%s/%s' % (self.prefix, frame) if self.prefix else frame


def static_frames(frames, world_frame='', odom_in_world=(0.0, 0.0, 0.0)):
    """[(parent, child, xyz, quat xyzw)] that never move: world -> odom when world_frame is
    set (the odom name is prefixed, the world's is shared), body -> each camera."""
    out = []
    if world_frame:
        out.append((world_frame, frames.odom, tuple(float(v) for v in odom_in_world),
                    (0.0, 0.0, 0.0, 1.0)))
    for name, spec in cameras.CAMERAS.items():
        out.append((frames.base, frames.cameras[name], tuple(spec.mount),
                    tuple(pb.getQuaternionFromEuler(OPTICAL_RPY[name]))))
    return out


def sensor_readings(nav, altitude):
    """Navdata's sensor fields the flight model does not produce: the earth's field turned
    by the heading, the barometer at `altitude` (m) and a room temperature."""
    yaw = math.radians(nav['rotZ'])
    return {'magX': int(200 * math.cos(yaw)), 'magY': int(-200 * math.sin(yaw)),
            'magZ': -400, 'pressure': int(101325 - 12.0 * altitude), 'temp': 25}


# Distortion vector lengths a consumer can rectify with (OpenCV's: 4, 5, 8, 12, 14; none
# = no distortion), and those of the models ROS names (sensor_msgs/distortion_models.h).
DISTORTION_LENGTHS = (0, 4, 5, 8, 12, 14)
ROS_DISTORTION_MODELS = {'plumb_bob': 5, 'rational_polynomial': 8, 'equidistant': 4}


def calibration_error(name, width, height, K=None, D=(), R=None, P=None, model=''):
    """'' when a calibration of width x height fits camera `name`, else why not (like
    camera_info_manager, any calibration of the camera's size is taken, if its numbers are
    finite, its focal lengths positive and its distortion one of a known model's length:
    DISTORTION_LENGTHS, or for a model ROS names, that model's, or none)."""
    spec = cameras.CAMERAS[name]
    if (width, height) != (spec.width, spec.height):
        return '%s camera is %dx%d, got %dx%d' % (name, spec.width, spec.height, width, height)
    for field, values, n in (('K', K, 9), ('R', R, 9), ('P', P, 12)):
        if values is not None and (len(values) != n
                                   or not all(math.isfinite(v) for v in values)):
            return '%s must be %d finite numbers' % (field, n)
    if K is not None and not (K[0] > 0 and K[4] > 0):
        return 'K: the focal lengths fx, fy must be > 0'
    if len(D) > 14:
        return 'D must be at most 14 numbers, got %d' % len(D)
    if not all(math.isfinite(v) for v in D):
        return 'D must be finite numbers'
    wanted = ROS_DISTORTION_MODELS.get(model)
    if wanted is not None and len(D) not in (0, wanted):
        return 'D has %d numbers: %s takes %d (or none)' % (len(D), model, wanted)
    if len(D) not in DISTORTION_LENGTHS:
        return 'D has %d numbers: a distortion model takes %s' % (
            len(D), ', '.join(map(str, DISTORTION_LENGTHS)))
    if len(model) > 64:
        return 'distortion_model is %d characters: no model is named so' % len(model)
    return ''


@dataclass
class DroneReading:
    """One consistent copy of the drone's state, taken under the lock."""
    time: float
    nav: dict               # navdata fields: the sim's plus sensor_readings
    pos: tuple
    quat: tuple             # x, y, z, w
    omega: tuple
    altitude: float
    new_state: str          # the state's name when it changed since the last reading, else ''


def check_combinations(p):
    """ValueError for ~params each allowed alone but not together. (A takeoff above the
    ceiling is no error: the sim levels off at the ceiling.)"""
    steps = p['physics_rate'] / p['looprate']
    if steps < 1.0 - 1e-9 or abs(steps - round(steps)) > 1e-6 * steps:
        # each tick runs whole physics steps: any other rate would be rounded to one
        raise ValueError('~looprate %g Hz must be ~physics_rate %g Hz divided by a whole '
                         'number (%s Hz, ...)' % (p['looprate'], p['physics_rate'], ', '.join(
                             '%g' % (p['physics_rate'] / n) for n in range(1, 5))))
    if p['altitude_min'] >= p['altitude_max']:
        raise ValueError('~altitude_min %g mm must be below ~altitude_max %g mm'
                         % (p['altitude_min'], p['altitude_max']))
    # A takeoff ends just below its level, which must be above the floor kept in flight.
    lowest = p['altitude_min'] / 1000.0 + TAKEOFF_ABOVE_FLOOR
    if p['takeoff_altitude'] < lowest - 1e-9:           # 0.07 + 0.05 > 0.12 in floats
        raise ValueError('~takeoff_altitude %g m: allowed %g .. %g m with ~altitude_min %g mm '
                         '(at least %g m above it)' % (
                             p['takeoff_altitude'], lowest, RUNNER_PARAMS['takeoff_altitude'].le,
                             p['altitude_min'], TAKEOFF_ABOVE_FLOOR))
    if p['altitude_max'] / 1000.0 < lowest - 1e-9:
        raise ValueError('~altitude_max %g mm: a takeoff levels off at the ceiling, which must '
                         'be at least %g mm with ~altitude_min %g mm'
                         % (p['altitude_max'], lowest * 1000.0, p['altitude_min']))
    frames = DroneFrames(p['tf_prefix'], p['base_frame'], p['odom_frame'])
    if frames.base == frames.odom:
        raise ValueError('~base_frame and ~odom_frame are both %r: odometry needs two frames'
                         % frames.odom)
    if p['world_frame'] and p['world_frame'].lstrip('/') in (frames.odom.lstrip('/'),
                                                             frames.base.lstrip('/')):
        raise ValueError('~world_frame %r is the drone\'s own frame: a transform needs two'
                         % p['world_frame'])


class DroneSimRunner:
    """ArDroneSim behind one lock (service threads, the camera thread and the loop share
    it), stepped in blocks of physics steps per ~looprate tick."""

    def __init__(self, p, use_sim_time, warn=None):
        check_combinations(p)
        self.p = p
        self.sim = ArDroneSim({k: p[k] for k in SIM_KEYS}, gui=bool(p['gui']), warn=warn,
                              start_xyz=tuple(p['start_xy']))
        self.lock = threading.Lock()
        self.sim.set_camera_channel(int(p['camera_channel']))
        self.frames = DroneFrames(p['tf_prefix'], p['base_frame'], p['odom_frame'])
        self.snapshots = cameras.ChaseSnapshots(SNAPSHOT_TIMEOUT)
        self.cameras = None
        self.path_gate = SendGate(1.0 / p['path_rate'] if p['path_rate'] > 0 else None)
        self.steps = max(1, int(round(self.sim.p.physics_rate / float(p['looprate']))))
        self.use_sim_time = use_sim_time
        self.factor, self.pace_warning = pace_factor(float(p['realtime_factor']),
                                                     use_sim_time)
        self._last_state = None

    def call(self, fn, *args):
        """fn(*args) under the lock (a command from a callback)."""
        with self.lock:
            return fn(*args)

    def read(self):
        with self.lock:
            s = self.sim
            nav, alt = s.navdata(), s.altitude
            reading = DroneReading(s.time, dict(nav, **sensor_readings(nav, alt)), s.pos,
                                   s.quat, s.omega, alt, '')
        if nav['state'] != self._last_state:
            reading.new_state = STATE_NAMES[nav['state']]
            self._last_state = nav['state']
        return reading

    # The driver's commands (services): the simulated firmware logs why it ignores one;
    # each returns a line for the node's log ('' when there is nothing to say), or False:
    # a request refused, to be answered false.
    def flight_animation(self, kind, duration):
        why = animation_duration_error(duration)
        if why:     # steering would wait it out: refused, not passed on as the driver would
            self.call(self.sim.warn, 'anim_duration', 'flight animation refused: %s', why)
            return False
        self.call(self.sim.flight_animation, kind, duration)
        return ''

    def flat_trim(self):
        return 'flat trim done' if self.call(self.sim.flat_trim) else ''

    def toggle_camera(self):
        self.call(self.sim.toggle_camera)
        return 'video channel %d' % self.sim.camera_channel

    def set_camera_channel(self, channel):
        self.call(self.sim.set_camera_channel, channel)
        return 'video channel %d' % self.sim.camera_channel

    def set_led_animation(self, kind, freq, duration):
        if not self.call(self.sim.set_led_animation, kind, freq, duration):
            return ''
        return 'LED animation %s at %.1f Hz for %d s' % (self.sim.led_animation[0], freq,
                                                         duration)

    def set_record(self, enable):
        self.call(self.sim.set_record, enable)
        return 'video recording %s' % ('on' if enable else 'off')

    def run(self, publish, stopped):
        """Step, then publish(), until stopped(); paced to ~realtime_factor."""
        pacer = RealtimePacer(self.factor, self.sim.time, MAX_LAG_S[bool(self.use_sim_time)])
        while not stopped():
            with self.lock:
                for _ in range(self.steps):
                    self.sim.step()
            publish()
            pacer.wait(self.sim.time)

    def start_cameras(self, deliver, on_error, stamp):
        """Render the cameras at their ~rates in a thread of their own: deliver(name, rgb,
        stamp, active) gets each image with stamp(sim time) of the pose it shows, taken
        with the pose under the lock; active = it is the video channel's camera."""
        def pose():
            with self.lock:
                active = 'front' if self.sim.camera_channel == CAMERA_FRONT else 'bottom'
                return self.sim.pos, self.sim.quat, (stamp(self.sim.time), active)

        self.cameras = cameras.CameraLoop(
            {'front': float(self.p['front_rate']), 'bottom': float(self.p['bottom_rate'])},
            pose, lambda name, rgb, ctx: deliver(name, rgb, ctx[0], name == ctx[1]), on_error)
        self.cameras.start()

    def snapshot(self):
        """The path of a chase-view PNG of the drone now. Only the pose is copied under the
        lock: the picture is drawn in another process. OSError, ValueError or RuntimeError
        when it cannot be taken."""
        w, h = (int(v) for v in self.p['snapshot_size'])
        with self.lock:
            t, pos, quat = self.sim.time, self.sim.pos, self.sim.quat
        path = snapshot_path(self.p['snapshot_dir'], 'ardrone', t)
        try:
            self.snapshots.take(pos, quat, path, w, h, self.sim.p.arm)
        except BaseException:
            release_snapshot_path(path)          # no empty file for a failed picture
            raise
        return path

    def close(self):
        if self.cameras is not None:
            self.cameras.stop()
        self.snapshots.close()
        self.sim.close()
