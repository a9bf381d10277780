"""AR.Drone 2.0 in PyBullet, flown the way ardrone_autonomy flies the real one.

A rigid body with the indoor-hull mass and inertia receives, each physics step, the
thrust and torques of four motors (X layout, thrust clamped to [0, max]) computed by an
emulated onboard controller:

- cmd_vel (as the driver receives it, every component clamped to [-1, 1]; a warning says
  so when linear.x / y / z or angular.z was beyond it):
  linear.x / linear.y = pitch / roll set points as fractions of ``euler_angle_max``
  (+x forward, +y left), linear.z = climb rate fraction of ``control_vz_max``,
  angular.z = yaw rate fraction of ``control_yaw`` (+ = left, counter-clockwise).
  All six ~0 = auto-hover: brake, then hold the position and altitude reached;
  angular.x or angular.y non-zero = no auto-hover (zero tilt, no position hold).
  Like the driver, the last command is held until a new one arrives.
- states (Navdata codes): 2 landed -> 6 taking off (climbs to ``takeoff_altitude``) ->
  4 hovering / 3 flying -> 8 landing -> 2; 9 looping during flips; 0 emergency (reset
  toggles it, motors off). Commands that make no sense in a state are ignored with a
  warning.
- flight animations: 16..19 are real flips (kick up, spin 360 degrees about the body
  axis with the thrust cut, catch, climb back, hover). 0..15 are approximated by set-
  point sequences (tilts, yaw turns, dances) over the SDK's default durations. Types
  > 19 are refused. A flip's ``duration`` is ignored (the SDK's 15 ms is not the spin
  time either); ardrone_sim refuses durations beyond MAX_ANIMATION_MS (its runner).
- the driver's other commands: flat trim (on the ground only), LED animations 0..13,
  video recording on / off and the video channel (front / bottom camera).
- altitude limits (``altitude_min`` .. ``altitude_max`` while flying), a battery that
  drains with thrust-weighted flight time (lands at 0, refuses takeoff below
  ``battery_takeoff_min``), and an optional link-loss landing (``link_timeout``, off by
  default: the real driver re-sends the last command continuously, so the firmware's
  2 s no-input landing only happens when the driver or its WiFi is gone; time taking off
  or flipping does not count, as no pilot steers then). Here driver and firmware are one
  process: all the simulator sees is the pilot's commands, and a pilot that hovers sends
  none (drone_pilot with the hand lost, until its land_after; in paper mode after a hover;
  in tilt mode once disengaged). That silence cannot be told from a dead pilot's, so with
  ``link_timeout`` shorter than it those hovers land too: keep it 0 with drone_pilot.

World frame: x forward and y left of the start pose, z up (the driver's ``odom``).
Navdata follows the driver's conversions: rotX/rotY/rotZ ROS roll/pitch/yaw in degrees,
vx/vy/vz body-frame mm/s, altd mm, ax/ay/az specific force in g (az = +1 at rest).
"""
import collections
import logging
import math
import numbers
from dataclasses import dataclass, fields

import pybullet as pb

from leap_teleop.drone import scene
from leap_teleop.vectors import rpy_matrix, wrap_angle

log = logging.getLogger(__name__)

G = 9.81
UNKNOWN, INIT, LANDED, FLYING, HOVERING, TEST, TAKING_OFF, GOTO_FIX, LANDING, LOOPING = range(10)
UPRIGHT_COS = math.cos(math.radians(30.0))   # a takeoff needs the body z this near vertical
STATE_NAMES = {0: 'unknown/emergency', 1: 'init', 2: 'landed', 3: 'flying', 4: 'hovering',
               5: 'test', 6: 'taking off', 7: 'goto fix point', 8: 'landing', 9: 'looping'}
FLIP_AHEAD, FLIP_BEHIND, FLIP_LEFT, FLIP_RIGHT = 16, 17, 18, 19
ANIMATION_NAMES = (
    'PHI_M30_DEG', 'PHI_30_DEG', 'THETA_M30_DEG', 'THETA_30_DEG', 'THETA_20DEG_YAW_200DEG',
    'THETA_20DEG_YAW_M200DEG', 'TURNAROUND', 'TURNAROUND_GODOWN', 'YAW_SHAKE', 'YAW_DANCE',
    'PHI_DANCE', 'THETA_DANCE', 'VZ_DANCE', 'WAVE', 'PHI_THETA_MIXED',
    'DOUBLE_PHI_THETA_MIXED', 'FLIP_AHEAD', 'FLIP_BEHIND', 'FLIP_LEFT', 'FLIP_RIGHT')
# The SDK's default animation durations (ms); flips use their own dynamics.
DEFAULT_DURATION_MS = (1000, 1000, 1000, 1000, 1000, 1000, 5000, 5000, 2000, 5000,
                       5000, 5000, 5000, 5000, 5000, 5000, 15, 15, 15, 15)
# Flip: (body axis index, sign of rotation about it). Ahead = nose down = +pitch.
FLIP_AXES = {FLIP_AHEAD: (1, 1.0), FLIP_BEHIND: (1, -1.0), FLIP_LEFT: (0, -1.0),
             FLIP_RIGHT: (0, 1.0)}
