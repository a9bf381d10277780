"""Hand -> UR10 teleoperation logic, one instance per arm, no ROS.

Protocol (as the original UR10_lm_arm): thumbs-up arms, fist disarms and stops, rock
stores the origin (palm reference + the TCP's current pose), pinch drives the gripper.
Modes: imitation (TCP follows the palm's offset from the origin, scaled) and joystick
(beyond a dead zone around the origin, the TCP moves at a speed proportional to the
excess). Unlike the original: the input is low-pass filtered and validated (out-of-order
and late messages are dropped and counted, see input_check), the target is clamped to a
workspace box, IK failures hold the arm instead of raising, stale input or a lost hand
holds and disarms (watchdog), stale joint states or the clock jumping back (a simulator
restart) disarm without commanding the old pose, and every state change says why.
"""
import math
from dataclasses import dataclass, field, fields

import numpy as np

from leap_teleop.params import Param, check_params
from leap_teleop.teleop.filters import LowPass
from leap_teleop.teleop.input_check import InputStream
from leap_teleop.ur10 import kinematics as kin

DISARMED, ARMED, TRACKING, HOLDING = 'disarmed', 'armed', 'tracking', 'holding'
MODES = ('imitation', 'joystick')
GRIPPER_MODES = ('binary', 'proportional')


@dataclass
class ArmTeleopParams:
    mode: str = 'imitation'
    # Leap axes (x right, y up, z toward the user) -> arm base axes, rows = base x, y, z.
    axis_map: tuple = ((0.0, 0.0, -1.0), (-1.0, 0.0, 0.0), (0.0, 1.0, 0.0))
    scale: float = 2.5                 # imitation: robot m per hand m
    deadzone_mm: float = 30.0          # joystick: radius around the origin that moves nothing
    joystick_gain: float = 2.0         # joystick: TCP m/s per m of palm excess
    max_tcp_speed: float = 0.25        # joystick: m/s cap
    workspace_min: tuple = (0.25, -0.9, 0.0)    # m, arm base frame
    workspace_max: tuple = (1.15, 0.9, 0.9)
    tool_yaw: float = 0.0              # rad, fixed tool orientation: pointing down, turned by this
    filter_cutoff_hz: float = 4.0      # low-pass on the palm position; 0 disables
    max_joint_speed: float = 0.05      # rad/s: trajectory duration = max|dq| / this
    min_duration: float = 0.05         # s, shortest trajectory sent
    input_timeout: float = 0.2         # s without hand input -> hold and disarm
    gripper_mode: str = 'binary'
    gripper_binary_closed: float = 0.43
    max_palm_mm: float = 1000.0        # |palm| beyond this is a tracking error, ignored
    max_input_age: float = 0.25        # s a message may arrive later than the stream's
                                       # best-case latency
    joint_timeout: float = 0.5         # s without joint states -> disarm (robot gone)

    @classmethod
    def from_dict(cls, values):
        """Build from a dict (YAML / ROS params); unknown keys and bad values raise
        ValueError naming them."""
        known = {f.name for f in fields(cls)}
        unknown = set(values) - known
        if unknown:
            raise ValueError('unknown arm teleop parameters: %s' % ', '.join(sorted(unknown)))
        p = cls(**values)
        p.validate()
        return p

    def validate(self):
        """Check every field against TELEOP_PARAMS (ParamError, a ValueError, names the
        first bad one), then what involves two fields."""
        for name, value in check_params(TELEOP_PARAMS, vars(self)).items():
            setattr(self, name, value)
        lo, hi = np.asarray(self.workspace_min, float), np.asarray(self.workspace_max, float)
        if np.any(lo >= hi):
            raise ValueError('workspace_min must be below workspace_max on every axis')
        if not np.linalg.matrix_rank(np.asarray(self.axis_map, float)) == 3:
            raise ValueError('axis_map must be invertible (every hand axis moves the robot)')


