"""The gesture pilot: hand state + gesture events + navdata in, drone commands out.

Pure logic (no ROS): the node adapter feeds ``on_hand`` / ``on_gesture`` /
``on_navdata`` from its callbacks (cheap, never blocking) and a worker thread drains
the command queue with ``pop`` and runs ``watchdog``.

Gestures: ``unfold`` -> takeoff (when landed), ``fold`` -> land (when airborne),
``circle_cw`` / ``circle_ccw`` -> flip (``flip_type``) when flying with the altitude, less
FLIP_SINK_S of the sink when descending, at ``flip_min_altitude`` or above, and the circle's
radius is ``flip_min_radius`` .. FLIP_MAX_RADIUS_M:
a hand-sized circle is meant, while fingertips loop by themselves (on the real Leap
recordings: 27 fingertip loops of 4-20 mm, clapping and flapping included). Gesture
events act only when on time: a stamped event arriving more than ``max_input_age`` later
(or earlier) than the Hand stream's best-case latency (the same sender stamps both with
the frame's capture time), or, with no stamped Hand to judge by, stamped more than
``max_input_age`` off this clock, is refused; an unfold takes off, and a circle flips,
only with a fresh present hand (an unfold still engages in a short gap, see below).
hand_lost and fold always act (they hover / land: a late one still asks for the safe
thing); unknown names are warned about.

Modes:

- ``tilt`` (default): on unfold the palm position and the hand's orientation become the
  reference (back after a short loss, kept if the palm is within ``recapture_beyond`` of
  where it was lost and turned less than RECAPTURE_TURN_DEG, else re-captured where it
  is, so nothing jumps). Palm offset
  beyond ``dead_zone`` maps linearly to a command reaching 1 at ``dead_zone +
  full_scale``: away from the user (-Leap z) -> forward (linear.x), to the left
  (-Leap x) -> left (linear.y), up (+Leap y) -> climb (linear.z); turning the hand
  left about the vertical -> yaw left (angular.z: the change of the fingers' heading, so
  raising or rolling the hand, or both, turns nothing while the fingers point more than
  30 deg from vertical; nearer vertical they have none, and the axis across the palm
  gives it: there rolling the hand turns the drone). A step of more than
  MAX_HEADING_STEP_DEG between two frames (a slow camera, a stall) is read by the hand's
  own turn about the vertical between them, so a fast turn and a raise past vertical are
  told apart; within NEAR_REFERENCE_DEG of an unfold's orientation with the fingers within
  30 deg of level, then and now, the turn's half turn is read from the rotation since the
  unfold, so a hand back at such an unfold pose turns nothing whatever path it took.
  Clamped to ``max_cmd``; angular.x / y are zero, so a centred hand is the driver's
  auto-hover.
- ``paper``: the mapping of the original drone paper (its Algorithm 1, named in the
  README), quirks included. With the Leap SDK's angles
  (pitch = atan2(dir_y, -dir_z), roll = atan2(normal_x, -normal_y)), a frame whose
  pitch AND roll both exceed +25 degrees (signed, as written) captures init_x = palm z,
  init_y = palm x (mm); it re-captures on every such frame. Once captured, every frame
  sends linear.x = -(palm_z - init_x) / 3000, linear.y = -(palm_x - init_y) / 3000,
  linear.z = palm normal y (about -1 for a flat palm: that drone sinks unless
  the palm is tilted), angular.x = init_x, angular.y = init_y (raw mm: any non-zero
  value disables the driver's auto-hover; the driver clamps them), angular.z = 0.
  Nothing is sent before the first capture, nor after a ``hover`` event until the next.
  The linear ones are clamped to [-1, 1] here, as the driver would.

Safety added in both modes: hand twists are only sent while fresh navdata (no older
than ``navdata_timeout``) says the drone flies or hovers, and a takeoff only while it
says landed; stale or missing navdata -> hover (repeated every HOVER_REPEAT s) and, if
the drone was last seen airborne, land after ``land_after``; hand lost (Hand.present
false, a hand_lost event, no Hand message for ``hand_timeout``, or none since the start)
-> one zero Twist (auto-hover) at once; back within
``disarm_after`` -> steering resumes without a new unfold (tilt: with the same reference
when the palm is back within ``recapture_beyond`` of where it was lost, so a hand held
through a stall gives the command it gave; else re-captured, so nothing jumps); lost for ``disarm_after`` ->
steering is off until a new unfold (tilt) or capture pose (paper); lost for
``land_after`` -> land; Hand messages that are non-finite, out of order or late (see
teleop.input_check) are dropped, counted in ``rejected_inputs`` and do not feed the
watchdog; the clock jumping back counts as a lost hand, and input stamped before it
stopped (a session played again; unstamped input on a clock gone back alike) needs a new
unfold. Commands go through a bounded
FIFO: a twist replaces an unsent twist at the tail (the newer hand state wins, so a hand
faster than ``rate`` adds no lag); when full, the oldest twist is dropped (takeoff /
land / flip never are) and a land puts a hover in place of the unsent ones; steering
twists leave at most ``rate`` per second, a hover after them and discrete commands at once.
"""
import collections
import functools
import math
import numbers
import re
import threading
import time
from dataclasses import dataclass

from leap_teleop.control.input_check import InputStream
from leap_teleop.drone.pilot_params import PILOT_PARAMS, PilotParams  # noqa: F401 (re-exported)
from leap_teleop.vectors import cross3, norm3