HOVER_EPS = 1e-4        # a command component below this counts as zero
# A flip not caught this long after it began (1.8 s from any height above 0.45 m; one
# asked too low strikes the floor and ends upside down) cuts the motors: the firmware's
# emergency, which ardrone/reset clears.
FLIP_CUTOFF_S = 3.0
# Longest flight animation ardrone_sim takes, ms: twice the SDK's longest default (5 s), the
# pilot's own flip_duration bound; steering waits out an animation: longer is a lockout.
MAX_ANIMATION_MS = 10000
# cmd_vel beyond [-1, 1] by more than this is clamped with a warning (rounding is not).
CMD_RANGE_TOLERANCE = 0.01
EVENTS_KEPT = 1000      # state changes remembered in ArDroneSim.events (oldest dropped)
# The firmware's LED animations (ardrone/setledanimation types 0..13).
LED_ANIMATION_NAMES = (
    'BLINK_GREEN_RED', 'BLINK_GREEN', 'BLINK_RED', 'BLINK_ORANGE', 'SNAKE_GREEN_RED', 'FIRE',
    'STANDARD', 'RED', 'GREEN', 'RED_SNAKE', 'BLANK', 'LEFT_GREEN_RIGHT_RED',
    'LEFT_RED_RIGHT_GREEN', 'BLINK_STANDARD')
CAMERA_FRONT, CAMERA_BOTTOM = 0, 1    # AR.Drone 2.0 video channels


# The LEDs blink at a few Hz; far faster is no animation the firmware shows.
MAX_LED_HZ = 100.0
# The longest durations the driver's services carry (FlightAnim's uint32 ms, LedAnim's
# uint8 s): longer ones, only possible through this API, overflowed a float.
MAX_FLIGHT_DURATION_MS, MAX_LED_DURATION_S = 2 ** 32 - 1, 255
# A takeoff ends within TAKEOFF_DONE_WITHIN of its level, and that level (the ceiling when it
# is lower) is at least TAKEOFF_ABOVE_FLOOR above altitude_min: else it ended at once on the
# ground ('hovering' at 1 mm, motors running) or held below the floor kept in flight.
TAKEOFF_DONE_WITHIN = 0.03          # m
TAKEOFF_ABOVE_FLOOR = 0.05          # m
MAX_ADVANCE_S = 3600.0              # one advance() call steps at most this much sim time
MIN_IMAGE_PX, MAX_IMAGE_PX = 16, 4096   # a snapshot's width and height


@dataclass
class DroneParams:
    """Driver / firmware parameters in the driver's units, plus the model's constants."""
    euler_angle_max: float = 0.21        # rad (driver sample launch; firmware indoor 12 deg)
    control_vz_max: float = 700.0        # mm/s
    control_yaw: float = math.radians(100.0)   # rad/s
    altitude_max: float = 3000.0         # mm
    altitude_min: float = 50.0           # mm
    takeoff_altitude: float = 1.0        # m, where a takeoff levels off
    mass: float = 0.42                   # kg, indoor hull
    inertia: tuple = (2.24e-3, 2.99e-3, 4.80e-3)   # kg m^2 (identified values, indoor hull)
    arm: float = 0.18                    # m, centre to motor
    thrust_to_weight: float = 2.2        # all four motors at full throttle / weight
    yaw_moment: float = 0.016            # m, rotor drag torque per newton of thrust
    drag: float = 0.35                   # N per m/s, horizontal (terminal ~2.5 m/s at 12 deg)
    hull: tuple = (0.26, 0.26, 0.06)     # half extents of the collision box, m
    physics_rate: float = 200.0          # Hz, also the onboard controller's rate
    battery_flight_time: float = 720.0   # s of hover on a full battery
    battery_takeoff_min: float = 10.0    # percent
    link_timeout: float = 0.0            # s without any command (a quiet pilot's too) -> land; 0 = off
    flip_rate: float = 20.0              # rad/s spin rate of a flip

    def update(self, values):
        known = {f.name for f in fields(self)}
        for key, value in values.items():
            if key not in known:
                raise ValueError('unknown drone parameter %r' % key)
            setattr(self, key, type(getattr(self, key))(value)
                    if not isinstance(getattr(self, key), tuple) else tuple(value))
        if self.euler_angle_max <= 0 or self.control_vz_max <= 0 or self.control_yaw <= 0:
            raise ValueError('euler_angle_max, control_vz_max and control_yaw must be > 0')
        if not 0 <= self.altitude_min < self.altitude_max:
            raise ValueError('need 0 <= altitude_min < altitude_max (mm)')
        level = min(self.takeoff_altitude, self.altitude_max / 1000.0)
        if not level >= self.altitude_min / 1000.0 + TAKEOFF_ABOVE_FLOOR - 1e-9:
            raise ValueError('takeoff_altitude and altitude_max must be at least altitude_min '
                             '+ %g mm (a takeoff levels off at the lower of the two)'
                             % (TAKEOFF_ABOVE_FLOOR * 1000))
        if self.physics_rate < 50:
            raise ValueError('physics_rate must be >= 50 Hz')
        return self


def _clamp(x, lo, hi):
    return lo if x < lo else hi if x > hi else x