_P = ArmTeleopParams()
# Every ArmTeleopParams field's declaration: ur10_arm's ~params (config/ur10_teleop.yaml)
# and ArmTeleopParams.validate share it. Timeouts and speeds have upper bounds too.
TELEOP_PARAMS = {
    'mode': Param(_P.mode, 'imitation (TCP follows the palm) or joystick (speed beyond the '
                           'dead zone)', choices=MODES),
    'axis_map': Param([list(r) for r in _P.axis_map], 'Leap axes -> arm base axes, rows = '
                      'base x, y, z', length=3,
                      item=Param([0.0, 0.0, 0.0], '', length=3, ge=-1.0, le=1.0)),
    'scale': Param(_P.scale, 'imitation: robot m per hand m', gt=0.0, le=10.0),
    'deadzone_mm': Param(_P.deadzone_mm, 'joystick: radius around the origin that moves '
                                         'nothing', unit='mm', gt=0.0, le=300.0),
    'joystick_gain': Param(_P.joystick_gain, 'joystick: TCP m/s per m of palm beyond the '
                                             'dead zone', unit='1/s', gt=0.0, le=20.0),
    'max_tcp_speed': Param(_P.max_tcp_speed, 'joystick: TCP speed cap', unit='m/s',
                           gt=0.0, le=1.0),
    'workspace_min': Param(list(_P.workspace_min), 'TCP target box, low corner (base frame)',
                           unit='m', length=3, ge=-3.0, le=3.0),
    'workspace_max': Param(list(_P.workspace_max), 'TCP target box, high corner', unit='m',
                           length=3, ge=-3.0, le=3.0),
    'tool_yaw': Param(_P.tool_yaw, 'tool turned about z by this (pointing down)', unit='rad',
                      ge=-2 * math.pi, le=2 * math.pi),
    'filter_cutoff_hz': Param(_P.filter_cutoff_hz, 'low-pass on the palm position; 0 = off',
                              unit='Hz', ge=0.0, le=1000.0),
    'max_joint_speed': Param(_P.max_joint_speed, 'trajectory duration = max|dq| / this',
                             unit='rad/s', gt=0.0, le=float(min(kin.MAX_JOINT_SPEED))),
    'min_duration': Param(_P.min_duration, 'shortest trajectory sent', unit='s',
                          gt=0.0, le=5.0),
    'input_timeout': Param(_P.input_timeout, 'no hand input this long -> hold and disarm '
                                             '(watchdog)', unit='s', gt=0.0, le=10.0),
    'gripper_mode': Param(_P.gripper_mode, 'binary (closed while pinching) or proportional',
                          choices=GRIPPER_MODES),
    'gripper_binary_closed': Param(_P.gripper_binary_closed, 'binary: knuckle when closed',
                                   unit='rad', ge=0.0, le=0.8),
    'max_palm_mm': Param(_P.max_palm_mm, '|palm| beyond this is a tracking error, ignored',
                         unit='mm', gt=0.0, le=2000.0),
    'max_input_age': Param(_P.max_input_age, 'drop a message arriving this much later than '
                                             'the stream\'s best latency', unit='s',
                           gt=0.0, le=10.0),
    'joint_timeout': Param(_P.joint_timeout, 'no joint states this long -> disarm (robot '
                                             'gone)', unit='s', gt=0.0, le=10.0),
}


@dataclass
class HandInput:
    """One hand message, side-free (see conversions.from_leapcobot)."""
    present: bool
    palm_mm: tuple = (0.0, 0.0, 0.0)
    fist: bool = False
    thumb_up: bool = False
    pinch: bool = False
    pinch_value: float = 0.0
    rock: bool = False
    stamp: float = 0.0

    @classmethod
    def from_leapcobot_dict(cls, d):
        return cls(present=bool(d['present']), palm_mm=tuple(d['palmpos']), fist=bool(d['fist']),
                   thumb_up=bool(d['thumb_up']), pinch=bool(d['pinch']),
                   pinch_value=float(d['pinch_value']),
                   rock=bool(d['set_origin_frame_detected']), stamp=float(d['stamp']))