FLYING_STATES = (3, 4, 7)            # flying, hovering, goto fix point
MAX_PALM_M = 1.0      # |palm| component beyond this (m) is not a tracked hand
AIRBORNE_STATES = (3, 4, 6, 7, 9)    # + taking off, looping
LANDED = 2
# Navdata still saying landed this long after a takeoff was queued: the firmware refused
# it. The node may hold a takeoff up to 5 s (~takeoff_hold) before its driver listens, and
# the drone reports one within a few seconds of getting it; a land sent to a drone that
# stayed down is harmless, a takeoff forgotten too soon is not (a fold would not land it).
TAKEOFF_CONFIRM_S = 10.0
# A flip loses up to 0.45 m from a hover (flip_min_altitude's floor); a descent carries on
# through it, so the altitude it is judged by is less this many seconds of the sink (the
# simulated drone sinking 0.7..1.9 m/s, flipped where this first allows: the hull stays
# 0.17 m or more above the floor). Sink is measured over NAVDATA_SINK_S of navdata.
FLIP_SINK_S = 0.9
NAVDATA_SINK_S = 0.25
ZERO_TWIST = (0.0,) * 6
HOVER_REPEAT = 1.0                   # s between hover commands while navdata is stale
# The recognizer reports circles up to 0.3 m (CircleRules.r_max; people's fitted 0.2 m) in
# a tracking volume under a metre: beyond 0.5 m no hand drew it.
FLIP_MAX_RADIUS_M = 0.5
# Trackers send unit normals / directions (recordings: within 1e-6); a vector off by more
# is no tracked hand, and near zero length its angles (yaw) are noise.
UNIT_TOLERANCE = 0.01
# Events that move the drone toward safety (hover, land): they act however late they come.
SAFE_EVENTS = ('hand_lost', 'hover', 'fold')
# What a sender's GestureEvent may name: a built-in gesture or event, or a class of a user's
# pose model (letters, digits, _; at most 64). The pilot acts on unfold, fold, circle_*,
# hand_lost and hover and passes over the others quietly; a name no sender sends is warned
# about.
GESTURE_NAME = re.compile(r'[A-Za-z0-9_]{1,64}')
# Back from a short loss turned this far (deg) about the vertical from where it was lost,
# the hand's reference is re-captured, as when it comes back elsewhere (the arm's 0.3 rad).
RECAPTURE_TURN_DEG = 17.0
# What a flip call returns when, the service there at last, the flip is no longer wanted.
FLIP_NOT_CALLED = 'not called'
# Fingers this near vertical (deg) have no heading: within the first, the hand's heading is
# that of the axis across its palm; from the second on, all the fingers' (sideways tracking
# jitter of 0.6 deg then moves it by 1.2 deg at most).
NEAR_VERTICAL_DEG = (10.0, 30.0)
# Fingers whose heading moved further than this (deg) since the reading before moved too
# fast to follow by continuity (300 deg/s at 5 fps, never at a Leap's rate): a turn of 95 deg
# reads like one of -85 with the fingers raised past vertical, and a raise past vertical like
# a half turn. The hand's own turn about the vertical between the two readings tells which.
MAX_HEADING_STEP_DEG = 60.0
# Within this rotation (deg) of a reference whose fingers were within LEVEL_SIN (the sine of
# their raise) of level, and level now, the half turn of the heading is read from the
# rotation since the reference, not along the path (see DronePilot._twist).
NEAR_REFERENCE_DEG = 45.0
LEVEL_SIN = 0.5
# A Hand message whose arrival time is this much before the last one's saw the clock jump
# back (two connections' callbacks reading the clock a moment apart are not one).
CLOCK_BACK_S = 0.05


@dataclass
class PilotInput:
    """What the pilot reads from a leap_teleop/Hand message (metres, Leap axes)."""
    present: bool
    palm: tuple = (0.0, 0.0, 0.0)
    normal: tuple = (0.0, -1.0, 0.0)
    direction: tuple = (0.0, 0.0, -1.0)
    stamp: float = 0.0          # header stamp, s (0 = unstamped: only order is checked)


@dataclass(frozen=True)
class Command:
    kind: str                   # twist | takeoff | land | flip
    twist: tuple = ZERO_TWIST   # (lx, ly, lz, ax, ay, az) for twist
    anim: tuple = ()            # (type, duration) for flip
    stamp: float = 0.0          # time of the input that caused it (latency accounting)
    input_stamp: float = 0.0    # capture stamp of that input (0: none, a watchdog's)


def leap_angles(normal, direction):
    """(pitch, roll, yaw) in degrees as the Leap SDK defines them."""
    pitch = math.degrees(math.atan2(direction[1], -direction[2]))
    roll = math.degrees(math.atan2(normal[0], -normal[1]))
    yaw = math.degrees(math.atan2(direction[0], -direction[2]))
    return pitch, roll, yaw


def hand_axes(normal, direction):
    """The hand's orientation (Leap axes) as the rows of the matrix whose columns are
    across the palm, the palm normal and the direction, made orthonormal; None when the
    normal lies along the direction (no orientation)."""
    d_len = norm3(direction)
    d = (direction[0] / d_len, direction[1] / d_len, direction[2] / d_len)
    c = cross3(normal, d)
    c_len = norm3(c)
    if c_len < 1e-6:
        return None
    c = (c[0] / c_len, c[1] / c_len, c[2] / c_len)
    n = cross3(d, c)
    return ((c[0], n[0], d[0]), (c[1], n[1], d[1]), (c[2], n[2], d[2]))


def _nearest_turn(angle, near, period):
    """`angle` plus the whole number of `period`s (deg) that brings it nearest `near`."""
    return angle + period * round((near - angle) / period)