def _finite(x):
    try:
        x = float(x)
    except (TypeError, ValueError, OverflowError):   # an int beyond a float: infinite
        return None
    return x if math.isfinite(x) else None


def _attitude_error(rd, r):
    """Geometric attitude error 0.5 vee(Rd^T R - R^T Rd) (body frame)."""
    # M = Rd^T R; only the off-diagonal terms are needed.
    def m(i, j):
        return rd[i] * r[j] + rd[3 + i] * r[3 + j] + rd[6 + i] * r[6 + j]
    return (0.5 * (m(2, 1) - m(1, 2)), 0.5 * (m(0, 2) - m(2, 0)), 0.5 * (m(1, 0) - m(0, 1)))


class ArDroneSim:
    """One simulated AR.Drone 2.0. Drive it with the command methods and step()/advance().

    Every method returns quickly and never raises on bad input: it warns (through
    ``warn(key, message)``, rate-limited per key) and ignores the command.
    """

    def __init__(self, params=None, gui=False, warn=None, start_xyz=(0.0, 0.0)):
        self.p = DroneParams()
        if isinstance(params, DroneParams):
            self.p = params
        elif params:
            self.p.update(params)
        self.dt = 1.0 / self.p.physics_rate
        self._warn_cb = warn
        self._last_warn = {}
        self.gui = gui
        self.client = pb.connect(pb.GUI if gui else pb.DIRECT)
        c = self.client
        pb.setGravity(0, 0, -G, physicsClientId=c)
        pb.setTimeStep(self.dt, physicsClientId=c)
        pb.setPhysicsEngineParameter(numSolverIterations=10, physicsClientId=c)
        plane = pb.createCollisionShape(pb.GEOM_PLANE, physicsClientId=c)
        self.ground = pb.createMultiBody(0, plane, -1, physicsClientId=c)
        # A collision shape without a visual is drawn (checkered) by the renderer: hide it.
        pb.changeVisualShape(self.ground, -1, rgbaColor=(0, 0, 0, 0), physicsClientId=c)
        self._scene = None      # the pictures' scene, built on the first picture: its
                                # bodies would slow every physics step by about a third
        self._make_body(start_xyz)
        self._z_rest = self.p.hull[2]
        self.reset_state()

    # -- construction ---------------------------------------------------------------
    def _make_body(self, start_xyz):
        c, p = self.client, self.p
        col = pb.createCollisionShape(pb.GEOM_BOX, halfExtents=p.hull, physicsClientId=c)
        hz = p.hull[2]
        vis = scene.body_visual(c, p.arm)
        self.body = pb.createMultiBody(p.mass, col, vis, (start_xyz[0], start_xyz[1], hz),
                                       physicsClientId=c)
        pb.changeDynamics(self.body, -1, localInertiaDiagonal=p.inertia, linearDamping=0.0,
                          angularDamping=0.0, lateralFriction=0.8, physicsClientId=c)
        self._start_xyz = (start_xyz[0], start_xyz[1], hz)

    def close(self):
        if self.client is not None:
            pb.disconnect(self.client)
            self.client = None

    def __del__(self):
        try:
            self.close()
        except Exception:
            pass

    def reset_state(self):
        """Back on the ground at the start pose, landed, full battery."""
        pb.resetBasePositionAndOrientation(self.body, self._start_xyz, (0, 0, 0, 1),
                                           physicsClientId=self.client)
        pb.resetBaseVelocity(self.body, (0, 0, 0), (0, 0, 0), physicsClientId=self.client)
        self.time = 0.0
        self.state = LANDED
        self.emergency = False
        self.battery = 100.0
        self.cmd = (0.0,) * 6
        self.last_input_time = 0.0
        self.motors = (0.0,) * 4          # thrust per motor, N
        self._alt_hold = None
        self._pos_hold = None
        self._yaw_d = 0.0
        self._anim = None                 # dict describing a running animation
        self._land_after_flip = False     # a land came during a flip
        self._acc_world = (0.0, 0.0, 0.0)
        self._prev_vel = (0.0, 0.0, 0.0)
        self.flip_count = 0
        self.last_flip_angle = 0.0        # rad turned by the last finished flip
        self.last_flip_min_altitude = None  # m, lowest point of the last finished flip
        # (time, state) at every state change, the latest EVENTS_KEPT of them.
        self.events = collections.deque(maxlen=EVENTS_KEPT)
        self.camera_channel = CAMERA_FRONT   # which camera the video stream carries
        self.recording = False            # ardrone/setrecord (video onto the USB stick)
        self.led_animation = None         # (name, freq Hz, ends at sim time s) or None
        self.flat_trims = 0               # flat trims done (landed only)
        self._read()

    # -- warnings -------------------------------------------------------------------
    def warn(self, key, msg, *args):
        """A command refused by the sim's owner, warned about as the sim's own are."""
        self._warn(key, msg, *args)

    def _warn(self, key, msg, *args):
        last = self._last_warn.get(key)
        if last is not None and 0 <= self.time - last < 2.0:
            return
        self._last_warn[key] = self.time
        text = msg % args if args else msg
        if self._warn_cb is not None:
            self._warn_cb(key, text)
        else:
            log.warning(text)

    def _set_state(self, state):
        if state != LOOPING:               # a land asked during a flip goes with the flip
            self._land_after_flip = False
        if state != self.state:
            self.state = state
            self.events.append((self.time, state))

    # -- commands (the driver's topics and service) -----------------------------------
    @property
    def airborne(self):
        return self.state in (FLYING, HOVERING, LOOPING, TAKING_OFF, LANDING, GOTO_FIX)

    def takeoff(self):
        self.last_input_time = self.time
        if self.emergency:
            self._warn('takeoff', 'takeoff ignored: emergency state (send reset first)')
            return False
        if self.state != LANDED:
            self._warn('takeoff', 'takeoff ignored: drone is %s', STATE_NAMES[self.state])
            return False
        if self.battery < self.p.battery_takeoff_min:
            self._warn('takeoff', 'takeoff refused: battery %.0f%% < %.0f%%',
                       self.battery, self.p.battery_takeoff_min)
            return False
        if self.R[8] < UPRIGHT_COS:
            # Thrust along a body axis pointing sideways or down lifts nothing: it stayed
            # 'taking off' for ever, motors running.
            self._warn('takeoff', 'takeoff refused: the drone is not upright (tilted %.0f deg)',
                       math.degrees(math.acos(_clamp(self.R[8], -1.0, 1.0))))
            return False
        self._yaw_d = self.yaw
        self._alt_hold = None
        self._pos_hold = None
        self._set_state(TAKING_OFF)
        return True

    def land(self):
        self.last_input_time = self.time
        if self.state == LOOPING and not self.emergency:
            # Cut short upside down it fell at 4-8 m/s: it lands once the flip has caught.
            self._land_after_flip = True
            return True
        if self.state in (FLYING, HOVERING, TAKING_OFF, GOTO_FIX) and not self.emergency:
            self._anim = None
            self._set_state(LANDING)
            return True
        self._warn('land', 'land ignored: drone is %s', STATE_NAMES[self.state])
        return False

    def reset(self):
        """Toggle the emergency state (motors off while in it)."""
        self.last_input_time = self.time
        self.emergency = not self.emergency
        self._anim = None
        if self.emergency or not self._at_rest_on_ground():
            # Left while still falling, it stays unknown until it is down: 'landed' at
            # 968 mm was believed, and took off in the air.
            self._set_state(UNKNOWN)
        else:
            self._set_state(LANDED)
        return True

    def _at_rest_on_ground(self):
        return self.altitude < 0.03 and abs(self.vel[2]) < 0.05

    def set_cmd_vel(self, lx=0.0, ly=0.0, lz=0.0, ax=0.0, ay=0.0, az=0.0):
        """The driver's cmd_vel: each component clamped to [-1, 1]; NaN rejects the command."""
        values = [_finite(v) for v in (lx, ly, lz, ax, ay, az)]
        if any(v is None for v in values):
            self._warn('cmd_vel', 'cmd_vel ignored: non-finite component in %r',
                       (lx, ly, lz, ax, ay, az))
            return False
        self.last_input_time = self.time
        # angular.x / y only switch the auto-hover off (any size): no warning for them
        if any(abs(values[i]) > 1.0 + CMD_RANGE_TOLERANCE for i in (0, 1, 2, 5)):
            self._warn('cmd_vel_range', 'cmd_vel %r: a component beyond [-1, 1], clamped '
                       '(as the driver does)', (lx, ly, lz, ax, ay, az))
        self.cmd = tuple(_clamp(v, -1.0, 1.0) for v in values)
        if self.state in (LANDED, UNKNOWN) and any(abs(v) > HOVER_EPS for v in self.cmd):
            self._warn('cmd_vel_landed', 'cmd_vel held: drone is %s (flown after takeoff, as '
                       'the driver keeps the last one)', STATE_NAMES[self.state])
        return True

    @property
    def auto_hover(self):
        return all(abs(v) <= HOVER_EPS for v in self.cmd)

    def flight_animation(self, anim_type, duration_ms=0):
        """ardrone/setflightanimation. True when the animation starts (the driver answers
        true whatever this returns: the firmware ignores what it cannot do)."""
        self.last_input_time = self.time
        try:
            anim_type = int(anim_type)
            duration_ms = int(duration_ms)
        except (TypeError, ValueError, OverflowError):
            self._warn('anim', 'flight animation refused: bad type %r or duration %r',
                       anim_type, duration_ms)
            return False
        if duration_ms > MAX_FLIGHT_DURATION_MS:
            self._warn('anim', 'flight animation refused: a duration beyond %d ms',
                       MAX_FLIGHT_DURATION_MS)
            return False
        if not 0 <= anim_type < len(ANIMATION_NAMES):
            self._warn('anim', 'flight animation refused: type %d is not in 0..19', anim_type)
            return False
        if self.state not in (FLYING, HOVERING) or self.emergency:
            self._warn('anim', 'flight animation %s ignored: drone is %s',
                       ANIMATION_NAMES[anim_type], STATE_NAMES[self.state])
            return False
        duration = (duration_ms if duration_ms > 0 else DEFAULT_DURATION_MS[anim_type]) / 1000.0
        self._anim = {'type': anim_type, 't0': self.time, 'duration': duration,
                      'alt0': self.altitude, 'phase': 'kick', 'angle': 0.0,
                      'yaw0': self._yaw_d}
        if anim_type in FLIP_AXES:
            self._set_state(LOOPING)
        self._pos_hold = None
        return True

    def flat_trim(self):
        """ardrone/flattrim: re-level the attitude reference; the firmware only does it
        on the ground. True when done."""
        self.last_input_time = self.time
        if self.state != LANDED or self.emergency:
            self._warn('flattrim', 'flat trim ignored: drone is %s', STATE_NAMES[self.state])
            return False
        self.flat_trims += 1
        return True

    def set_led_animation(self, anim_type, freq, duration_s):
        """ardrone/setledanimation. True when the type is one of the firmware's 0..13, the
        frequency a positive number of Hz (up to MAX_LED_HZ) and the duration at most
        MAX_LED_DURATION_S."""
        try:
            anim_type, freq, duration_s = int(anim_type), float(freq), int(duration_s)
        except (TypeError, ValueError, OverflowError):
            self._warn('led', 'LED animation ignored: type %r, frequency %r, duration %r are '
                       'not an integer, a number and an integer', anim_type, freq, duration_s)
            return False
        if not 0 <= anim_type < len(LED_ANIMATION_NAMES):
            self._warn('led', 'LED animation ignored: type %r is not in 0..13', anim_type)
            return False
        if not 0.0 < freq <= MAX_LED_HZ:                  # NaN fails too
            self._warn('led', 'LED animation ignored: frequency %r Hz is not in (0, %g]',
                       freq, MAX_LED_HZ)
            return False
        if duration_s > MAX_LED_DURATION_S:
            self._warn('led', 'LED animation ignored: a duration beyond %d s', MAX_LED_DURATION_S)
            return False
        self.led_animation = (LED_ANIMATION_NAMES[anim_type], freq, self.time + max(0, duration_s))
        return True

    def set_record(self, enable):
        """ardrone/setrecord: start / stop recording video onto the USB stick."""
        self.recording = bool(enable)
        return True

    def set_camera_channel(self, channel):
        """ardrone/setcamchannel: the AR.Drone 2.0 has two channels; like the driver, the
        channel is taken modulo 2."""
        try:
            self.camera_channel = int(channel) % 2
        except (TypeError, ValueError, OverflowError):     # OverflowError: inf
            self._warn('camera', 'camera channel ignored: %r', channel)
            return False
        return True

    def toggle_camera(self):
        """ardrone/togglecam: front <-> bottom."""
        self.camera_channel = 1 - self.camera_channel
        return True

    @property
    def led_active(self):
        return self.led_animation is not None and self.time < self.led_animation[2]

    # -- state ----------------------------------------------------------------------
    def _read(self):
        c = self.client
        pos, quat = pb.getBasePositionAndOrientation(self.body, physicsClientId=c)
        vel, omega = pb.getBaseVelocity(self.body, physicsClientId=c)
        self.pos, self.quat, self.vel, self.omega_world = pos, quat, vel, omega
        self.R = pb.getMatrixFromQuaternion(quat, physicsClientId=c)
        R = self.R
        # Body rates: R^T omega.
        self.omega = (R[0] * omega[0] + R[3] * omega[1] + R[6] * omega[2],
                      R[1] * omega[0] + R[4] * omega[1] + R[7] * omega[2],
                      R[2] * omega[0] + R[5] * omega[1] + R[8] * omega[2])
        self.roll = math.atan2(R[7], R[8])
        self.pitch = math.asin(_clamp(-R[6], -1.0, 1.0))
        self.yaw = math.atan2(R[3], R[0])
        self.altitude = pos[2] - self._z_rest if hasattr(self, '_z_rest') else 0.0

    # -- stepping -------------------------------------------------------------------
    def advance(self, seconds):
        """Run the simulation for `seconds` of simulated time (at most MAX_ADVANCE_S a call)."""
        t = _finite(seconds)
        if t is None or isinstance(seconds, bool) or not 0.0 <= t <= MAX_ADVANCE_S:
            self._warn('advance', 'advance(%r) ignored: a number of seconds from 0 to %g',
                       seconds, MAX_ADVANCE_S)
            return
        for _ in range(int(round(t / self.dt))):
            self.step()

    def step(self):
        p = self.p
        self._read()
        self._update_mode()
        if self.state in (LANDED, UNKNOWN) or self.emergency:
            thrust, torque = 0.0, (0.0, 0.0, 0.0)
        else:
            thrust, torque = self._control()
        thrust, torque = self._mix(thrust, torque)
        R = self.R
        # Thrust along body z, horizontal drag, torque in the world frame.
        fx = R[2] * thrust - p.drag * self.vel[0]
        fy = R[5] * thrust - p.drag * self.vel[1]
        fz = R[8] * thrust
        c = self.client
        if thrust > 0.0 or self.airborne:
            pb.applyExternalForce(self.body, -1, (fx, fy, fz), self.pos, pb.WORLD_FRAME,
                                  physicsClientId=c)
            tw = (R[0] * torque[0] + R[1] * torque[1] + R[2] * torque[2],
                  R[3] * torque[0] + R[4] * torque[1] + R[5] * torque[2],
                  R[6] * torque[0] + R[7] * torque[1] + R[8] * torque[2])
            pb.applyExternalTorque(self.body, -1, tw, pb.WORLD_FRAME, physicsClientId=c)
        pb.stepSimulation(physicsClientId=c)
        self.time += self.dt
        v0 = self._prev_vel
        vel = pb.getBaseVelocity(self.body, physicsClientId=c)[0]
        self._acc_world = tuple((a - b) / self.dt for a, b in zip(vel, v0))
        self._prev_vel = vel
        if thrust > 0.0:
            load = _clamp(thrust / (p.mass * G), 0.3, 2.5)
            self.battery = max(0.0, self.battery - self.dt * 100.0 / p.battery_flight_time * load)

    def _update_mode(self):
        """State transitions that depend on the flight, not on commands."""
        p = self.p
        if self.emergency:
            return
        if self.state == UNKNOWN and self._at_rest_on_ground():
            self._set_state(LANDED)         # down after an emergency left in the air
        if self.state in (TAKING_OFF, LOOPING):
            # The firmware ignores steering then, so a pilot sends none (a takeoff takes 2 s,
            # a flip 1.8 s): the link-loss clock starts again when they end.
            self.last_input_time = self.time
        if self.airborne and self.state != LANDING and not self._land_after_flip:
            why = None
            if self.battery <= 0.0:
                why = ('battery', 'battery empty: landing')
            elif p.link_timeout > 0 and self.time - self.last_input_time > p.link_timeout:
                why = ('link', 'no input for %.1f s: landing (link_timeout: a pilot hovering '
                       'without sending looks like a lost link; 0 turns it off)' % p.link_timeout)
            if why is not None:
                self._warn(*why)
                if self.state == LOOPING:
                    # As a land(): cut short upside down it fell into the floor at 4 m/s.
                    self._land_after_flip = True
                else:
                    self._anim = None
                    self._set_state(LANDING)
        if self.state in (FLYING, HOVERING):
            self._set_state(HOVERING if self.auto_hover else FLYING)

    # -- the onboard controller -------------------------------------------------------
    def _vertical(self, vz_des, kv=5.0):
        """Thrust that tracks a climb rate (m/s), compensating the tilt."""
        if self.R[8] < 0.5:
            # Tilted past 60 deg (a flip cut short by a land, a battery or link landing):
            # climb control would thrust toward the ground; half the weight while the
            # attitude control levels it, as a flip's catch does.
            return 0.5 * self.p.mass * G
        az = kv * (vz_des - self.vel[2])
        return self.p.mass * (G + az) / self.R[8]

    def _attitude(self, roll_d, pitch_d, yaw_rate_d):
        """Body torque tracking roll/pitch set points and a yaw rate (integrated yaw)."""
        J = self.p.inertia
        self._yaw_d = wrap_angle(self._yaw_d + yaw_rate_d * self.dt)
        # Keep the integrated yaw near the real one so a saturated turn cannot wind up.
        err = wrap_angle(self._yaw_d - self.yaw)
        if abs(err) > 0.5:
            self._yaw_d = wrap_angle(self.yaw + math.copysign(0.5, err))
        e = _attitude_error(rpy_matrix(roll_d, pitch_d, self._yaw_d), self.R)
        w = self.omega
        kr, kw = 625.0, 45.0
        wd = (0.0, 0.0, yaw_rate_d)
        return tuple(J[i] * (-kr * e[i] - kw * (w[i] - wd[i])) for i in range(3))

    def _hold_tilt(self):
        """Roll/pitch set points of the auto-hover: brake, then hold the position."""
        p = self.p
        vx, vy = self.vel[0], self.vel[1]
        if self._pos_hold is None and math.hypot(vx, vy) < 0.1:
            self._pos_hold = (self.pos[0], self.pos[1])
        if self._pos_hold is None:
            ax, ay = -1.5 * vx, -1.5 * vy
        else:
            ax = 1.2 * (self._pos_hold[0] - self.pos[0]) - 1.8 * vx
            ay = 1.2 * (self._pos_hold[1] - self.pos[1]) - 1.8 * vy
        cy, sy = math.cos(self.yaw), math.sin(self.yaw)
        a_fwd, a_left = cy * ax + sy * ay, -sy * ax + cy * ay
        m = p.euler_angle_max
        return _clamp(-math.atan2(a_left, G), -m, m), _clamp(math.atan2(a_fwd, G), -m, m)

    def _alt_limited(self, vz_des):
        """Keep a flying drone within altitude_min .. altitude_max."""
        lo, hi = self.p.altitude_min / 1000.0, self.p.altitude_max / 1000.0
        alt = self.altitude
        return _clamp(vz_des, min(0.0, 2.0 * (lo - alt)), max(0.0, 2.0 * (hi - alt)))

    def _hold_alt_rate(self):
        if self._alt_hold is None:
            if abs(self.vel[2]) < 0.1:     # not below the floor a full descent overshoots
                self._alt_hold = max(self.altitude, self.p.altitude_min / 1000.0)
            return 0.0
        return _clamp(2.0 * (self._alt_hold - self.altitude), -0.5, 0.5)

    def _control(self):
        p = self.p
        vz_max = p.control_vz_max / 1000.0
        if self.state == TAKING_OFF:
            target = min(p.takeoff_altitude, p.altitude_max / 1000.0)
            vz = _clamp(1.5 * (target - self.altitude) + 0.1, 0.0, min(vz_max, 0.8))
            if self.altitude > target - TAKEOFF_DONE_WITHIN and abs(self.vel[2]) < 0.15:
                self._alt_hold = self.altitude
                self._pos_hold = None
                self._set_state(HOVERING)
            roll_d, pitch_d = self._hold_tilt()
            return self._vertical(vz), self._attitude(roll_d, pitch_d, 0.0)
        if self.state == LANDING:
            vz = -_clamp(0.2 + 1.0 * self.altitude, 0.2, 0.6)
            if self.altitude < 0.01 or (self.altitude < 0.03 and abs(self.vel[2]) < 0.05):
                self._set_state(LANDED)
                self._pos_hold = None
                return 0.0, (0.0, 0.0, 0.0)
            roll_d, pitch_d = self._hold_tilt()
            return self._vertical(vz), self._attitude(roll_d, pitch_d, 0.0)
        if self._anim is not None:
            return self._animate()
        lx, ly, lz, ax, ay, az = self.cmd
        if self.auto_hover:
            roll_d, pitch_d = self._hold_tilt()
            vz = self._hold_alt_rate()
            yaw_rate = 0.0
        else:
            self._pos_hold = None
            m = p.euler_angle_max
            roll_d, pitch_d = -ly * m, lx * m
            yaw_rate = az * p.control_yaw
            if abs(lz) > HOVER_EPS:
                self._alt_hold = None
                vz = lz * vz_max
            else:
                vz = self._hold_alt_rate()
        return self._vertical(self._alt_limited(vz)), self._attitude(roll_d, pitch_d, yaw_rate)

    def _animate(self):
        a = self._anim
        t = self.time - a['t0']
        if a['type'] in FLIP_AXES:
            return self._flip(a, t)
        if t >= a['duration']:
            self._anim = None
            self._alt_hold = None
            return self._control()
        roll_d, pitch_d, yaw_rate, vz = _animation_setpoints(a['type'], t / a['duration'],
                                                             a['duration'])
        vz = vz if vz is not None else _clamp(2.0 * (a['alt0'] - self.altitude), -0.5, 0.5)
        return self._vertical(self._alt_limited(vz)), self._attitude(roll_d, pitch_d, yaw_rate)

    def _flip(self, a, t):
        p, J = self.p, self.p.inertia
        if t >= FLIP_CUTOFF_S and a['phase'] != 'settle':
            self._warn('flip', 'the flip did not catch in %.0f s (asked at %.2f m): motors '
                       'cut, emergency (ardrone/reset clears it)', FLIP_CUTOFF_S, a['alt0'])
            self._anim = None
            self.emergency = True
            self._set_state(UNKNOWN)
            return 0.0, (0.0, 0.0, 0.0)
        axis, sign = FLIP_AXES[a['type']]
        a['angle'] += sign * self.omega[axis] * self.dt
        a['min_alt'] = min(a.get('min_alt', a['alt0']), self.altitude)
        mg = p.mass * G
        if a['phase'] == 'kick':
            # A short climb first, so the spin costs less height.
            if t >= 0.1:
                a['phase'] = 'spin'
            return 1.5 * mg, self._attitude(0.0, 0.0, 0.0)
        if a['phase'] == 'spin':
            if a['angle'] >= math.radians(290.0):
                a['phase'] = 'catch'
            else:
                w = self.omega
                wd = [0.0, 0.0, 0.0]
                wd[axis] = sign * p.flip_rate
                return 0.3 * mg, tuple(J[i] * 60.0 * (wd[i] - w[i]) for i in range(3))
        # Catch: level out on the shortest path (still forward), climb back, then hover.
        self._yaw_d = a['yaw0']
        torque = self._attitude(0.0, 0.0, 0.0)
        vz = _clamp(1.5 * (a['alt0'] - self.altitude), -0.3, 0.7)
        tilt = math.acos(_clamp(self.R[8], -1.0, 1.0))
        if a['phase'] == 'catch' and tilt < math.radians(5) and max(map(abs, self.omega)) < 0.5:
            a['phase'] = 'settle'
        if a['phase'] == 'settle' and abs(a['alt0'] - self.altitude) < 0.1:
            self.last_flip_angle = abs(a['angle'])
            self.flip_count += 1
            self.last_flip_min_altitude = a['min_alt']
            self._anim = None
            self._alt_hold = a['alt0']
            self._pos_hold = None
            self._set_state(LANDING if self._land_after_flip else FLYING)
        return self._vertical(vz) if tilt < math.radians(60) else 0.5 * mg, torque

    def _mix(self, thrust, torque):
        """Per-motor thrusts within [0, max]; returns what the motors really produce."""
        p = self.p
        a = p.arm / math.sqrt(2.0)
        km = p.yaw_moment
        fmax = p.thrust_to_weight * p.mass * G / 4.0
        tx, ty, tz = torque[0] / a, torque[1] / a, torque[2] / km
        # Motors 1..4: front-left, front-right, rear-right, rear-left.
        f = [(thrust + tx - ty - tz) / 4.0, (thrust - tx - ty + tz) / 4.0,
             (thrust - tx + ty - tz) / 4.0, (thrust + tx + ty + tz) / 4.0]
        f = [_clamp(x, 0.0, fmax) for x in f]
        self.motors = tuple(f)
        return (f[0] + f[1] + f[2] + f[3],
                (a * (f[0] - f[1] - f[2] + f[3]), a * (-f[0] - f[1] + f[2] + f[3]),
                 km * (-f[0] + f[1] - f[2] + f[3])))

    # -- outputs --------------------------------------------------------------------
    def navdata(self):
        """The driver's Navdata fields (degrees, mm/s, mm, g), as a dict."""
        R, v = self.R, self.vel
        body_v = [R[0] * v[0] + R[3] * v[1] + R[6] * v[2],
                  R[1] * v[0] + R[4] * v[1] + R[7] * v[2],
                  R[2] * v[0] + R[5] * v[1] + R[8] * v[2]]
        a = self._acc_world
        f = (a[0], a[1], a[2] + G)   # specific force, world
        body_f = [R[0] * f[0] + R[3] * f[1] + R[6] * f[2],
                  R[1] * f[0] + R[4] * f[1] + R[7] * f[2],
                  R[2] * f[0] + R[5] * f[1] + R[8] * f[2]]
        fmax = self.p.thrust_to_weight * self.p.mass * G / 4.0
        return {
            'batteryPercent': self.battery, 'state': self.state,
            'rotX': math.degrees(self.roll), 'rotY': math.degrees(self.pitch),
            'rotZ': math.degrees(self.yaw), 'altd': int(round(max(self.altitude, 0.0) * 1000)),
            'vx': body_v[0] * 1000, 'vy': body_v[1] * 1000, 'vz': body_v[2] * 1000,
            'ax': body_f[0] / G, 'ay': body_f[1] / G, 'az': body_f[2] / G,
            'motor1': int(255 * self.motors[0] / fmax), 'motor2': int(255 * self.motors[1] / fmax),
            'motor3': int(255 * self.motors[2] / fmax), 'motor4': int(255 * self.motors[3] / fmax),
            'tm': self.time * 1e6,
        }

    def show_scene(self):
        """Add the gridded ground and landmarks (visual only) for pictures."""
        if self._scene is None:
            self._scene = scene.add_bodies(self.client)

    def snapshot(self, path=None, width=640, height=480):
        """Render the chase view (behind and above the drone); write a PNG when `path` is
        given. Returns (h, w, 3) uint8. Drawn in the physics client, in this thread: a
        simulator that must keep stepping meanwhile copies the pose and has
        `cameras.ChaseSnapshots` draw it instead."""
        from leap_teleop.drone.cameras import chase_view
        if not all(isinstance(v, numbers.Integral) and not isinstance(v, bool) and MIN_IMAGE_PX <= v <= MAX_IMAGE_PX
                   for v in (width, height)):
            # a negative size ended the process (the renderer's allocation failed in C++)
            self._warn('snapshot', 'snapshot %r x %r ignored: whole pixels from %d to %d',
                       width, height, MIN_IMAGE_PX, MAX_IMAGE_PX)
            return None
        self.show_scene()
        img = chase_view(self.client, self.pos, self.yaw, width, height)
        if path:
            from PIL import Image
            Image.fromarray(img).save(path)
        return img