@dataclass
class ArmCommand:
    """What to send this control period; None fields mean nothing to send."""
    q: np.ndarray = None               # joint target
    duration: float = 0.0              # s, time_from_start of the target
    gripper: float = None              # knuckle 0 (open) .. 0.8 (closed)


@dataclass
class ArmStatus:
    state: str = DISARMED
    reason: str = 'waiting for thumbs-up'
    origin_set: bool = False
    target: tuple = ()                 # TCP target, base frame, m
    rejected_inputs: int = 0           # non-finite / absurd / out-of-order / late messages
    ik_failures: int = 0
    counters: dict = field(default_factory=dict)


class ArmTeleop:
    def __init__(self, params=None):
        self.p = params or ArmTeleopParams()
        self.p.validate()
        self._axes = np.asarray(self.p.axis_map, dtype=float)
        self._lo = np.asarray(self.p.workspace_min, dtype=float)
        self._hi = np.asarray(self.p.workspace_max, dtype=float)
        self._rotation = kin.tool_down(self.p.tool_yaw)
        self._filter = LowPass(self.p.filter_cutoff_hz)
        self.status = ArmStatus()
        self._hand = None
        self._hand_rx = None
        self._q = None
        self._joints_rx = None
        self._stream = InputStream(self.p.max_input_age, self.p.input_timeout)
        self._palm_ref = None
        self._tcp_ref = None
        self._target = None
        self._last_step = None
        self._gripper_sent = None

    # -- input (cheap; called from subscriber callbacks) ----------------------------
    def on_hand(self, hand, now):
        """Store one hand message. Returns None, or why it was rejected."""
        palm = np.asarray(hand.palm_mm, dtype=float)
        why = None
        if hand.present and (not np.all(np.isfinite(palm))
                             or np.any(np.abs(palm) > self.p.max_palm_mm)):
            why = 'palm position %s is not a trackable hand' % (tuple(palm),)
        elif not math.isfinite(hand.pinch_value):
            why = 'pinch value %r is not finite' % hand.pinch_value
        else:
            why = self._stream.check(hand.stamp, now)
        if why:
            self.status.rejected_inputs += 1
            return why
        self._hand, self._hand_rx = hand, now
        return None

    def on_joints(self, q, now=None):
        """Store the arm's joint positions; with `now`, their staleness is watched."""
        q = np.asarray(q, dtype=float)
        # Non-finite or far outside the joint limits: a corrupt state, never echoed in a hold.
        if (q.shape == (6,) and np.all(np.isfinite(q)) and np.all(q >= kin.JOINT_LOWER - 0.01)
                and np.all(q <= kin.JOINT_UPPER + 0.01)):
            self._q = np.clip(q, kin.JOINT_LOWER, kin.JOINT_UPPER)
            self._joints_rx = now
            return True
        return False

    # -- control period ---------------------------------------------------------------
    def _set(self, state, reason):
        self.status.state, self.status.reason = state, reason

    def _hold(self):
        self._target = None
        if self._q is None:
            return ArmCommand()
        return ArmCommand(q=self._q.copy(), duration=self.p.min_duration)

    def _lose_robot(self, reason):
        """The robot's state is unknown (simulator or driver gone / restarted): forget it
        and disarm without a hold, which would command the old pose to a new robot."""
        self._q = self._joints_rx = self._hand = None
        self._stream.reset()
        if self.status.state != DISARMED:
            self._set(DISARMED, reason)
            self.status.origin_set = False
            self._palm_ref = self._tcp_ref = self._target = None
        return ArmCommand()

    def _disarm(self, reason):
        was_moving = self.status.state in (ARMED, TRACKING, HOLDING)
        self._set(DISARMED, reason)
        self.status.origin_set = False
        self._palm_ref = self._tcp_ref = self._target = None
        return self._hold() if was_moving else ArmCommand()

    def step(self, now):
        """One control period: the command to send (possibly empty)."""
        jumped_back = self._last_step is not None and now < self._last_step - 1e-6
        dt = 0.0 if self._last_step is None else max(0.0, now - self._last_step)
        self._last_step = now
        if jumped_back:
            return self._lose_robot('the clock jumped back (simulation restarted?)')
        if self._joints_rx is not None and now - self._joints_rx > self.p.joint_timeout:
            return self._lose_robot('no joint states for %.2f s' % self.p.joint_timeout)
        if self._q is None:
            self._set(DISARMED, 'waiting for joint states')
            return ArmCommand()
        hand = self._hand
        if hand is None or now - self._hand_rx > self.p.input_timeout:
            if self.status.state != DISARMED:
                return self._disarm('no hand input for %.2f s (watchdog)' % self.p.input_timeout)
            return ArmCommand()
        if not hand.present:
            if self.status.state != DISARMED:
                return self._disarm('hand left the sensor')
            return ArmCommand()
        if hand.fist:
            if self.status.state != DISARMED:
                return self._disarm('fist')
            return ArmCommand()
        if self.status.state == DISARMED:
            if hand.thumb_up:
                self._set(ARMED, 'thumbs-up; show rock to set the origin')
            return ArmCommand()

        palm = np.asarray(hand.palm_mm, dtype=float)
        if hand.rock:
            self._palm_ref = palm.copy()
            self._tcp_ref = kin.fk(self._q)[:3, 3].copy()
            self._target = self._tcp_ref.copy()
            self._filter.reset(palm, now)
            self.status.origin_set = True
            self._set(TRACKING, 'origin set')
        cmd = ArmCommand(gripper=self._gripper_command(hand))
        if self._palm_ref is None:
            return cmd
        palm_f = self._filter.update(palm, now)
        offset = palm_f - self._palm_ref
        if self.p.mode == 'imitation':
            target = self._tcp_ref + self._axes @ offset * 0.001 * self.p.scale
        else:
            target = self._joystick(offset, dt)
        target = np.clip(target, self._lo, self._hi)
        self._target = target
        self.status.target = tuple(target)
        q = kin.ik_nearest(kin.pose(target, self._rotation), self._q)
        if q is None:
            self.status.ik_failures += 1
            if self.status.state != HOLDING:
                self._set(HOLDING, 'no IK solution within the joint limits for %s'
                          % np.round(target, 3).tolist())
                held = self._hold()
                self._target = target
                cmd.q, cmd.duration = held.q, held.duration
            return cmd
        if self.status.state == HOLDING:
            self._set(TRACKING, 'target reachable again')
        cmd.q = q
        cmd.duration = max(float(np.max(np.abs(q - self._q))) / self.p.max_joint_speed,
                           self.p.min_duration)
        return cmd

    def _joystick(self, offset_mm, dt):
        n = float(np.linalg.norm(offset_mm))
        base = self._target if self._target is not None else self._tcp_ref
        if n <= self.p.deadzone_mm:
            return base
        excess = offset_mm * (1.0 - self.p.deadzone_mm / n)
        v = self._axes @ excess * 0.001 * self.p.joystick_gain
        speed = float(np.linalg.norm(v))
        if speed > self.p.max_tcp_speed:
            v *= self.p.max_tcp_speed / speed
        return base + v * dt

    def _gripper_command(self, hand):
        if self.p.gripper_mode == 'binary':
            want = self.p.gripper_binary_closed if hand.pinch else 0.0
        else:
            want = min(max(hand.pinch_value, 0.0), 0.8) if hand.pinch else 0.0
        if self._gripper_sent is not None and abs(want - self._gripper_sent) < 0.01:
            return None
        self._gripper_sent = want
        return want