def hand_heading(axes, near=None):
    """The heading (deg, as the Leap yaw counts: positive with the fingers turned to +x) of
    a hand's orientation (hand_axes): its fingers' heading, the Leap yaw, which raising the
    hand or rolling it about its fingers leaves as it is. Within NEAR_VERTICAL_DEG of
    vertical the fingers have no heading: it passes over smoothly to that of the axis
    across the palm (there rolling the hand is turning it). Fingers raised past vertical
    point backwards: their heading is taken, up to a half turn, nearest `near` (the
    reading before; None: the palm's, which has no half-turn ambiguity: from the fingers'
    own, the same pose read twice could differ by up to 75 deg), and the palm's up to a
    full turn."""
    (cx, _, dx), _, (cz, _, dz) = axes
    fingers = math.degrees(math.atan2(dx, -dz))
    across = math.degrees(math.atan2(cz, cx))
    lo, hi = (math.sin(math.radians(a)) for a in NEAR_VERTICAL_DEG)
    weight = min(1.0, max(0.0, (math.hypot(dx, dz) - lo) / (hi - lo)))
    if near is None:
        near = across
    fingers = _nearest_turn(fingers, near, 180.0)
    across = _nearest_turn(across, near, 360.0)
    # Of the blends that differ by whole turns of the fingers, the one nearest `near`: a palm
    # rolled past 90 deg puts the across axis half a turn from the fingers, where choosing
    # by the difference alone tipped either way on rounding and read a whole turn.
    return min((across + weight * (fingers - across + turn) for turn in (-360.0, 0.0, 360.0)),
               key=lambda heading: abs(heading - near))


def fingers_heading(axes):
    """The heading (deg) of a hand's fingers (hand_axes), as the Leap yaw; None when they
    are too near vertical to have one of their own (NEAR_VERTICAL_DEG)."""
    (_, _, dx), _, (_, _, dz) = axes
    if math.hypot(dx, dz) < math.sin(math.radians(NEAR_VERTICAL_DEG[1])):
        return None
    return math.degrees(math.atan2(dx, -dz))


def turn_between(before, after):
    """The turn (deg, as the Leap yaw counts) about the vertical of the rotation from hand
    orientation `before` to `after` (hand_axes): exact for a turn about the vertical
    composed with a raise, and 0 for a raise or a roll alone."""
    # rel = after . before^T: the rotation between them, in the Leap's axes
    rel = [[sum(after[i][k] * before[j][k] for k in range(3)) for j in range(3)] for i in range(3)]
    return -math.degrees(math.atan2(rel[0][2] - rel[2][0], rel[0][0] + rel[2][2]))


def rotation_deg(before, after):
    """The angle (deg) of the rotation from hand orientation `before` to `after` (hand_axes)."""
    trace = sum(after[i][k] * before[i][k] for i in range(3) for k in range(3))
    return math.degrees(math.acos(max(-1.0, min(1.0, (trace - 1.0) / 2.0))))


def turn_about_vertical(before, after):
    """How far (deg, as the Leap yaw counts) the hand turned about the vertical from
    orientation `before` to `after` (hand_axes): the change of its hand_heading."""
    start = hand_heading(before)
    return hand_heading(after, start) - start


def paper_twist(palm_mm, normal, init_x, init_y, scale=3000.0):
    """paper mode's twist (the original drone paper's mapping) from a palm (mm) and the captured reference."""
    return (-(palm_mm[2] - init_x) / scale, -(palm_mm[0] - init_y) / scale, normal[1],
            init_x, init_y, 0.0)


def shaped(offset, dead_zone, full_scale, cap=1.0):
    """0 inside the dead zone, then linear, reaching `cap` at dead_zone + full_scale."""
    excess = abs(offset) - dead_zone
    if excess <= 0.0:
        return 0.0
    return math.copysign(min(cap, excess / full_scale * cap), offset)


class CommandQueue:
    """Bounded FIFO shared by callbacks (push) and one worker (pop, wait)."""

    def __init__(self, maxsize):
        self.maxsize = maxsize
        self._items = collections.deque()
        self._cond = threading.Condition()
        self.dropped = 0

    def push(self, cmd):
        with self._cond:
            if cmd.kind == 'land':
                # Supersedes the steering not sent yet: a hover in its place, which leaves
                # at once (the land waited behind the steering's pacing).
                for i, old in enumerate(self._items):
                    if old.kind == 'twist' and old.twist != ZERO_TWIST:
                        self._items[i] = Command('twist', ZERO_TWIST, stamp=old.stamp,
                                                 input_stamp=old.input_stamp)
                        self.dropped += 1
            if cmd.kind == 'twist' and self._items and self._items[-1].kind == 'twist':
                # A newer hand state supersedes an unsent twist: latency stays one slot.
                self._items[-1] = cmd
                self.dropped += 1
                self._cond.notify()
                return
            if len(self._items) >= self.maxsize:
                for i, old in enumerate(self._items):
                    if old.kind == 'twist':
                        del self._items[i]
                        self.dropped += 1
                        break
                else:
                    if cmd.kind == 'twist':
                        self.dropped += 1
                        return
            self._items.append(cmd)
            self._cond.notify()

    def discard(self, kind):
        """Withdraw every unsent command of this kind; how many there were."""
        with self._cond:
            kept = [c for c in self._items if c.kind != kind]
            gone = len(self._items) - len(kept)
            self._items = collections.deque(kept)
            return gone

    def holds(self, kind):
        with self._cond:
            return any(c.kind == kind for c in self._items)

    def peek(self):
        with self._cond:
            return self._items[0] if self._items else None

    def popleft(self):
        with self._cond:
            return self._items.popleft() if self._items else None

    def wait(self, timeout):
        with self._cond:
            if not self._items:
                self._cond.wait(timeout)

    def wake(self):
        with self._cond:
            self._cond.notify_all()

    def __len__(self):
        return len(self._items)