def animation_duration_error(duration_ms):
    """'' when a flight animation may last duration_ms, else why not."""
    try:
        ok = 0 <= int(duration_ms) <= MAX_ANIMATION_MS
    except (TypeError, ValueError, OverflowError):
        ok = False
    return '' if ok else ('duration %r ms is not in 0..%d ms (0 = the animation\'s default)'
                          % (duration_ms, MAX_ANIMATION_MS))


def _animation_setpoints(kind, u, duration):
    """(roll, pitch, yaw rate, climb rate or None) of animations 0..15 at progress u.

    Approximations of the firmware's manoeuvres, named after the SDK's constants."""
    d30, d20 = math.radians(30), math.radians(20)
    s = math.sin(2 * math.pi * u)
    osc = math.sin(2 * math.pi * 4 * u)       # 4 cycles per animation
    table = {
        0: (-d30, 0.0, 0.0, None), 1: (d30, 0.0, 0.0, None),
        2: (0.0, -d30, 0.0, None), 3: (0.0, d30, 0.0, None),
        4: (0.0, d20, math.radians(200) / duration, None),
        5: (0.0, d20, -math.radians(200) / duration, None),
        6: (0.0, 0.0, 2 * math.pi / duration, None),
        7: (0.0, 0.0, 2 * math.pi / duration, -0.2),
        8: (0.0, 0.0, 3.0 * osc, None), 9: (0.0, 0.0, 2.0 * osc, None),
        10: (0.25 * osc, 0.0, 0.0, None), 11: (0.0, 0.25 * osc, 0.0, None),
        12: (0.0, 0.0, 0.0, 0.5 * osc),
        13: (0.2 * s, 0.2 * math.cos(2 * math.pi * u), 0.0, None),
        14: (0.25 * osc, 0.25 * math.cos(2 * math.pi * 4 * u), 0.0, None),
        15: (0.3 * osc, 0.3 * math.cos(2 * math.pi * 4 * u), 0.0, None),
    }
    return table[kind]
