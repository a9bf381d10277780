"""Hand -> UR10 teleoperation logic, one instance per arm, no ROS.

Protocol (as the original UR10_lm_arm): thumbs-up arms, fist disarms and stops, rock
stores the origin (palm reference + the TCP's pose where the arm comes to rest: it may
still be moving), pinch drives the gripper.
Modes: imitation (TCP follows the palm's offset from the origin, scaled) and joystick
(beyond a dead zone around the origin, the TCP moves at a speed proportional to the
excess). Orientation modes: fixed (tool pointing down, turned by tool_yaw), yaw (the
tool's yaw follows the hand's turn about the vertical), full (the tool turns as the palm
does); the hand's rotation since the origin goes through the same axis map as positions, is
scaled, and the tool's tilt from vertical and turn from its yaw at the rock (kept across
re-anchors) are clamped like the workspace. Unlike the original: the input is smoothed by
One Euro filters (position and rotation vector) and validated (out-of-order and late
messages are dropped and counted, see input_check), the target is clamped to a workspace
box, motion is commanded by a joint servo with speed and acceleration limits whose
trajectories keep the velocity continuous (servo.py), a target further than the joints go
in one period is approached in steps along the straight TCP line (the arm catches up along
the hand's path, inside the box), IK failures and other arm configurations hold the arm
instead of raising, stale input holds at once and resumes from the current pose when fresh
input returns within disarm_after (when the hand itself moved the target more than
reanchor_beyond meanwhile, the origin is re-anchored: the hand where it is maps to where
its last message put the target, so none of the motion unseen is driven; else the mapping
stays; either way the arm catches up within the servo's limits with what it lagged behind
before the stall), while a longer silence, a lost hand or a fist disarms (watchdog). Stale joint
states (a loaded simulator) hold without commanding anything; states back within
joint_loss_after resume on the same origin (the hand's input never stopped), caught up
within the servo's limits; a longer loss or the clock jumping back (a simulator restart)
disarms without commanding the old pose. Every state change says why.
"""
import collections
import math
import numbers
from dataclasses import dataclass, field

import numpy as np

from leap_teleop.control.input_check import InputStream
from leap_teleop.control.one_euro import OneEuroFilter
from leap_teleop.control.servo import JointServo
from leap_teleop.ur10 import kinematics as kin
from leap_teleop.ur10 import orientation as ori
from leap_teleop.ur10.teleop_params import TELEOP_PARAMS, ArmTeleopParams  # noqa: F401 (re-exported)

DISARMED, ARMED, TRACKING, HOLDING = 'disarmed', 'armed', 'tracking', 'holding'
# While tracking, an IK answer this far (rad, any joint) from the last goal is another
# arm configuration (elbow, shoulder or wrist flip), not the hand's motion: hold instead
# (unless it keeps the configuration, see _same_configuration: then it is caught up in
# steps, and only steps, far below this, are sent).
MAX_GOAL_JUMP = 1.0
# Catch-up: a step whose joints need between this much and all of the period's allowance
# ends the search for it (shorter ones are taken when nothing longer is found).
CATCH_UP_ENOUGH = 0.95
# A stepped goal slows down to the target at this much of the acceleration limit: the servo
# follows it a little late and must still stop there (at the full limit it overran a 5 cm
# step by 12 mm).
CATCH_UP_DECEL = 0.25
# A goal heading for a face of the workspace box (where the clamp stops the target dead)
# slows down to stop there at this much of the acceleration limit (at the simulation's
# limits: 1.8 mm past it at most straight on, against 78, 4.3 mm obliquely; CATCH_UP_DECEL's
# 1.3 mm began braking twice as far from it). Not covered: a goal catching up with a target
# that turns back at a face turns with it within a period, and the servo brakes past it
# (a hand at 250 mm/s up to the box's top and back: 46-90 mm above it).
FACE_DECEL = 0.5
# Whether the target heads for a face is judged from its motion over this long (s, about a
# hand tremor's period), and only from a speed toward the face above FACE_APPROACH_MIN
# (m/s): 1-3 mm from the table, the hand's noise made the last single step point at it in
# most periods, and a slide along it lagged 10.5 mm rms instead of 4.1. At 10 mm/s over the
# window the noise 1 mm from the table slows 4 % of the goals and the slide lags as far
# (4.09 mm rms) as 100 mm above it; at 40 a target reaching the top at 39 mm/s with
# max_joint_accel 0.5 ran 17.6 mm above it.
FACE_WINDOW_S = 0.1
FACE_APPROACH_MIN = 0.01
# Joint states back after a stall further than this (rad) outside where the robot could
# have got to (its last trajectory to rest, or its braking distance at the speed it last
# reported): another robot state, not a stall.
RESUME_TOLERANCE = 0.02
# After a hand-input stall, a hand that turned the tool's target further than this (rad)
# meanwhile re-anchors the origin, as reanchor_beyond does for its position.
REANCHOR_TURN_RAD = 0.3
# An origin is set where the arm's plan comes to rest; one within this (rad, every joint) of
# where the plan is now (a rock held at rest: the goal of its last frame) is the pose now,
# not that pose recomputed with other rounding.
AT_REST_RAD = 1e-9
# A robot whose joints stay further from the plan than this much of its motion at
# max_joint_speed (plus RESUME_TOLERANCE) for OFF_PLAN_S does not follow its commands (a
# protective stop, a stopped controller): planning on from the plan would ask it for the
# whole distance within one command once it follows again. A simulator lagging under load
# stays within it (it falls behind by at most 0.5 s before it starts its count afresh).
OFF_PLAN_LAG_S = 0.6
OFF_PLAN_S = 0.25
# Joystick: the target leads where the arm is commanded to be by at most this much (s) of
# max_tcp_speed (about the servo's lag while it speeds up).
JOYSTICK_LEAD_S = 0.1
# A max_joint_accel lowered live comes down over LOWER_ACCEL_RAMP_S, at once when every
# joint can stop within LOWER_ACCEL_STOP_S at it.
LOWER_ACCEL_STOP_S = 0.1
LOWER_ACCEL_RAMP_S = 1.0
# Per arm action, the gesture behind its flag as the default bindings have it.
GESTURE_WORDS = {'arm': 'thumbs-up', 'origin': 'rock', 'stop': 'fist', 'gripper': 'pinch'}
# The servo's commanded state this many periods of travel behind the goal: it lags.
SERVO_LAG_PERIODS = 3.0
# The step intervals a command's horizon follows: the loop's own period and a hand's wake-ups
# alternate within it.
STEP_WINDOW_S = 0.25
STEP_WINDOW_MAX = 256              # ... at most this many (0.25 s of 1000 Hz steps)
_TWO_PI = 2 * math.pi
# Joint states this far outside the limits are corrupt, not rounding (as floats: checked
# on every state; NaN fails the comparisons, infinities the bounds).
_JOINTS_LOW = (kin.JOINT_LOWER - 0.01).tolist()
_JOINTS_HIGH = (kin.JOINT_UPPER + 0.01).tolist()