class DronePilot:
    def __init__(self, config=None, warn=None):
        self.cfg = (config or PilotParams()).validate()
        self._warn = warn or (lambda key, text: None)
        self.queue = CommandQueue(self.cfg.queue_size)
        self._lock = threading.RLock()     # watchdog_at re-enters it in watchdog
        self.drone_state = None          # navdata state, None until known
        self.altitude = 0.0              # m
        self._altitudes = collections.deque()   # (time, m) of the last NAVDATA_SINK_S
        self.last_navdata_time = None
        self.navdata_lost_since = None   # set while navdata is stale (watchdog)
        self._navdata_lost_said = False  # and whether that was warned about
        self._landed_for_navdata = False
        self._last_hover = None          # when the navdata watchdog last sent a hover
        self.last_hand_time = None
        self.hand_present = False
        self.lost_since = None
        self._landed_for_loss = False
        self.engaged = False             # tilt: unfold seen, not folded since
        self._takeoff_asked = False      # an unfold asked for a takeoff; no fold or loss since
        # takeoffs queued (withdrawn ones taken off) that no navdata has shown yet, and when
        # the last went in
        self._takeoffs_unconfirmed = 0
        self._takeoff_queued_at = None
        self._stopped_at = None          # when the last fold or loss came
        self.reference = None            # tilt: (palm xyz m, hand_heading or None)
        self._last_turn = 0.0            # tilt: the last turn about the vertical (deg)
        self._fingers_before = None      # tilt: fingers_heading at that turn's reading
        self._axes_before = None         # tilt: hand_axes at that reading
        self._axes_ref = None            # tilt: hand_axes at the reference
        self._clock_went_back = False    # the watchdog saw it before the next Hand message
        self.paper_ref = None            # paper: (init_x, init_y) mm
        self._last_hand = None
        self._hand_at_loss = None        # the last hand before the latest loss
        self._last_twist_out = None      # monotonic time of the last twist published
        self._last_twist_sent = None     # and its values
        self._zero_sent = False
        # A stream silent for hand_timeout is a lost hand: back, it is judged afresh (and may
        # be a session played again). The bound keeps that above the Hand interval.
        self._stream = InputStream(self.cfg.max_input_age, self.cfg.hand_timeout)
        self.rejected_inputs = 0         # bad or late Hand messages and gesture events

    # -- inputs (callbacks: quick, never block) --------------------------------------
    def on_navdata(self, state, altd_mm, now):
        with self._lock:
            self.drone_state = int(state)
            self.altitude = float(altd_mm) / 1000.0
            alts = self._altitudes
            if alts and now < alts[-1][0]:
                alts.clear()                    # the clock jumped back
            alts.append((now, self.altitude))
            while len(alts) > 2 and now - alts[1][0] >= NAVDATA_SINK_S:
                alts.popleft()
            first = self.last_navdata_time is None
            self.last_navdata_time = now
            if self.navdata_lost_since is not None and self._navdata_lost_said:
                self._warn('navdata_back', 'navdata %s after %.2f s' % (
                    'arrived' if first else 'back', now - self.navdata_lost_since))
            self.navdata_lost_since = None
            self._navdata_lost_said = False
            self._landed_for_navdata = False
            # Only navdata that shows the drone off the ground confirms a takeoff: one made
            # before the driver acted on it still says landed. A takeoff the firmware
            # refused (landed for TAKEOFF_CONFIRM_S) is forgotten.
            at = self._takeoff_queued_at
            if self.drone_state != LANDED or (at is not None
                                              and now - at > TAKEOFF_CONFIRM_S):
                self._takeoffs_unconfirmed = 0

    def navdata_fresh(self, now):
        """Navdata arrived within navdata_timeout (and the clock did not jump back)."""
        t = self.last_navdata_time
        return t is not None and -1e-6 <= now - t <= self.cfg.navdata_timeout

    def _navdata_ok(self, now):
        """Fresh by a callback's clock reading and not declared stale meanwhile: the
        callback reads the clock before it takes the lock, so the watchdog may have found
        the navdata stale (and hovered) in between."""
        return self.navdata_lost_since is None and self.navdata_fresh(now)

    def flip_still_wanted(self, since, now):
        """A flip queued at `since` may still go: fresh navdata says flying or hovering at
        flip_min_altitude or higher, the hand is fresh, and no fold or loss came since."""
        with self._lock:
            return (self._navdata_ok(now) and self.drone_state in (3, 4)
                    and self._flip_altitude() >= self.cfg.flip_min_altitude
                    and self._hand_fresh(now)
                    and (self._stopped_at is None or self._stopped_at < since))

    def sink_rate(self):
        """How fast the drone descends (m/s, >= 0) by the navdata altitudes of the last
        NAVDATA_SINK_S (0 with fewer than two)."""
        alts = self._altitudes
        if len(alts) < 2 or alts[-1][0] - alts[0][0] <= 0.0:
            return 0.0
        return max(0.0, (alts[0][1] - alts[-1][1]) / (alts[-1][0] - alts[0][0]))

    def _flip_altitude(self):
        """The altitude a flip is judged by: the navdata's, less what a descent carries
        the drone down through the flip."""
        return self.altitude - FLIP_SINK_S * self.sink_rate()

    def takeoff_still_wanted(self, now):
        """A takeoff held back (its driver not listening yet) may still go: no fold and no
        lost hand since the unfold, and fresh navdata still says landed."""
        with self._lock:
            return (self._takeoff_asked and self._navdata_ok(now)
                    and self.drone_state == LANDED)

    def new_input_connection(self):
        """The Hand input's connection was re-made: judge its lateness afresh."""
        with self._lock:
            self._stream.reset()

    def on_hand(self, hand, now):
        """Take one PilotInput; returns why it was ignored (None if it was not)."""
        with self._lock:
            why = None
            if hand.present and not all(math.isfinite(v) for v in tuple(hand.palm)
                                        + tuple(hand.normal) + tuple(hand.direction)):
                why = 'non-finite values'
            elif hand.present and any(abs(v) > MAX_PALM_M for v in hand.palm):
                # Leap range is well under a metre: beyond that it is a tracking error,
                # and the paper mode's raw arithmetic would overflow on it.
                why = 'palm %s m from the device' % (tuple(hand.palm),)
            elif hand.present and not all(abs(math.hypot(*v) - 1.0) <= UNIT_TOLERANCE
                                          for v in (hand.normal, hand.direction)):
                why = 'palm normal / direction are not unit vectors (lengths %.3g, %.3g)' % (
                    math.hypot(*hand.normal), math.hypot(*hand.direction))
            else:
                why = self._stream.check(hand.stamp, now)
            if why:
                # Not fed to the watchdog: a stream of bad messages hovers, then lands.
                self.rejected_inputs += 1
                self._warn('hand', 'ignored a Hand message: %s' % why)
                return why
            clock_back = self._clock_went_back or (self.last_hand_time is not None
                                                   and now < self.last_hand_time - CLOCK_BACK_S)
            self._clock_went_back = False
            self.last_hand_time = now
            # Stamped before the last stream ended (a session played again), or unstamped on
            # a clock gone back (nothing else can tell): another session, a new unfold.
            rewound = self._stream.rewound or (clock_back and not hand.stamp > 0)
            if not hand.present or clock_back or rewound:
                # The hand of the old timeline is lost, whatever this message shows.
                self._lose(now)
            if rewound:
                self._disengage_after_loss(now, True)
            if not hand.present:
                return
            if not self.hand_present:
                self._disengage_after_loss(now)
                self.hand_present = True
                self.lost_since = None
                self._landed_for_loss = False
                if self.engaged and (self.reference is None or self._moved_since_loss(hand)):
                    self._capture(hand)        # none yet, or back elsewhere: steer from here
            self._last_hand = hand
            twist = self._twist(hand)
            if twist is None:
                return
            if not self._navdata_ok(now) or self.drone_state not in FLYING_STATES:
                return      # unknown or not flying: the navdata watchdog owns hovering
            self._zero_sent = all(v == 0.0 for v in twist)
            self.queue.push(Command('twist', twist, stamp=now, input_stamp=hand.stamp))

    def on_gesture(self, name, active, now, value=0.0, stamp=0.0):
        """A GestureEvent: its name, active flag, arrival time, value (for a circle,
        its radius in m) and capture stamp."""
        with self._lock:
            state = self.drone_state if self._navdata_ok(now) else None
            if not isinstance(name, str) or not GESTURE_NAME.fullmatch(name):
                self._warn('gesture_name', 'ignored gesture %r: not one a sender sends (the '
                           'pilot acts on unfold, fold, circle_cw, circle_ccw, hand_lost, hover)' % name)
                return
            why = None if name in SAFE_EVENTS else self._stream.judge_beside(stamp, now)
            if why:
                self.rejected_inputs += 1
                self._warn('gesture_' + name, 'ignored %s: %s' % (name, why))
                return
            if name == 'hand_lost':
                self._lose(now)
            elif name == 'hover':
                # A bound hover gesture, the hand still in view: stop, and steer on from
                # where the hand is next (a hand kept where it was would fly on as before).
                # Paper mode has no neutral of its own: it waits for the capture pose.
                self._lose(now)
                self._hand_at_loss = None
                self.paper_ref = None
            elif name == 'unfold':
                if self.cfg.mode == 'tilt':
                    self.engaged = True
                    if self._last_hand is not None and self.hand_present:
                        self._capture(self._last_hand)
                if state == LANDED and not self._hand_fresh(now):
                    # engaged as before (a hand back soon steers), but nothing takes off
                    # that no hand in view asks for
                    self._warn('unfold', 'unfold: no takeoff, no fresh Hand input')
                elif state == LANDED:
                    self._takeoff_asked = True
                    self._takeoffs_unconfirmed += 1
                    self._takeoff_queued_at = now
                    self.queue.push(Command('takeoff', stamp=now, input_stamp=stamp))
                elif state is None:
                    self._warn('unfold', 'unfold: no takeoff, %s' % self._no_navdata(now))
                else:
                    self._warn('unfold', 'unfold: no takeoff, the drone is not landed (state %s)'
                               % state)
            elif name == 'fold':
                self.engaged = False
                self._takeoff_asked = False
                self._stopped_at = now
                self.reference = None
                withdrawn = self._withdraw_takeoffs()
                # A takeoff sent and not yet shown by navdata flies however that navdata read.
                sent = self._takeoffs_unconfirmed > 0
                if state is None or state in AIRBORNE_STATES or sent:
                    self._takeoffs_unconfirmed = 0      # the land follows them
                    self.queue.push(Command('land', stamp=now, input_stamp=stamp))
                elif withdrawn:
                    self._warn('fold', 'fold: the unsent takeoff withdrawn')
                else:
                    self._warn('fold', 'fold: no landing, the drone is not flying (state %s)'
                               % state)
            elif name in ('circle_cw', 'circle_ccw'):
                radius = (float(value) if isinstance(value, numbers.Real)
                          and not isinstance(value, bool) else math.nan)
                if not (state in (3, 4) and self._flip_altitude() >= self.cfg.flip_min_altitude):
                    self._warn('circle', '%s: no flip (state %s, altitude %.2f m, sinking %.2f '
                               'm/s: %.2f m < %.2f m or not flying)'
                               % (name, state, self.altitude, self.sink_rate(),
                                  self._flip_altitude(), self.cfg.flip_min_altitude))
                elif not self._hand_fresh(now):
                    # as for a takeoff: no flip that no hand in view asks for
                    self._warn('circle', '%s: no flip, no fresh Hand input' % name)
                elif not self.cfg.flip_min_radius <= radius <= FLIP_MAX_RADIUS_M:   # NaN too
                    self._warn('circle_radius', '%s: no flip, radius %r m is not a hand-sized '
                               'circle (flip_min_radius %g m .. %g m)'
                               % (name, value, self.cfg.flip_min_radius, FLIP_MAX_RADIUS_M))
                else:
                    self.queue.push(Command('flip', anim=(self.cfg.flip_type,
                                                          self.cfg.flip_duration), stamp=now,
                                            input_stamp=stamp))

    def _withdraw_takeoffs(self):
        """Withdraw the unsent takeoffs; how many. Those left unconfirmed were sent."""
        gone = self.queue.discard('takeoff')
        self._takeoffs_unconfirmed = max(0, self._takeoffs_unconfirmed - gone)
        return gone

    def _hand_fresh(self, now):
        """A present hand arrived within hand_timeout (the watchdog may not have run yet)."""
        return (self.hand_present and self.last_hand_time is not None
                and now - self.last_hand_time <= self.cfg.hand_timeout)

    # -- mapping ---------------------------------------------------------------------
    def _moved_since_loss(self, hand):
        """The palm came back recapture_beyond or further from where it was lost (or
        where is not known). Nearer, the reference stays: the hand's offset is a rate
        command, so re-capturing a hand held forward through a stall would turn the
        old neutral into a command backwards."""
        lost = self._hand_at_loss
        if lost is None or math.dist(hand.palm, lost.palm) >= self.cfg.recapture_beyond:
            return True
        # Turned since: its old reference would give a yaw command nobody showed.
        before, after = (hand_axes(h.normal, h.direction) for h in (lost, hand))
        return (before is not None and after is not None
                and abs(turn_about_vertical(before, after)) > RECAPTURE_TURN_DEG)

    def _capture(self, hand):
        axes = hand_axes(hand.normal, hand.direction)
        self.reference = (tuple(hand.palm), None if axes is None else hand_heading(axes))
        self._last_turn = 0.0
        # the captured pose is the reading before the next frame's (a first step too long
        # to follow is judged from it too)
        self._axes_ref = self._axes_before = axes
        self._fingers_before = None if axes is None else fingers_heading(axes)

    def _twist(self, hand):
        cfg = self.cfg
        if cfg.mode == 'paper':
            pitch, roll, _ = leap_angles(hand.normal, hand.direction)
            palm_mm = tuple(1000.0 * v for v in hand.palm)
            if pitch > cfg.paper_angle and roll > cfg.paper_angle:
                self.paper_ref = (palm_mm[2], palm_mm[0])
            if self.paper_ref is None:
                return None
            t = paper_twist(palm_mm, hand.normal, self.paper_ref[0], self.paper_ref[1],
                            cfg.paper_scale)
            # linear clamped as the driver clamps it anyway: out of range, a driver (or
            # the sim) would warn; angular x / y only switch the auto-hover off
            return tuple(max(-1.0, min(1.0, v)) for v in t[:3]) + t[3:]
        if not self.engaged or self.reference is None:
            return None
        ref, heading_ref = self.reference
        d = [hand.palm[i] - ref[i] for i in range(3)]
        axes = hand_axes(hand.normal, hand.direction)
        if heading_ref is None and axes is not None:    # captured with no orientation
            heading_ref = hand_heading(axes)
            self.reference = (ref, heading_ref)
            self._axes_ref = axes
        # On from the last turn (a hand turned half round keeps its side, at full rate);
        # a frame without an orientation turns nothing and leaves the last turn as it was
        # (reset, the next frame read a hand turned past 90 deg a half turn off).
        dyaw = 0.0
        if axes is not None:
            near = heading_ref + self._last_turn
            fingers, before = fingers_heading(axes), self._fingers_before
            if (self._axes_ref is not None and abs(self._axes_ref[1][2]) < LEVEL_SIN
                    and abs(axes[1][2]) < LEVEL_SIN
                    and rotation_deg(self._axes_ref, axes) < NEAR_REFERENCE_DEG):
                # Near a reference of level fingers, with the fingers level, the turn is small
                # whatever path led here (rolls and raises on the way could leave the reading
                # a half turn off): its half turn is taken from the rotation. (Nearer vertical
                # the heading is the palm's, legitimately far from that rotation's turn.)
                near = heading_ref + turn_between(self._axes_ref, axes)
            elif fingers is not None and self._axes_before is not None and (
                    abs(_nearest_turn(fingers - near, 0.0, 180.0)) > MAX_HEADING_STEP_DEG
                    or (before is not None
                        and abs(_nearest_turn(fingers - before, 0.0, 360.0)) > MAX_HEADING_STEP_DEG)):
                near += turn_between(self._axes_before, axes)
            self._fingers_before, self._axes_before = fingers, axes
            dyaw = self._last_turn = hand_heading(axes, near) - heading_ref
        cap = min(abs(cfg.max_cmd), 1.0)
        return (-shaped(d[2], cfg.dead_zone, cfg.full_scale, cap),
                -shaped(d[0], cfg.dead_zone, cfg.full_scale, cap),
                shaped(d[1], cfg.z_dead_zone, cfg.z_full_scale, cap),
                0.0, 0.0,
                -shaped(dyaw, cfg.yaw_dead_zone, cfg.yaw_full_scale, cap))

    def _no_navdata(self, now):
        if self.last_navdata_time is None:
            return 'no navdata yet'
        if now < self.last_navdata_time:
            return 'no navdata since the clock jumped back'
        return 'no navdata for %.2f s' % (now - self.last_navdata_time)

    # -- watchdog ----------------------------------------------------------------------
    def _lose(self, now):
        self._takeoff_asked = False
        self._stopped_at = now
        self._withdraw_takeoffs()           # nothing takes off that no hand in view asks for
        if self.hand_present or self.lost_since is None:
            self.lost_since = now
        was_present = self.hand_present
        self.hand_present = False
        if self._last_hand is not None:
            self._hand_at_loss = self._last_hand
        self._last_hand = None
        if was_present or not self._zero_sent:
            self._zero_sent = True
            self.queue.push(Command('twist', ZERO_TWIST, stamp=now))

    def watchdog_at(self, clock):
        """The watchdog at clock() read under the lock (returned). The callbacks read the
        clock before they take the lock, so a reading taken before it could be older than
        a hand or navdata that got in between: under load, a false 'clock jumped back'
        (hover, and the reference re-captured wherever the hand was)."""
        with self._lock:
            now = clock()
            self.watchdog(now)
        return now

    def watchdog(self, now):
        """Call often (every ~20 ms): stale input -> hover; long loss -> land."""
        with self._lock:
            if self.last_hand_time is not None and now < self.last_hand_time - 1e-6:
                # The clock jumped back (a /clock publisher restarted): the hand is stale.
                self._warn('clock', 'the clock jumped back: hovering')
                # The stream is kept: the next Hand message starts a new one there, and
                # says whether its stamps went back too (another session: a new unfold).
                self.last_hand_time = None
                self._clock_went_back = True
                self.lost_since = None
                self._lose(now)
            if self.last_hand_time is None and self.lost_since is None:
                # No Hand message yet (a pilot restarted beside a flying drone, its sender
                # down or on another topic): lost from the start, so it hovers, then lands.
                self._lose(now)
            # A callback usually sees such a jump first (a Hand message comes every 10 ms):
            # times kept from the old timeline would hold the landings off for as long as
            # the jump. They start again from now.
            if self.lost_since is not None and self.lost_since > now:
                self.lost_since = now
            if self.navdata_lost_since is not None and self.navdata_lost_since > now:
                self.navdata_lost_since = now
            if self._stopped_at is not None and self._stopped_at > now:
                self._stopped_at = now
            if (self.hand_present and self.last_hand_time is not None
                    and now - self.last_hand_time > self.cfg.hand_timeout):
                # On the ground a stream that ends (a script, a take) is the normal end of
                # a session: nothing hovers, nothing to say.
                if not self._known_landed():
                    self._warn('stale', 'no Hand message for %.2f s: hovering'
                               % (now - self.last_hand_time))
                self._lose(self.last_hand_time + self.cfg.hand_timeout)
            self._disengage_after_loss(now)
            self._navdata_watchdog(now)
            if (self.lost_since is not None and not self._landed_for_loss
                    and now - self.lost_since >= self.cfg.land_after
                    and (self.drone_state in AIRBORNE_STATES
                         # navdata lost: land unless last seen landed; never seen at all
                         # (a slow start), the hover was enough, as for navdata lost
                         or (self.navdata_lost_since is not None and self.drone_state is not None
                             and not self._known_landed()))):
                self._landed_for_loss = True
                self.engaged = False
                self.reference = None
                self._warn('lost', 'hand lost for %.1f s: landing' % (now - self.lost_since))
                self.queue.push(Command('land', stamp=now))

    def _disengage_after_loss(self, now, rewound=False):
        """A hand lost for disarm_after steers only after a new unfold (tilt) or capture
        pose (paper); a shorter loss (a stalled stream) steers on from where it is, unless
        the stream came back `rewound` (stamped before it ended: a session played again)."""
        if not (self.engaged or self.paper_ref is not None) or (not rewound and (
                self.lost_since is None or now - self.lost_since < self.cfg.disarm_after)):
            return
        self.engaged = False
        self.reference = None
        self.paper_ref = None
        self._hand_at_loss = None
        until = 'a new unfold' if self.cfg.mode == 'tilt' else 'the capture pose'
        if rewound:
            self._warn('disengaged', 'the hand input began again at older stamps (a session '
                       'played again?): steering off until %s' % until)
        else:
            self._warn('disengaged', 'hand lost for %.2f s: steering off until %s'
                       % (now - self.lost_since, until))

    def _known_landed(self):
        """The last navdata said landed and no takeoff was queued after it."""
        return (self.drone_state == LANDED
                and not self._takeoffs_unconfirmed)

    def _navdata_watchdog(self, now):
        """Stale navdata: hover at once (again every HOVER_REPEAT s), land after land_after
        unless the last fresh navdata said landed (and no takeoff went out since); the state
        counts as unknown meanwhile."""
        if self.navdata_fresh(now):
            return
        if self.navdata_lost_since is None:
            self.navdata_lost_since = now
            self._last_hover = None
        # At start-up the driver's first navdata comes a moment after the pilot's first
        # tick: said only once it is navdata_timeout late, as a lost stream is.
        if not self._navdata_lost_said and (self.last_navdata_time is not None or
                                            now - self.navdata_lost_since >= self.cfg.navdata_timeout):
            self._navdata_lost_said = True
            self._warn('navdata', '%s: drone state unknown, %s' % (
                self._no_navdata(now), 'last seen landed' if self._known_landed() else 'hovering'))
        if self._known_landed() or self._landed_for_navdata:
            return
        if self._last_hover is None or not 0.0 <= now - self._last_hover < HOVER_REPEAT:
            self._last_hover = now
            self._zero_sent = True
            self.queue.push(Command('twist', ZERO_TWIST, stamp=now))
        if (self.drone_state is not None
                and now - self.navdata_lost_since >= self.cfg.land_after):
            self._landed_for_navdata = True
            self.engaged = False
            self.reference = None
            self._warn('navdata_land', 'no navdata for %.1f s: landing'
                       % (now - self.navdata_lost_since))
            self.queue.push(Command('land', stamp=now))

    # -- output ------------------------------------------------------------------------
    def pop(self, mono_now):
        """The next command due at monotonic time mono_now, or (None, seconds to wait)."""
        cmd = self.queue.peek()
        if cmd is None:
            return None, None
        # A hover after steering or before a land is not paced (at a low rate it waited up
        # to 1/rate s); hovers after hovers are.
        stopping = cmd.kind == 'twist' and cmd.twist == ZERO_TWIST and (
            self._last_twist_sent != ZERO_TWIST or self.queue.holds('land'))
        if cmd.kind == 'twist' and not stopping and self._last_twist_out is not None:
            wait = self._last_twist_out + 1.0 / self.cfg.rate - mono_now
            if wait > 0:
                return None, wait
        cmd = self.queue.popleft()
        if cmd is not None and cmd.kind == 'twist':
            self._last_twist_out, self._last_twist_sent = mono_now, cmd.twist
        return cmd, 0.0