def _within(v, limit):
    """Every element of the array v finite and within +-limit."""
    if v.shape == (3,):
        x, y, z = v.tolist()
        return -limit <= x <= limit and -limit <= y <= limit and -limit <= z <= limit
    return bool(np.isfinite(v).all()) and not (np.abs(v) > limit).any()


def _joint_time(q, ref, speed):
    """Seconds the joints need from ref to q at their speed limits (lists of floats)."""
    return max([abs(a - b) / v for a, b, v in zip(q, ref, speed)])


def _branch(q):
    """(shoulder, elbow, wrist) sides of the arm configuration of joints q (the IK's
    2 x 2 x 2 solutions); the shoulder's: the wrist centre's side of the base axis in the
    arm's plane."""
    q2, q3, q4, q5 = q[1], q[2], q[3], q[4]
    reach = kin.A2 * math.cos(q2) + kin.A3 * math.cos(q2 + q3) + kin.D5 * math.sin(q2 + q3 + q4)
    return reach > 0.0, math.sin(q3) > 0.0, math.sin(q5) > 0.0


def _largest_joint_move(q, ref):
    return max([abs(a - b) for a, b in zip(q, ref)])


def _same_configuration(q, ref):
    """q is reached from ref without a flip: near (crossing a singularity on the way), or
    on the same branch with no joint turning half a turn or more (the nearest copy within
    the limits went the other way round a joint limit)."""
    diff = _largest_joint_move(q, ref)
    return diff <= MAX_GOAL_JUMP or (diff < math.pi and _branch(q) == _branch(ref))


def _joints_plausible(q):
    """Six joint positions (floats) finite and not far outside the joint limits."""
    for v, lo, hi in zip(q, _JOINTS_LOW, _JOINTS_HIGH):
        if not lo <= v <= hi:
            return False
    return True


@dataclass
class ArmInput:
    """One hand message, side-free (see hand_conversions.from_leapcobot)."""
    present: bool
    palm_mm: tuple = (0.0, 0.0, 0.0)
    fist: bool = False
    thumb_up: bool = False
    pinch: bool = False
    pinch_value: float = 0.0
    rock: bool = False
    stamp: float = 0.0
    # Rotation since the origin (rad) about Leap z, y, x, as the sender measures it.
    rotate: float = 0.0
    turn: float = 0.0
    swing: float = 0.0

    @classmethod
    def from_leapcobot_dict(cls, d):
        return cls(present=bool(d['present']), palm_mm=tuple(d['palmpos']), fist=bool(d['fist']),
                   thumb_up=bool(d['thumb_up']), pinch=bool(d['pinch']),
                   pinch_value=float(d['pinch_value']),
                   rock=bool(d['set_origin_frame_detected']), stamp=float(d['stamp']),
                   rotate=float(d.get('rotate_value', 0.0)),
                   turn=float(d.get('turn_value', 0.0)), swing=float(d.get('swing_value', 0.0)))


@dataclass
class ArmCommand:
    """What to send this control period; None fields mean nothing to send."""
    q: np.ndarray = None               # joint goal: the target pose's IK, or where a hold stops
    points: list = None                # trajectory [(time_from_start s, q, qd)] from `stamp`
    stamp: float = 0.0                 # time the trajectory starts (the control period's)
    gripper: float = None              # knuckle 0 (open) .. 0.8 (closed)
    input_stamp: float = 0.0           # capture stamp of the hand behind it (0: none, a
                                       # watchdog hold)


@dataclass
class ArmTeleopStatus:
    state: str = DISARMED
    reason: str = ''
    origin_set: bool = False
    target: tuple = ()                 # TCP target, base frame, m
    target_rotation: tuple = ()        # tool orientation target (3x3 rows), base frame
    rejected_inputs: int = 0           # non-finite / absurd / out-of-order / late messages
    ik_failures: int = 0
    input_stamp: float = 0.0           # capture stamp of the hand behind the latest command
    counters: dict = field(default_factory=dict)


class ArmTeleop:
    def __init__(self, params=None, step_interval=0.0, gesture_words=None):
        """gesture_words: per arm action (arm, origin, stop), the gesture the state lines
        name for it, GESTURE_WORDS where not given (the sender's bindings decide which
        gesture raises each flag).
        step_interval: the longest time the loop that steps it leaves between two steps.
        Every command is planned over at least 1.5 times the longest step interval of the
        last STEP_WINDOW_S, up to that (and command_horizon's bound): a shorter horizon,
        braked to rest before the next command, moved the arm in short pulses, while a
        longer one than the steps need (a slow loop woken by a fast hand) overshoots."""
        self.p = params or ArmTeleopParams()
        self.p.validate()
        self._words = dict(GESTURE_WORDS, **(gesture_words or {}))
        self._axes = np.asarray(self.p.axis_map, dtype=float)
        self._axes_rotation = ori.axis_rotation(self._axes)
        self._lo = np.asarray(self.p.workspace_min, dtype=float)
        self._hi = np.asarray(self.p.workspace_max, dtype=float)
        self._rotation = kin.tool_down(self.p.tool_yaw)
        self._joint_lower = np.maximum(np.concatenate([kin.JOINT_LOWER[:3], self.p.wrist_lower]),
                                       kin.JOINT_LOWER)
        self._joint_upper = np.minimum(np.concatenate([kin.JOINT_UPPER[:3], self.p.wrist_upper]),
                                       kin.JOINT_UPPER)
        # As floats: what the IK compares against every period.
        self._ik_limits = (tuple(self._joint_lower.tolist()), tuple(self._joint_upper.tolist()))
        self._filter = OneEuroFilter(self.p.filter_min_cutoff_hz, self.p.filter_beta,
                                     self.p.filter_d_cutoff_hz)
        self._rotation_filter = OneEuroFilter(self.p.rotation_min_cutoff_hz,
                                              self.p.rotation_beta, self.p.rotation_d_cutoff_hz)
        speed = np.minimum(self.p.max_joint_speed, kin.MAX_JOINT_SPEED)
        self._longest_horizon = min(max(self.p.command_horizon, float(step_interval)),
                                    TELEOP_PARAMS['command_horizon'].le)
        # (when, interval) of the recent steps; bounded: a stopped clock never ages them out
        self._step_intervals = collections.deque(maxlen=STEP_WINDOW_MAX)
        self._servo = JointServo(speed, np.minimum(self.p.max_joint_accel, kin.MAX_JOINT_ACCEL),
                                 self.p.command_horizon, self.p.servo_gain,
                                 kin.JOINT_LOWER, kin.JOINT_UPPER, self.p.servo_lead,
                                 self.p.servo_reach_fast)
        self.status = ArmTeleopStatus(reason='waiting for %s' % self._words['arm'])
        self._hand = None
        self._hand_rx = None
        self._q = None
        self._qd = np.zeros(6)             # the joint velocities last reported
        self._gripper_asked = None         # when the hand asked for a change not yet sent
        self._joints_rx = None
        self._stream = InputStream(self.p.max_input_age, self.p.input_timeout)
        self._rewound = False           # the stream began again at older stamps
        self._palm_ref = None
        self._tcp_ref = None
        self._tool_ref = None          # tool rotation at the origin (base frame)
        self._yaw_ref = 0.0
        self._turn_ref = 0.0           # yaw mode: the tool's turn at the hand's reference
        self._hand_rot_ref = None      # hand rotation vector at the origin (Leap axes)
        self._hand_ref_rotation_t = None   # its rotation matrix, transposed
        self._hand_rot_key = None      # (orientation mode, hand angles) of _hand_rot
        self._hand_rot = None
        # (relative rotation vector, (swing or None, turn from _yaw_ref)) last aimed
        self._tool_near = (None, None)
        self._target = None
        self._joy_still = False        # joystick: the last target was a dead-zone stop
        self._goal = None              # (time, joint goal) of the last tracked target
        self._goal_rate = 0.0          # its last step / (max_joint_speed x the period)
        self._catching_up = False      # the goal is a step toward the target
        self._last_reach = None        # (time, the target's IK, the target) the period before
        # (time, the target's IK, the target) of the periods since _last_reach was last unset,
        # the last FACE_WINDOW_S of them
        self._reached = collections.deque(maxlen=STEP_WINDOW_MAX)
        self._lower_accel = None       # a max_joint_accel lowered live, not applied yet
        self._last_step = None
        self._gripper_sent = None
        self._thumb_up_since = None       # (capture stamp, receipt) of the current thumbs-up's start
        self._stalled = None              # holding: (what stalled, when it last came)
        # The hand input fell silent during the current stall (its last message before the
        # silence), whatever else stalled with it: its return re-anchors as after a hand
        # stall alone.
        self._hand_silent = None
        self._off_plan_since = None       # when the joints were first seen off the plan
        self._slower_since = (0.0, -math.inf)   # (max_joint_speed before, when it was lowered)
        self._resume_box = None           # joint stall: (lo, hi) joints it may resume in

    def retune(self, changes):
        """Apply checked changes ({name: value}, the node's reconfigurable ones) while
        running: the params (read where used) and the filters and servo built from them."""
        old_scale, old_turn_scale = self.p.scale, self.p.orientation_scale
        if changes.get('max_joint_speed', math.inf) < self.p.max_joint_speed:
            self._slower_since = (self.p.max_joint_speed,
                                  -math.inf if self._last_step is None else self._last_step)
        for name, value in changes.items():
            setattr(self.p, name, value)
        p = self.p
        if self._palm_ref is not None:
            self._rescale_origin(old_scale, old_turn_scale)
        for filt, prefix in ((self._filter, 'filter_'), (self._rotation_filter, 'rotation_')):
            filt.min_cutoff_hz = getattr(p, prefix + 'min_cutoff_hz')
            filt.beta = getattr(p, prefix + 'beta')
            filt.d_cutoff_hz = getattr(p, prefix + 'd_cutoff_hz')
        self._servo.max_speed = np.minimum(p.max_joint_speed, kin.MAX_JOINT_SPEED)
        accel = np.minimum(p.max_joint_accel, kin.MAX_JOINT_ACCEL)
        if 'max_joint_accel' not in changes:
            pass                    # another parameter: a ramp under way goes on
        elif self._servo.moving and float(accel.max()) < float(self._servo.max_accel.max()):
            # Braking at a lowered limit at once mid-motion runs each joint past its goal by
            # v^2/2a (0.23 m off a catch-up): it comes down over LOWER_ACCEL_RAMP_S, or at
            # once when the joints can stop at it quickly.
            # Meanwhile no joint speeds up beyond the new limit: at the ramped one it gained
            # speeds the new limit could not shed, and ran hundreds of mm past its goal.
            self._lower_accel = (self._servo.max_accel.copy(), accel, None)
            self._servo.speedup_accel = accel
        else:
            self._servo.max_accel, self._lower_accel = accel, None
            self._servo.speedup_accel = None
        self._servo.gain = float(p.servo_gain)
        self._servo.lead = float(p.servo_lead)

    def _rescale_origin(self, old_scale, old_turn_scale):
        """A new scale applies to the hand's motion from here on: the target stays where it
        is. (Applied to the whole offset since the rock, it moved the arm of a hand held
        still: 0.25 m for a palm 10 cm out when the scale went from 2.5 to 5.)"""
        if (self.p.scale != old_scale and self.p.mode == 'imitation'
                and self._filter.value is not None):
            offset = self._filter.value - self._palm_ref
            self._tcp_ref = self._tcp_ref + self._axes @ offset * (0.001 * (old_scale - self.p.scale))
        hand_rot = self._rotation_filter.value
        if (self.p.orientation_scale != old_turn_scale and self.p.orientation != 'fixed'
                and hand_rot is not None):
            # The rotation so far becomes part of the reference; the hand's own reference
            # moves to where it is.
            rel = kin.rotation_from_vector(hand_rot) @ self._hand_ref_rotation_t
            delta = old_turn_scale * kin.rotation_vector_near(
                ori.map_rotation(rel, self._axes_rotation), self._tool_near[0])
            self._turn_ref += float(delta[2])
            self._tool_ref = kin.rotation_from_vector(delta) @ self._tool_ref
            self._hand_rot_ref = hand_rot.copy()
            self._hand_ref_rotation_t = kin.rotation_from_vector(hand_rot).T
            self._tool_near = (np.zeros(3), self._tool_near[1])

    def diagnostics(self):
        """(level 'ok' | 'warn', summary, [(key, value)]) of the status, for a diagnostics
        report: warn while holding."""
        s = self.status
        return ('warn' if s.state == HOLDING else 'ok', '%s: %s' % (s.state, s.reason),
                [('origin set', s.origin_set), ('rejected inputs', s.rejected_inputs),
                 ('IK failures', s.ik_failures)])

    # -- input (cheap; called from subscriber callbacks) ----------------------------
    def new_input_connection(self):
        """The hand input's connection was re-made: judge its lateness afresh (a baseline
        taken while this node's clock lagged would refuse every message for ever)."""
        self._stream.reset()

    def on_hand(self, hand, now):
        """Store one hand message. Returns None, or why it was rejected."""
        angles = (hand.rotate, hand.turn, hand.swing)
        try:
            palm = np.asarray(hand.palm_mm, dtype=float)
        except (TypeError, ValueError):
            palm = None
        if palm is None or not all(isinstance(v, numbers.Real)
                                   for v in angles + (hand.pinch_value, hand.stamp)):
            self.status.rejected_inputs += 1
            return 'hand fields are not numbers'
        why = None
        if hand.present and (palm.shape != (3,) or not _within(palm, self.p.max_palm_mm)):
            why = 'palm position %s is not a trackable hand' % (
                tuple(palm.tolist()) if palm.ndim else palm.tolist(),)
        elif not math.isfinite(hand.pinch_value):
            why = 'pinch value %r is not finite' % hand.pinch_value
        elif not (-_TWO_PI <= hand.rotate <= _TWO_PI and -_TWO_PI <= hand.turn <= _TWO_PI
                  and -_TWO_PI <= hand.swing <= _TWO_PI):     # finite, within a turn
            why = 'hand rotation %s is not an angle' % (angles,)
        elif not math.isfinite(hand.stamp):
            # NaN fails every order comparison: taken, it would let stale messages through.
            why = 'stamp %r is not finite' % hand.stamp
        else:
            why = self._stream.check(hand.stamp, now)
        if why:
            self.status.rejected_inputs += 1
            return why
        self._rewound = self._rewound or self._stream.rewound
        if self._hand_rx is not None and now - self._hand_rx > self.p.input_timeout:
            self._thumb_up_since = None       # a hold is seen, not assumed across a silence
        self._hand, self._hand_rx = hand, now
        # A thumbs-up shown with the fist (both flags on at a transition) is no hold: the
        # first frame without the fist armed at once.
        if not (hand.present and hand.thumb_up) or hand.fist:
            self._thumb_up_since = None
        elif self._thumb_up_since is None:
            self._thumb_up_since = (hand.stamp, now)
        return None

    def on_joints(self, q, now=None, qd=None):
        """Store the arm's joint positions (and velocities, when the state has them);
        with `now`, their staleness is watched."""
        q = np.asarray(q, dtype=float)
        # Non-finite or far outside the joint limits: a corrupt state, never echoed in a hold.
        if q.shape == (6,) and _joints_plausible(q.tolist()):
            self._q = np.minimum(np.maximum(q, kin.JOINT_LOWER), kin.JOINT_UPPER)
            qd = None if qd is None else np.asarray(qd, dtype=float)
            ok = qd is not None and qd.shape == (6,) and all(map(math.isfinite, qd.tolist()))
            self._qd = qd if ok else np.zeros(6)
            self._joints_rx = now
            # (states received before the servo's last plan ended are not where it rests)
            self._servo.received = now
            return True
        return False

    # -- control period ---------------------------------------------------------------
    def _set(self, state, reason):
        self.status.state, self.status.reason = state, reason

    def _hold(self, now):
        """Stop the commanded motion within the acceleration limits and hold there."""
        self._target = None
        self._goal = None
        if self._q is None:
            return ArmCommand()
        # As fast as the robot may stop: a hold is not bound by the teleop's own pace.
        start = now + self.p.command_lead
        points = self._servo.stop(start, self._q, self.p.min_duration, kin.MAX_JOINT_ACCEL)
        return ArmCommand(q=points[-1][1].copy(), points=points, stamp=start)

    def _lose_robot(self, reason):
        """The robot's state is unknown (simulator or driver gone / restarted): forget it
        and disarm without a hold, which would command the old pose to a new robot."""
        self._q = self._joints_rx = self._hand = None
        self._qd = np.zeros(6)
        self._stalled = self._gripper_sent = self._gripper_asked = None   # a new robot
        self._hand_silent = self._thumb_up_since = None
        self._stream.reset()
        self._servo.reset()
        if self.status.state != DISARMED:
            self._set(DISARMED, reason)
            self.status.origin_set = False
            self._palm_ref = self._tcp_ref = self._target = self._last_reach = None
        return ArmCommand()

    def _disarm(self, reason, now):
        # A stall has already sent its hold: the arm is stopping or at rest.
        was_moving = self.status.state in (ARMED, TRACKING, HOLDING) and self._stalled is None
        self._stalled = self._hand_silent = None
        self._gripper_asked = None
        self._thumb_up_since = None           # re-arming needs a thumbs-up held anew
        self._set(DISARMED, reason)
        self.status.origin_set = False
        self._palm_ref = self._tcp_ref = self._target = self._last_reach = None
        return self._hold(now) if was_moving else ArmCommand()

    def step(self, now):
        """One control period: the command to send (possibly empty)."""
        if self._lower_accel is not None and self._q is not None:
            old, new, since = self._lower_accel
            if since is None:
                since, self._lower_accel = now, (old, new, now)
            v = self._servo.state_at(now, self._q)[1]
            ramp = (now - since) / LOWER_ACCEL_RAMP_S
            if ramp >= 1.0 or float(np.abs(v).max()) <= float(new.min()) * LOWER_ACCEL_STOP_S:
                # (the cap on speeds toward the goals stays while it holds a joint back: the
                # lag it kept, caught up with the goal's own speed on top, overran the goal)
                self._servo.max_accel, self._lower_accel = new, None
            else:
                self._servo.max_accel = old + (new - old) * ramp
        elif self._servo.speedup_accel is not None and not self._servo.cap_binding:
            self._servo.speedup_accel = None
        cmd = self._step(now)
        if cmd.input_stamp > 0 and (cmd.points is not None or cmd.gripper is not None):
            self.status.input_stamp = cmd.input_stamp
        return cmd

    def _joints_stalled(self, now):
        """No joint states for joint_timeout: the robot's pose is unknown, so nothing is
        commanded (its last trajectory ends at rest). A stall (a loaded simulator) holds and
        stays armed; joint_loss_after without states, or any stall while disarmed, forgets
        the robot. A fist or a lost hand still disarms at once."""
        if self.status.state == DISARMED:
            return self._lose_robot('no joint states for %.2f s' % self.p.joint_timeout)
        if now - self._joints_rx > self.p.joint_loss_after:
            return self._lose_robot('no joint states for %.2f s' % self.p.joint_loss_after)
        hand = self._hand
        if (hand is not None and now - self._hand_rx <= self.p.input_timeout
                and (not hand.present or hand.fist)):
            self._stalled = self._stalled or ('joint states', self._joints_rx)   # no hold
            return self._disarm(self._words['stop'] if hand.present else 'hand left the sensor', now)
        if hand is None or now - self._hand_rx > self.p.input_timeout:
            if self._hand_silent is None:
                self._hand_silent = self._hand
            if hand is None or now - self._hand_rx > self.p.disarm_after:
                self._stalled = self._stalled or ('joint states', self._joints_rx)   # no hold
                return self._disarm('no hand input for %.2f s (watchdog)' % self.p.disarm_after,
                                    now)
        if self._stalled is None or self._stalled[0] != 'joint states':
            self._stalled = ('joint states', self._joints_rx)
            # Where the robot may be when states return: wherever its last trajectory
            # goes on to until it rests, or as far as it takes to brake from the speed it
            # last reported (a robot still moving when the servo planned it at rest).
            lo, hi = self._servo.reach(self._joints_rx, self._q)
            # Its trajectories never ran a joint faster than max_joint_speed: a faster
            # report (a spike, a sprinting simulator) brakes from that speed.
            v = np.clip(self._qd, -self.p.max_joint_speed, self.p.max_joint_speed)
            brake = v * np.abs(v) / (2.0 * self.p.max_joint_accel)
            self._resume_box = (np.minimum(np.minimum(self._q, lo), self._q + brake)
                                - RESUME_TOLERANCE,
                                np.maximum(np.maximum(self._q, hi), self._q + brake)
                                + RESUME_TOLERANCE)
            self._target = self._goal = self._gripper_asked = None   # its wait starts again
            # The plan stays: a robot still braking along it when states return is planned
            # on from there, not from rest (it drops the plan itself once that has ended).
            self._set(HOLDING, 'no joint states for %.2f s: holding, disarms after %.2f s'
                      % (self.p.joint_timeout, self.p.joint_loss_after))
        return ArmCommand()

    def _step_horizon(self, now, dt):
        """The servo's horizon for this step: 1.5 times the longest step interval of the
        last STEP_WINDOW_S, between command_horizon and the longest the loop allows."""
        recent = self._step_intervals
        recent.append((now, dt))
        while recent[0][0] < now - STEP_WINDOW_S:
            recent.popleft()
        longest = max(d for _, d in recent)
        return min(max(self.p.command_horizon, 1.5 * longest), self._longest_horizon)

    def _step(self, now):
        jumped_back = self._last_step is not None and now < self._last_step - 1e-6
        dt = 0.0 if self._last_step is None else max(0.0, now - self._last_step)
        self._last_step = now
        if jumped_back:
            self._step_intervals.clear()        # stamped on a clock that is gone
            return self._lose_robot('the clock jumped back (simulation restarted?)')
        if self._longest_horizon > self.p.command_horizon:
            self._servo.horizon = self._step_horizon(now, dt)
        if self._joints_rx is not None and now - self._joints_rx > self.p.joint_timeout:
            return self._joints_stalled(now)
        if self._stalled is not None and self._stalled[0] == 'joint states':
            lo, hi = self._resume_box
            outside = np.maximum(lo - self._q, self._q - hi)
            if np.any(outside > 0):
                j = int(np.argmax(outside))
                return self._lose_robot('joint states came back at another pose (joint %d '
                                        '%.3f rad beyond where its last trajectory could '
                                        'have left it: the robot restarted or was moved): '
                                        'disarmed' % (j + 1, outside[j] + RESUME_TOLERANCE))
        if self._q is None:
            self._set(DISARMED, 'waiting for joint states')
            return ArmCommand()
        if self._off_plan(now):
            # Nothing is commanded (the robot's last trajectory ends at rest); the next plan
            # starts from the measured joints.
            self._stalled = ('joint states', self._joints_rx)
            self._disarm('the robot does not follow its commands (joint %d %.3f rad from where '
                         'they put it for %.2f s: a protective stop, a stopped controller?)'
                         % self._off_plan_seen, now)
            self._servo.reset()
            self._off_plan_since = None
            return ArmCommand()
        hand = self._hand
        if hand is None or now - self._hand_rx > self.p.input_timeout:
            if self.status.state == DISARMED:
                return ArmCommand()
            if hand is None or now - self._hand_rx > self.p.disarm_after:
                return self._disarm('no hand input for %.2f s (watchdog)'
                                    % self.p.disarm_after, now)
            if self._hand_silent is None:
                self._hand_silent = self._hand
            if self._stalled is not None:     # the hold was sent: nothing moves meanwhile
                return ArmCommand()
            # A stall: stop at once, but stay armed for a while in case input resumes.
            held = self._hold(now)
            self._stalled = ('hand input', self._hand_rx)
            self._gripper_asked = None                      # its wait starts again
            self._set(HOLDING, 'no hand input for %.2f s: holding, disarms after %.2f s '
                      '(watchdog)' % (self.p.input_timeout, self.p.disarm_after))
            return held
        if not hand.present or hand.fist:
            cmd = ArmCommand()
            if self.status.state != DISARMED:
                cmd = self._disarm(self._words['stop'] if hand.present else 'hand left the sensor',
                                   now)
            cmd.input_stamp = hand.stamp
            return cmd
        if self._rewound:
            # A new stream stamped before the old one ended (a bag played again): another
            # session, whose hand the old origin does not belong to.
            self._rewound = False
            if self.status.state != DISARMED:
                return self._disarm('the hand input began again at older stamps (a session '
                                    'played again?): show %s' % self._words['arm'], now)
        if self.status.state == DISARMED:
            # A glimpse of a thumbs-up (a hand passing through one) does not arm: it must
            # be held arm_hold_s by the hand's own capture times and by their receipt (a
            # stamp that leaps ahead is no hold; unstamped input has only its receipt).
            if hand.thumb_up and self._thumb_up_since is not None:
                since_stamp, since_rx = self._thumb_up_since
                held = self._hand_rx - since_rx
                if hand.stamp > 0 and since_stamp > 0:
                    held = min(held, hand.stamp - since_stamp)
                if held >= self.p.arm_hold_s - 1e-9:
                    self._set(ARMED, '%s; show %s to set the origin'
                              % (self._words['arm'], self._words['origin']))
                else:
                    self._set(DISARMED, 'hold the %s' % self._words['arm'])
            return ArmCommand()

        palm = np.asarray(hand.palm_mm, dtype=float)
        hand_rot = self._hand_rotation(hand)
        if self._stalled is not None:
            what, since = self._stalled
            fresh = self._hand_rx if what == 'hand input' else self._joints_rx
            # joint states given without their receipt time carry no duration
            back = '%s back' % what + (' after %.2f s' % (fresh - since) if fresh is not None else '')
            # A hand silent during a joint stall was not followed either, whichever stalled first.
            silent = self._hand_silent
            hand_stalled = what == 'hand input' or silent is not None
            self._stalled = self._hand_silent = None
            if self._palm_ref is not None:
                # After a joint-state stall alone the hand's input never stopped: the mapping
                # the operator followed stays, and the servo catches up within its limits.
                # So does a hand back within reanchor_beyond of where it fell silent: the
                # arm's lag behind it is caught up as before the stall (re-anchored on that
                # lag, the arm stayed short of the hand's place for the rest of the session).
                gap = self._resume_gap(palm)
                moved = turned = 0.0
                if silent is not None:
                    moved, turned = self._moved_while_silent(silent, palm, hand_rot)
                if hand_stalled and (moved > self.p.reanchor_beyond or turned > REANCHOR_TURN_RAD):
                    if self.p.mode == 'imitation':
                        self._skip_unseen(silent, palm, hand_rot, now)
                    else:
                        # Joystick: the hand where it is now is the dead zone's centre, and
                        # the arm stops where it can (a rate command: nothing to catch up).
                        self._set_origin(palm, hand_rot, now, reanchor=True)
                    self._set(TRACKING, back + ': origin re-anchored')
                else:
                    # The servo catches up within its limits; the mapping stays.
                    self._set(TRACKING, back + ': same origin, %.3f m to catch up' % gap)
            else:
                self._set(ARMED, back + '; show %s to set the origin' % self._words['origin'])
        if hand.rock:
            # where the arm's plan comes to rest; a held rock sets it every frame, so the
            # last frame's is where the arm stops
            self._set_origin(palm, hand_rot, now)
        cmd = ArmCommand(input_stamp=hand.stamp)
        if self._palm_ref is None:
            cmd.gripper = self._gripper_command(hand, now)
            return cmd
        palm_f = self._filter.update(palm, now)
        offset = palm_f - self._palm_ref
        reachable = self._target          # joystick: what an unreachable push falls back to
        if self.p.mode == 'imitation':
            target = self._tcp_ref + self._axes @ offset * 0.001 * self.p.scale
        else:
            target = self._joystick(offset, dt, now)
        target = np.minimum(np.maximum(target, self._lo), self._hi)
        rotation = self._tool_rotation(self._rotation_filter.update(hand_rot, now), aim=True)
        self._target = target
        cmd.gripper = self._gripper_command(hand, now)
        self.status.target = tuple(target.tolist())
        self.status.target_rotation = tuple(map(tuple, rotation.tolist()))
        q, why = self._next_goal(target, rotation, now, dt)
        if q is None:
            self.status.ik_failures += 1
            if self.p.mode != 'imitation' and reachable is not None:
                # A push out of reach does not wind the joystick's target up: pulling back
                # moves the arm at once. (None: it moves on from the arm, after a hold.)
                target = self._target = reachable
            if self.status.state != HOLDING:
                self._set(HOLDING, '%s %s' % (why, np.round(target, 3).tolist()))
                held = self._hold(now)
                self._target = target
                cmd.q, cmd.points, cmd.stamp = held.q, held.points, held.stamp
            return cmd
        if self.status.state == HOLDING:
            self._set(TRACKING, 'target reachable again')
        goal_velocity = None
        if self._goal is not None and now > self._goal[0]:
            goal_velocity = (q - self._goal[1]) / (now - self._goal[0])
        self._goal = (now, q)
        cmd.q = q
        cmd.stamp = now + self.p.command_lead
        cmd.points = self._servo.track(cmd.stamp, self._q, q, goal_velocity)
        return cmd

    def _time_to_face(self, target, before, dt):
        """Seconds until the target, moving on as it did from `before` over dt, reaches the
        first face of the box it heads for at FACE_APPROACH_MIN or faster (infinite: none)."""
        soon = math.inf
        for x, b, lo, hi in zip(target.tolist(), before.tolist(), self._lo.tolist(),
                                self._hi.tolist()):
            if x - b > FACE_APPROACH_MIN * dt:
                soon = min(soon, (hi - x) * dt / (x - b))
            elif b - x > FACE_APPROACH_MIN * dt:
                soon = min(soon, (x - lo) * dt / (b - x))
        return soon

    def _next_goal(self, target, rotation, now, dt):
        """(joint goal, None) for this period, or (None, why not). The target's IK when the
        joints reach it from the last goal within about one period at their speed limits;
        else a step toward it along the TCP's straight line from the last goal, as far as
        the joints allow (their speed, ramped by the acceleration limit): a far goal ran
        every joint at its own saturated speed, the TCP off the hand's path (under the
        table, out of the box, the tool tilted)."""
        lo, hi = self._ik_limits
        if self._goal is not None:
            seed, rate = self._goal[1].tolist(), self._goal_rate
        else:
            # After a hold, from where the arm is commanded to be (against the last goal
            # alone, the period after a hold took the other configuration).
            seed, v = (x.tolist() for x in self._servo.state_at(now, self._q))
            if not self._servo.moving:     # it has just come to rest: the servo goes on
                # from the measured joints (its rest while they are older than that)
                seed = self._servo.rest(self._q).tolist()
            rate = None
        # The target's IK follows its own of the period before (the hand moves on
        # continuously): nearest a goal that lags a fast wrist turn by half a turn, it took
        # the flipped shoulder, or the wrist's other way round.
        # Kept across holds that keep the origin (after a stall the wrist is as far behind).
        last = self._last_reach
        if last is None:
            self._reached.clear()
        q = kin.ik_nearest(kin.pose(target, rotation), seed if last is None else last[1],
                           lower=lo, upper=hi)
        if q is None:
            # the hand goes on turning out of reach: that IK says nothing of it any more
            self._last_reach = None
            return None, 'no IK solution within the joint limits for'
        speed = self._servo.max_speed.tolist()
        period = min(max(dt, 1e-3), self._servo.horizon)
        q_list = q.tolist()
        if last is not None and now - last[0] <= 3.0 * period \
                and _largest_joint_move(q_list, last[1]) >= math.pi:
            # half a turn in one period: the nearest copy within the limits went round
            return None, 'only another arm configuration reaches'
        need = _joint_time(q_list, seed, speed)
        # How fast the target's IK moves (normalised like the rate): a goal that follows it
        # closes the gap on top of that.
        self._last_reach = (now, q_list, target)
        reached = self._reached        # from the latest at least FACE_WINDOW_S ago on
        while len(reached) > 1 and now - reached[1][0] >= FACE_WINDOW_S:
            reached.popleft()
        first = reached[0] if reached else self._last_reach
        reached.append(self._last_reach)
        moving = 0.0
        if last is not None and now > last[0]:
            moving = _joint_time(q_list, last[1], speed) / (now - last[0])
        if rate is None:
            rate = _joint_time(v, [0.0] * 6, speed)
        # Normalised acceleration: the speed limit gained per second (the bottleneck joint's).
        accel = min([a / w for a, w in zip(self._servo.max_accel.tolist(), speed)])
        # Speed up within the acceleration limit, and slow down to stop at the target (a
        # goal stopped at speed is overrun by the servo's braking distance).
        rate = min(1.0, rate + accel * period,
                   moving + math.sqrt(2.0 * CATCH_UP_DECEL * accel * need))
        braking = False
        if now > first[0]:
            # Heading for a face of the box, where the clamp stops the target dead: no
            # faster than the goal can still stop there, the target's way on counted as its
            # motion over the last FACE_WINDOW_S going on (the servo, braking at its limit
            # once the goal had stopped, ran 16-78 mm past the face).
            soon = self._time_to_face(target, first[2], now - first[0])
            if soon < math.inf:
                moved = _joint_time(q_list, first[1], speed)
                most = math.sqrt(2.0 * FACE_DECEL * accel * (need + moved * soon / (now - first[0])))
                braking = most < rate
                rate = most if braking else rate
        lagging = False
        if self._goal is not None and self._servo.moving:
            # Goals each within a period can still run away from a servo bound by its
            # acceleration: while it lags, the goal moves on no faster than it does.
            sq, sv = (x.tolist() for x in self._servo.state_at(now, self._q))
            if _joint_time(seed, sq, speed) > SERVO_LAG_PERIODS * period:
                lagging = True
                rate = min(rate, _joint_time(sv, [0.0] * 6, speed) + accel * period)
        if not lagging and need <= period and (not (self._catching_up or braking)
                                               or need <= rate * period):
            # Within one period (a catch-up: within the slowed-down step): as it is.
            self._catching_up = False
            self._goal_rate = need / period
            return q, None
        self._catching_up = True
        reach = max(rate, 1e-3) * period
        # A joint a quarter turn or more behind (a wrist lagging a fast turn): the tool's
        # rotation on the way is the joints' straight line's, which turns it the hand's
        # way; the short way round, past half a turn, turned it against the hand.
        joint_turn = (_branch(q_list) == _branch(seed)
                      and _largest_joint_move(q_list, seed) >= 0.5 * math.pi)
        if not joint_turn and not _same_configuration(q_list, seed):
            # The target moved on to another branch while the arm lags on its own (past a
            # singularity): the arm's branch if it reaches the target, else a hold.
            branch = _branch(seed)
            q = kin.ik_nearest(kin.pose(target, rotation), seed, lower=lo, upper=hi,
                               accept=lambda c: _branch(c) == branch)
            if q is None or not _same_configuration(q.tolist(), seed):
                return None, 'only another arm configuration reaches'
            q_list = q.tolist()
            need = _joint_time(q_list, seed, speed)
        start = kin.fk(seed)
        p0, r0 = start[:3, 3], start[:3, :3]
        turn = kin.rotation_vector(r0.T @ rotation)
        if need <= reach:           # lagging, the target within this step: it is the goal
            self._goal_rate = need / period
            return q, None
        f, best, best_f = reach / need, None, 0.0
        q_seed = np.asarray(seed)
        for _ in range(3):
            # the position always on the straight TCP line
            if joint_turn:
                q_on = q_seed + f * (q - q_seed)
                step = kin.pose(p0 + f * (target - p0), kin.fk(q_on)[:3, :3])
                qs = kin.ik_nearest(step, q_on, lower=lo, upper=hi)
            else:
                step = kin.pose(p0 + f * (target - p0), r0 @ kin.rotation_from_vector(f * turn))
                qs = kin.ik_nearest(step, seed, lower=lo, upper=hi)
            d = math.inf if qs is None else _joint_time(qs.tolist(), seed, speed)
            if d <= reach:
                if f > best_f:
                    best, best_f, best_d = qs, f, d
                if d >= CATCH_UP_ENOUGH * reach:
                    break
                f = min(1.0, 0.99 * f * reach / max(d, 1e-12))
            elif d < 4.0 * reach:
                f *= 0.99 * reach / d
            else:
                # Past a singularity or a configuration boundary the IK moves on fast
                # or jumps: back off toward the last goal.
                f *= 0.5 if d == math.inf else min(0.5, reach / d)
        if best is None:
            return None, 'no IK solution within the joint limits on the way to'
        # A step within the window counts as the full rate (else the ramp stalls below it).
        self._goal_rate = rate if best_d >= CATCH_UP_ENOUGH * reach else best_d / period
        return best, None

    def _off_plan(self, now):
        """The measured joints have stayed off the servo's plan for OFF_PLAN_S; judged only
        while tracking or holding, on a plan not yet at rest."""
        # Joints given without their receipt time (no staleness watch) count as of now.
        seen = now if self._joints_rx is None else self._joints_rx
        # Only while it commands motion: an old hold's plan says nothing of a robot moved
        # since (by hand, another program) once the arm is re-armed.
        commanding = self.status.state in (TRACKING, HOLDING)
        planned = self._servo.planned_at(seen) if commanding else None
        if planned is None:
            self._off_plan_since = None
            return False
        off = np.abs(planned - self._q)
        # A speed limit lowered live: the robot may still lag the faster plans of before.
        speed = max(self.p.max_joint_speed, self._slower_since[0]
                    if now - self._slower_since[1] < OFF_PLAN_LAG_S + OFF_PLAN_S else 0.0)
        if float(off.max()) <= OFF_PLAN_LAG_S * speed + RESUME_TOLERANCE:
            self._off_plan_since = None
            return False
        if self._off_plan_since is None:
            self._off_plan_since = now
        j = int(np.argmax(off))
        self._off_plan_seen = (j + 1, float(off[j]), now - self._off_plan_since)
        return now - self._off_plan_since >= OFF_PLAN_S

    def _hand_rotation(self, hand):
        """The hand's rotation since the origin as a rotation vector (Leap axes), as far as
        the orientation mode follows it; computed once per new hand angles (the loop may
        run more often than messages come, and a still hand repeats them)."""
        mode = self.p.orientation
        key = (mode, hand.rotate, hand.turn, hand.swing)
        if key == self._hand_rot_key:
            return self._hand_rot
        hand_rot = self._rotation_of(hand, self._hand_rot)
        hand_rot.flags.writeable = False
        self._hand_rot_key, self._hand_rot = key, hand_rot
        return hand_rot

    def _rotation_of(self, hand, near):
        """The hand's rotation vector in the orientation mode, nearest `near`: a palm turned
        up from the rock passes pi, where the plain rotation vector flips its axis and the
        filter would sweep the tool through it."""
        mode = self.p.orientation
        if mode == 'fixed':
            return np.zeros(3)
        if mode == 'yaw':     # the turn about the vertical alone
            return kin.rotation_vector_near(ori.hand_rotation(0.0, hand.turn, 0.0), near)
        return kin.rotation_vector_near(ori.hand_rotation(hand.rotate, hand.turn, hand.swing), near)

    def _mapped_target(self, palm):
        """The TCP target the origin maps palm to (in the box)."""
        return np.minimum(np.maximum(
            self._tcp_ref + self._axes @ (palm - self._palm_ref) * 0.001 * self.p.scale,
            self._lo), self._hi)

    def _resume_gap(self, palm):
        """How far (m) the old origin would put the target from where the arm comes to rest;
        joystick mode has no such target (its origin is the dead zone's centre): infinite."""
        if self.p.mode != 'imitation':
            return math.inf
        return float(np.linalg.norm(self._mapped_target(palm)
                                    - kin.fk(self._servo.rest(self._q))[:3, 3]))

    def _moved_while_silent(self, last, palm, hand_rot):
        """(m, rad) the hand moved the target and turned the tool's target between `last`,
        its message before a silence, and palm / hand_rot now, through the old origin;
        joystick mode (its origin is the dead zone's centre): an infinite move. The arm's
        lag behind the target does not count: resuming it is what the arm was doing."""
        if self.p.mode != 'imitation':
            return math.inf, 0.0
        before = np.asarray(last.palm_mm, dtype=float)
        moved = float(np.linalg.norm(self._mapped_target(palm) - self._mapped_target(before)))
        if self.p.orientation == 'fixed':
            return moved, 0.0
        turned = kin.rotation_error(self._tool_rotation(self._rotation_of(last, hand_rot)),
                                    self._tool_rotation(hand_rot))
        return moved, float(turned)

    def _skip_unseen(self, last, palm, hand_rot, now):
        """Imitation's re-anchor: the hand at palm / hand_rot maps to where `last`, its
        message before the silence, put the tool's target, so none of the motion unseen
        meanwhile is driven, while the arm's lag behind that target is still caught up
        (mapped to where the hold came to rest, the arm stayed that lag short of the hand
        for the rest of the session). The tool's references, max_tool_turn's among them,
        stay as they are."""
        self._palm_ref = self._palm_ref + (palm - np.asarray(last.palm_mm, dtype=float))
        if self.p.orientation != 'fixed':
            # rel = R(hand) R(ref)^T: the new reference gives hand_rot the rotation last had.
            before = kin.rotation_from_vector(self._rotation_of(last, hand_rot))
            ref_t = kin.rotation_from_vector(hand_rot).T @ before @ self._hand_ref_rotation_t
            self._hand_ref_rotation_t = ref_t
            self._hand_rot_ref = kin.rotation_vector_near(ref_t.T, self._hand_rot_ref)
        self._filter.reset(palm, now)
        self._rotation_filter.reset(hand_rot, now)

    def _set_origin(self, palm, hand_rot, now, reanchor=False):
        """The hand at palm / hand_rot maps to the tool's pose where the arm comes to rest
        braked from now as tracking brakes: taken at the pose passed while it still moves
        (catching up, or a hold braking after a stall), the origin was one it ran past and
        drove back to with the hand still. A re-anchor keeps the yaw at the rock, which
        max_tool_turn is measured from (re-centred there, each stall let the tool turn
        another max_tool_turn on)."""
        self._palm_ref = palm.copy()
        q, v = self._servo.state_at(now, self._q)      # (a plan that has ended is dropped)
        if self._servo.moving:
            # Braked from now at the tracking's acceleration, every joint over the slowest
            # one's time, as the servo brakes: the plan's own rest, a hold's braked at the
            # UR10's pi rad/s^2, is one a lower max_joint_accel runs past and back to.
            t_stop = float(np.max(np.abs(v) / self._servo.max_accel))
            # (braked harder near a joint limit: the servo stops short of it)
            rest = np.minimum(np.maximum(q + v * (0.5 * t_stop), kin.JOINT_LOWER), kin.JOINT_UPPER)
            if float(np.abs(rest - q).max()) > AT_REST_RAD:
                q = rest
        tool = kin.fk(q)
        self._tcp_ref = tool[:3, 3].copy()
        self._tool_ref = tool[:3, :3].copy()
        near = (None, None)
        if reanchor:
            # The held tool's turn from the rock's yaw, taken nearest the last aimed turn
            # (clamped): at a max_tool_turn of pi, a tool held at the clamp is half a turn
            # from that yaw, and measured nearest 0 it came out on the clamp's other side.
            # Yaw mode keeps it as the turn reference; full mode measures from _yaw_ref
            # itself, nearest the turn it is handed.
            last = self._tool_near[1]
            last = 0.0 if last is None else max(-self.p.max_tool_turn,
                                                min(self.p.max_tool_turn, last[1]))
            self._turn_ref = last + math.remainder(
                kin.tilt_and_yaw(self._tool_ref)[1] - self._yaw_ref - last, _TWO_PI)
            near = (None, (None, last))
        else:
            self._yaw_ref = kin.tilt_and_yaw(self._tool_ref)[1]
            self._turn_ref = 0.0
        self._hand_rot_ref = hand_rot.copy()
        self._hand_ref_rotation_t = kin.rotation_from_vector(self._hand_rot_ref).T
        # Joystick: a hand in the dead zone holds the arm there (the plan's rest, a hold's
        # braked at pi rad/s^2, was one it ran past and back to)
        self._target = self._tcp_ref.copy()
        self._joy_still = True
        self._tool_near = near
        self._goal = self._last_reach = None
        self._filter.reset(palm, now)
        self._rotation_filter.reset(hand_rot, now)
        self.status.origin_set = True
        self._set(TRACKING, 'origin set')

    def _tool_rotation(self, hand_rot, aim=False):
        """Target tool rotation (base frame) for the filtered hand rotation vector; aim:
        it is the target from here on (the next one is taken nearest to it)."""
        mode = self.p.orientation
        if mode == 'fixed':
            return self._rotation
        # The hand's rotation since the origin, turned into the arm base's axes; nearest
        # the last one, so that a scale other than 1 sees no jump where it passes pi.
        rel = kin.rotation_from_vector(hand_rot) @ self._hand_ref_rotation_t
        near_delta, near_limit = self._tool_near
        delta = kin.rotation_vector_near(ori.map_rotation(rel, self._axes_rotation), near_delta)
        if mode == 'yaw':
            turn = self._turn_ref + float(delta[2]) * self.p.orientation_scale
            R = kin.tool_down(self._yaw_ref + max(-self.p.max_tool_turn,
                                                  min(self.p.max_tool_turn, turn)))
            near_limit = (None, turn)       # as full mode's: (no swing, the turn)
        else:
            R, near_limit = kin.limit_tool_rotation(
                kin.rotation_from_vector(delta * self.p.orientation_scale) @ self._tool_ref,
                self.p.max_tool_tilt, self._yaw_ref, self.p.max_tool_turn, near_limit)
        if aim:
            self._tool_near = (delta, near_limit)
        return R

    def _joystick(self, offset_mm, dt, now):
        n = float(np.linalg.norm(offset_mm))
        dead_zone_mm = 1000.0 * self.p.dead_zone
        if n <= dead_zone_mm:
            # Stop where the current plan comes to rest (a target ahead of the arm would
            # run it on), then stay there while the hand stays in the dead zone.
            if not self._joy_still or self._target is None:
                self._joy_still = True
                return kin.fk(self._servo.rest(self._q))[:3, 3]
            return self._target
        self._joy_still = False
        # From where the arm is commanded to be, leading it by a bounded distance: from the
        # last target alone it ran ahead of a slow arm without bound. (Not from that pose
        # alone: the servo's feed-forward of the goal's speed then runs away.) After a hold
        # (no target) it moves on from the arm, not from the origin; in an IK hold from the
        # last reachable target (pulled back toward the stopped arm, it crept along the
        # edge of the reach in holds and restarts).
        excess = offset_mm * (1.0 - dead_zone_mm / n)
        v = self._axes @ excess * 0.001 * self.p.joystick_gain
        speed = float(np.linalg.norm(v))
        if speed > self.p.max_tcp_speed:
            v *= self.p.max_tcp_speed / speed
        base = kin.fk(self._servo.state_at(now, self._q)[0])[:3, 3]
        if self.status.state == HOLDING and self._target is not None:
            base = self._target
        elif self._target is not None:
            lead = self._target - base
            d = float(np.linalg.norm(lead))
            cap = self.p.max_tcp_speed * JOYSTICK_LEAD_S
            # Pulled back only toward an arm behind it along the push: one that ran past it
            # (braking past a box face) dragged it along the face with its overrun, at 3x
            # max_tcp_speed and out of the box.
            base = self._target if d <= cap or float(lead @ v) <= 0.0 else base + lead * (cap / d)
        target = base + v * dt
        if self._target is not None:
            # (the pull-back and the push together: no more than max_tcp_speed either)
            step = target - self._target
            most = self.p.max_tcp_speed * dt
            length = float(np.linalg.norm(step))
            if length > most:
                target = self._target + step * (most / length)
        return target

    def _gripper_command(self, hand, now):
        if self.p.gripper_mode == 'binary':
            want = self.p.gripper_binary_closed if hand.pinch else 0.0
        else:
            want = min(max(hand.pinch_value, 0.0), 0.8) if hand.pinch else 0.0
        if self._gripper_sent is not None and abs(want - self._gripper_sent) < 0.01:
            self._gripper_asked = None
            return None
        # Closing or opening waits (up to gripper_wait_s) until the tool is where the hand
        # puts it: the hand closed there, and an arm still catching up (after a stall, or
        # behind a hand faster than its limits) would grasp or release short of it.
        # Changes of an already closed proportional grip go at once.
        if self._gripper_asked is None:
            self._gripper_asked = now
        toggles = self._gripper_sent is None or (want > 0.0) != (self._gripper_sent > 0.0)
        if (toggles and self._target is not None and self._q is not None
                and now - self._gripper_asked < self.p.gripper_wait_s
                and np.linalg.norm(kin.fk(self._q)[:3, 3] - self._target)
                > 0.001 * self.p.gripper_reach_mm):
            return None
        self._gripper_asked = None
        self._gripper_sent = want
        return want