class PilotWorker:
    """The one thread that acts: runs the watchdog and drains the queue. Twists, takeoff
    and land go out through `send(cmd)` (publishing, never blocking); a flip goes to
    `flip_call` (a ServiceCall: its own thread and timeout), so a peer that never answers
    cannot stop the watchdog. `send_held()` (when given) runs first in every step: a
    takeoff or land the sender holds until its driver listens. Any exception in a step is
    caught, counted and answered with the safe action: hover at once, land once the fault
    has lasted land_after."""

    def __init__(self, pilot, send, flip_call, clock, warn=None, info=None,
                 mono=None, extra=None, send_held=None):
        self.pilot = pilot
        self.send = send
        self.send_held = send_held              # a held takeoff / land, each step
        self.flip_call = flip_call
        self.clock = clock                      # the watchdog's clock (ROS time)
        self.mono = mono or time.monotonic      # the queue's pacing clock
        self.warn = warn or (lambda key, text: None)
        self.info = info or (lambda text: None)
        self.extra = extra                      # called every step (diagnostics)
        self.errors = 0
        self.flips_not_called = 0
        self.last_error = ''
        self.fault_since = None
        self._fault_landed = False

    def step(self):
        """One pass; returns how long to wait for the next (s, at most 0.02)."""
        now = None
        try:
            if self.send_held is not None:
                self.send_held()        # first: a faulty watchdog must not keep a land back
            now = self.pilot.watchdog_at(self.clock)
            self._poll_flip()
            if self.extra is not None:
                self.extra()
            cmd, wait = self.pilot.pop(self.mono())
            if cmd is not None:
                if cmd.kind == 'flip':
                    wanted = functools.partial(self._flip_wanted, cmd.stamp)
                    if not self.flip_call.submit(*cmd.anim, wanted):
                        self.warn('flip_busy', 'no flip: the previous flight animation call '
                                  'has not returned')
                else:
                    self.send(cmd)
            self.fault_since, self._fault_landed = None, False
            return 0.0 if cmd is not None else min(wait or 0.02, 0.02)
        except Exception as e:          # the worker must outlive any fault
            self._fault(self.clock() if now is None else now, e)
            return 0.02

    def run(self, stopped):
        """Step until stopped(): between steps, a twist waiting for its slot sleeps out
        the pacing; otherwise the wait ends early when a command is queued. Then one zero
        twist: the driver holds the last command, and a pilot that ends must leave the drone
        hovering, not flying its last tilt."""
        while not stopped():
            wait = self.step()
            if wait and len(self.pilot.queue):
                time.sleep(wait)
            elif wait:
                self.pilot.queue.wait(wait)
        try:
            self.send(Command('twist', ZERO_TWIST))
        except Exception as e:          # a topic rospy has closed already: nothing to tell
            self.warn('exit_hover', 'no hover sent on the way out: %s' % e)

    def diagnostics(self, now):
        """(level 'ok' | 'warn' | 'error', summary, [(key, value)]) of the pilot and this
        worker, for a diagnostics report."""
        pl = self.pilot
        lost = pl.lost_since is not None
        stale = pl.navdata_lost_since is not None
        summary = 'hand %s, drone state %s' % ('lost' if lost else 'tracked'
                                               if pl.hand_present else 'not seen yet',
                                               pl.drone_state)
        if self.fault_since is not None:
            level, summary = 'error', 'worker fault: %s (hovering)' % self.last_error
        elif stale:
            level = 'warn' if pl.drone_state != LANDED else 'ok'
            summary = ('no navdata for %.1f s (%s): hovering, no takeoff'
                       % (now - (pl.last_navdata_time or pl.navdata_lost_since), summary))
        else:
            level = 'warn' if lost and pl.drone_state in AIRBORNE_STATES else 'ok'
        values = [('navdata', 'stale' if stale else 'fresh'), ('worker faults', self.errors)]
        counts = dict(self.flip_call.counts, ok=self.flip_call.counts['ok'] - self.flips_not_called)
        values += [('flip calls %s' % outcome, n) for outcome, n in counts.items()]
        values += [('flips not called (landed, folded or hand lost meanwhile)',
                    self.flips_not_called)]
        values += [('rejected inputs', pl.rejected_inputs),
                   ('twists superseded or dropped', pl.queue.dropped)]
        return level, summary, values

    def _flip_wanted(self, since):
        """Asked on the flip call's thread once the service is there."""
        return self.pilot.flip_still_wanted(since, self.clock())

    def _poll_flip(self):
        outcome = self.flip_call.poll()
        if outcome is None:
            return
        kind, value = outcome
        if kind == 'ok' and value == FLIP_NOT_CALLED:     # a safety refusal, not a fault
            self.flips_not_called += 1
            self.info('flight animation not called: the drone is no longer flying high '
                      'enough, was told to land or lost the hand while its service was awaited')
        elif kind == 'ok':
            self.info('flight animation -> %s' % (value,))
        elif kind == 'timeout':
            self.warn('flip_timeout', 'flight animation call timed out after %.2f s (still '
                      'hovering / flying on)' % value)
        else:
            self.warn('flip_failed', 'flight animation call failed: %s' % (value,))

    def _fault(self, now, e):
        self.errors += 1
        self.last_error = '%s: %s' % (type(e).__name__, e)
        if self.fault_since is None or now < self.fault_since:
            self.fault_since = now
        self.warn('worker', 'pilot worker fault (%s): hovering' % self.last_error)
        try:
            self.send(Command('twist', ZERO_TWIST, stamp=now))
            if (not self._fault_landed
                    and now - self.fault_since >= self.pilot.cfg.land_after):
                self._fault_landed = True
                self.warn('worker_land', 'pilot worker faulty for %.1f s: landing'
                          % (now - self.fault_since))
                self.send(Command('land', stamp=now))
        except Exception as e2:
            self.warn('worker_send', 'pilot worker could not send the safe action: %s' % e2)
