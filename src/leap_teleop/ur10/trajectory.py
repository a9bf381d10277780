"""Joint trajectory following the way ros_control's JointTrajectoryController does it.

A command is a list of points (time_from_start, positions[, velocities[,
accelerations]]). It replaces whatever was being followed: the new trajectory starts
from the current *desired* state (position, velocity, acceleration) at the command's
start time and reaches each point at its time_from_start. As in the JTC, segments between
points with positions only are linear, with positions and velocities cubic (Hermite),
with accelerations too quintic, so a trajectory whose first point carries a velocity
continues the motion without a jump in velocity. Unlike a bare JTC, segments too fast for
the joint speed limits are stretched in time (and every later point shifted by the same
amount), so the desired velocity never exceeds the limits; a quintic that does not fit
them in its time is followed as the cubic through the same positions and velocities, and
never strays past that cubic's reach (accelerations beyond max_accel refuse the command);
neither swings past a joint limit (it stays there, at rest, while its path is beyond).
A command that starts later keeps the current trajectory until then, as in the JTC. After
the last point the desired state holds it.

max_accel bounds only the accelerations points give. At a position-only point the desired
velocity steps (the JTC's linear interpolation), and a cubic is as sharp as its timing: a
simulated joint takes such a step within one physics step (wrist_3 reversing at 3 rad/s:
1440 rad/s^2 at 240 Hz), within its speed limit.
"""
import bisect
import math
from dataclasses import dataclass

import numpy as np


class TrajectoryError(ValueError):
    """A command that cannot be followed (the caller keeps the old trajectory)."""


def _hermite(q0, q1, v0, v1, T, s):
    """Position, velocity, acceleration at s in [0, 1] of a cubic Hermite of duration T."""
    s2, s3 = s * s, s * s * s
    h00, h10, h01, h11 = 2 * s3 - 3 * s2 + 1, s3 - 2 * s2 + s, -2 * s3 + 3 * s2, s3 - s2
    d00, d10, d01, d11 = 6 * s2 - 6 * s, 3 * s2 - 4 * s + 1, -6 * s2 + 6 * s, 3 * s2 - 2 * s
    e00, e10, e01, e11 = 12 * s - 6, 6 * s - 4, -12 * s + 6, 6 * s - 2
    if s.__class__ is float and T > 0 and q0.ndim == 1:
        # One instant (the simulator samples every physics step): joint by joint in plain
        # floats, the arithmetic below in its order, without numpy's per-call cost.
        h10, h11, d10, d11, e10, e11 = h10 * T, h11 * T, d10 * T, d11 * T, e10 * T, e11 * T
        TT = T * T
        q, v, a = [], [], []
        for x0, x1, u0, u1 in zip(q0.tolist(), q1.tolist(), v0.tolist(), v1.tolist()):
            q.append(h00 * x0 + h10 * u0 + h01 * x1 + h11 * u1)
            v.append((d00 * x0 + d10 * u0 + d01 * x1 + d11 * u1) / T)
            a.append((e00 * x0 + e10 * u0 + e01 * x1 + e11 * u1) / TT)
        return np.array(q), np.array(v), np.array(a)
    q = h00 * q0 + h10 * T * v0 + h01 * q1 + h11 * T * v1
    v = (d00 * q0 + d10 * T * v0 + d01 * q1 + d11 * T * v1) / T
    a = (e00 * q0 + e10 * T * v0 + e01 * q1 + e11 * T * v1) / (T * T)
    return q, v, a


def _quintic_weights(s):
    """The quintic's basis at s in [0, 1]: the weights of (q1 - q0, T v0, T v1, T^2 a0,
    T^2 a1) in its position less q0, of (dq / T, v0, v1, T a0, T a1) in its velocity and of
    (dq / T^2, v0 / T, v1 / T, a0, a1) in its acceleration."""
    s2 = s * s
    s3 = s2 * s
    s4, s5 = s3 * s, s3 * s2
    return ((10 * s3 - 15 * s4 + 6 * s5, s - 6 * s3 + 8 * s4 - 3 * s5, -4 * s3 + 7 * s4 - 3 * s5,
             0.5 * s2 - 1.5 * s3 + 1.5 * s4 - 0.5 * s5, 0.5 * s3 - s4 + 0.5 * s5),
            (30 * s2 - 60 * s3 + 30 * s4, 1 - 18 * s2 + 32 * s3 - 15 * s4,
             -12 * s2 + 28 * s3 - 15 * s4, s - 4.5 * s2 + 6 * s3 - 2.5 * s4,
             1.5 * s2 - 4 * s3 + 2.5 * s4),
            (60 * s - 180 * s2 + 120 * s3, -36 * s + 96 * s2 - 60 * s3, -24 * s + 84 * s2 - 60 * s3,
             1 - 9 * s + 18 * s2 - 10 * s3, 3 * s - 12 * s2 + 10 * s3))


def _quintic(q0, q1, v0, v1, a0, a1, T, s, lo, hi):
    """Position, velocity, acceleration at s in [0, 1] of the quintic of duration T > 0
    matching position, velocity and acceleration at both ends; a joint whose position
    falls outside [lo, hi] stays at that bound, at rest."""
    (p1, p2, p3, p4, p5), (w1, w2, w3, w4, w5), (e1, e2, e3, e4, e5) = _quintic_weights(s)
    TT = T * T
    if s.__class__ is float and q0.ndim == 1:
        # One instant (the simulator samples every physics step): joint by joint in plain
        # floats, the arithmetic below in its order, without numpy's per-call cost.
        q, v, a = [], [], []
        for x0, x1, u0, u1, b0, b1, low, high in zip(
                q0.tolist(), q1.tolist(), v0.tolist(), v1.tolist(), a0.tolist(), a1.tolist(),
                lo.tolist(), hi.tolist()):
            d = x1 - x0
            x = x0 + (p1 * d + T * (p2 * u0 + p3 * u1) + TT * (p4 * b0 + p5 * b1))
            if low <= x <= high:
                q.append(x)
                v.append(w1 * d / T + (w2 * u0 + w3 * u1) + T * (w4 * b0 + w5 * b1))
                a.append(e1 * d / TT + (e2 * u0 + e3 * u1) / T + (e4 * b0 + e5 * b1))
            else:
                q.append(low if x < low else high)
                v.append(0.0)
                a.append(0.0)
        return np.array(q), np.array(v), np.array(a)
    d = q1 - q0
    q = q0 + (p1 * d + T * (p2 * v0 + p3 * v1) + TT * (p4 * a0 + p5 * a1))
    v = w1 * d / T + (w2 * v0 + w3 * v1) + T * (w4 * a0 + w5 * a1)
    a = e1 * d / TT + (e2 * v0 + e3 * v1) / T + (e4 * a0 + e5 * a1)
    inside = (q >= lo) & (q <= hi)
    return (np.minimum(np.maximum(q, lo), hi), np.where(inside, v, 0.0),
            np.where(inside, a, 0.0))


def _reach(seg):
    """Per joint, the range (lo, hi) a quintic segment may cover: its end positions widened
    by how far the cubic through the same ends and velocities can carry past them (its
    velocity weights s (1 - s)^2 and s^2 (1 - s) are at most 4/27), within the joint limits
    (seg[8]); or the range it was given (seg[9], a piece cut from a longer one keeps that
    one's). Accelerations may shape the path inside it, never push it out. Found when
    needed: a command may carry 10000 quintics."""
    if seg[9] is not None:
        return seg[9]
    t0, t1, q0, q1, v0, v1 = seg[:6]
    spread = (4.0 / 27.0) * (t1 - t0) * (np.abs(v0) + np.abs(v1))
    lower, upper = seg[8]
    return (np.maximum(np.minimum(q0, q1) - spread, lower),
            np.minimum(np.maximum(q0, q1) + spread, upper))


def _state(seg, t):
    t0, t1, q0, q1, v0, v1, a0, a1 = seg[:8]
    T = t1 - t0
    s = min(max((t - t0) / T, 0.0), 1.0) if T > 0 else 1.0
    if v0 is None:
        return q0 + (q1 - q0) * s, (q1 - q0) / T if T > 0 else np.zeros_like(q0), \
            np.zeros_like(q0)
    if a0 is None:
        q, v, a = _hermite(q0, q1, v0, v1, T, s)
        if seg[8] is not None:
            # Its swing may carry past a joint limit though both ends are inside (3.75 rad
            # for the elbow's pi): there it stays at the limit, at rest, as a quintic does.
            lo, hi = seg[8]
            inside = (q >= lo) & (q <= hi)
            if not inside.all():
                return (np.minimum(np.maximum(q, lo), hi), np.where(inside, v, 0.0),
                        np.where(inside, a, 0.0))
        return q, v, a
    return _quintic(q0, q1, v0, v1, a0, a1, T, s, *_reach(seg))


_SAMPLES = np.linspace(0.0, 1.0, 21)
# The quintic's velocity weights at _SAMPLES[1:], one row per sample: its velocities there
# are one product with (dq / T, v0, v1, T a0, T a1).
_QUINTIC_VELOCITY = np.array([_quintic_weights(float(s))[1] for s in _SAMPLES[1:]])


def _hermite_peak(q0, q1, v0, v1, T):
    """Per-joint max |v| over s in (0, 1] of a cubic Hermite: its velocity is the
    quadratic A s^2 + B s + v0, so the end and the vertex are the only candidates."""
    if T > 0 and q0.ndim == 1:
        # The simulator runs this per command: joint by joint in plain floats, the
        # arithmetic below in its order, without numpy's per-call cost.
        peaks = []
        for x0, x1, u0, u1 in zip(q0.tolist(), q1.tolist(), v0.tolist(), v1.tolist()):
            d = (x1 - x0) / T
            A = 3 * u0 + 3 * u1 - 6 * d
            peak = abs(u1)
            if abs(A) > 1e-12:
                B = 6 * d - 4 * u0 - 2 * u1
                s = -B / (2 * A)
                if 0.0 < s < 1.0:
                    vs = abs((A * s + B) * s + u0)
                    if vs > peak:
                        peak = vs
            peaks.append(peak)
        return np.array(peaks)
    d = (q1 - q0) / T
    A = 3 * v0 + 3 * v1 - 6 * d
    B = 6 * d - 4 * v0 - 2 * v1
    peak = np.abs(v1)
    # The vertex where A is not ~0.
    s = np.divide(-B, 2 * A, out=np.full_like(A, -1.0), where=np.abs(A) > 1e-12)
    inside = (s > 0.0) & (s < 1.0)
    if inside.any():
        vs = (A * s + B) * s + v0
        peak = np.where(inside, np.maximum(peak, np.abs(vs)), peak)
    return peak


def _peak_ratio(seg, vmax):
    """max over joints and time of |v| / vmax for a segment (its start excluded: that
    is the current state's velocity, whatever a retiming does)."""
    t0, t1, q0, q1, v0, v1, a0 = seg[:7]
    T = t1 - t0
    if v0 is None:
        return float((np.abs(q1 - q0) / (T * vmax)).max()) if T > 0 else math.inf
    if T <= 0:
        return math.inf
    if a0 is None:
        return float((_hermite_peak(q0, q1, v0, v1, T) / vmax).max())
    # Sampled (without the clamp to its reach, which only ever slows it), in one product.
    # The terms go through floats: copying arrays into one lets go of the GIL, and getting
    # it back from a busy subscriber thread cost ~0.2 ms a point, 2 s on 10000.
    terms = np.array(((q1 - q0) / T).tolist() + v0.tolist() + v1.tolist()
                     + (T * a0).tolist() + (T * seg[7]).tolist()).reshape(5, -1)
    return float((np.abs(_QUINTIC_VELOCITY @ terms) / vmax).max())


def _retimed(seg, T):
    t0 = seg[0]
    return (t0, t0 + T) + tuple(seg[2:])


def _fits(seg, T, vmax):
    return _peak_ratio(_retimed(seg, T), vmax) <= 1.0 + 1e-9


def _stretched(seg, T, vmax):
    """A duration longer than T (where the segment is too fast), within 10 % of the
    shortest in which it keeps every speed limit: doubling, then halving the gap in ratio.
    About 10 tries where growing by 10 % a try took 48 (a 10,000-point command held the
    physics 5 s)."""
    lo, hi = T, 2.0 * T
    for _ in range(40):                   # bounded: a start above the limit never fits
        if _fits(seg, hi, vmax):
            break
        lo, hi = hi, 2.0 * hi
    while hi > 1.1 * lo:
        mid = math.sqrt(lo * hi)
        if _fits(seg, mid, vmax):
            hi = mid
        else:
            lo = mid
    return hi


@dataclass(frozen=True)
class Plan:
    """A checked command (TrajectoryFollower.plan): its points [(time_from_start, positions,
    velocities|None, accelerations|None)], the segment into each point from the one before
    (segments[0] is None: that one starts from the arm's state), timed from the start, the
    time each point is reached (ends) and the accelerations each point is followed with
    (accels: None where none or let go)."""
    points: list
    segments: list
    ends: list
    accels: list


class TrajectoryFollower:
    """Desired joint state over time for n joints with per-joint speed limits; optional
    joint limits, acceleration bounds for the points (max_accel) and joint names (for
    the errors)."""

    def __init__(self, q0, max_speed, lower=None, upper=None, max_accel=None, names=None):
        self.q = np.array(q0, dtype=float)
        self.n = len(self.q)
        self.vmax = np.broadcast_to(np.asarray(max_speed, dtype=float), (self.n,)).copy()
        if (lower is None) != (upper is None):
            raise ValueError('joint limits: give both lower and upper, or neither')
        self.lower = None if lower is None else np.asarray(lower, dtype=float)
        self.upper = None if upper is None else np.asarray(upper, dtype=float)
        self._limits = None if lower is None else (self.lower - 1e-9, self.upper + 1e-9)
        self._reach_limits = (np.full(self.n, -math.inf), np.full(self.n, math.inf)) \
            if lower is None else (self.lower, self.upper)
        self.max_accel = None if max_accel is None else np.broadcast_to(
            np.asarray(max_accel, dtype=float), (self.n,)).copy()
        self.names = list(names) if names is not None else ['joint %d' % j for j in range(self.n)]
        self.qd = np.zeros(self.n)
        self.qdd = np.zeros(self.n)
        # (t0, t1, q0, q1, v0|None, v1|None, a0|None, a1|None, joint limits|None,
        # reach|None): the limits bound a cubic's or a quintic's positions, the reach a
        # quintic's (_reach)
        self.segments = []
        self.end_time = -math.inf

    def hold(self, q=None):
        """Drop the trajectory and hold q (default: the current desired position)."""
        if q is not None:
            self.q = np.array(q, dtype=float)
        self.qd = np.zeros(self.n)
        self.qdd = np.zeros(self.n)
        self.segments = []
        self.end_time = -math.inf

    @property
    def active(self):
        return bool(self.segments)

    def _vector(self, value, k, what):
        if value is None or not len(value):
            return None
        value = np.asarray(value, dtype=float)
        if value.shape != (self.n,) or not np.isfinite(value).all():
            raise TrajectoryError('point %d: %s must be %d finite numbers' % (k, what, self.n))
        return value

    def _accelerations(self, value, k):
        """Point k's accelerations (None: none), or TrajectoryError naming the first joint
        whose acceleration is beyond max_accel (one test covers NaN too)."""
        if self.max_accel is None or value is None or not len(value):
            return self._vector(value, k, 'accelerations')
        value = np.asarray(value, dtype=float)
        if value.shape == (self.n,) and (np.abs(value) <= self.max_accel).all():
            return value
        value = self._vector(value, k, 'accelerations')        # the wrong size or NaN
        j = int(np.argmax(np.abs(value) > self.max_accel))
        raise TrajectoryError('point %d: %s acceleration %.6g rad/s^2 is beyond the %.3g '
                              'rad/s^2 it can follow' % (k, self.names[j], value[j],
                                                         self.max_accel[j]))

    def _cut(self, t):
        """The segments followed until t (the one under way then cut there) and the desired
        (q, qd, qdd) at t: at rest once they are over."""
        kept = []
        for seg in self.segments:
            t0, t1 = seg[0], seg[1]
            if t0 < t < t1:
                q, v, a = _state(seg, t)
                kept.append((t0, t, seg[2], q, seg[4], None if seg[5] is None else v,
                             seg[6], None if seg[7] is None else a, seg[8],
                             None if seg[6] is None else _reach(seg)))
                return kept, (q.copy(), v.copy(), a.copy())
            if t <= t0:
                if t == t0 and kept and kept[-1][1] == t0:     # under way through t
                    return kept, tuple(x.copy() for x in _state(seg, t0))
                break
            kept.append(seg)
        q = kept[-1][3] if kept else self.q
        return kept, (q.copy(), np.zeros(self.n), np.zeros(self.n))

    def plan(self, points):
        """Check a command's points and time every segment from its second point on: what
        does not depend on the state the arm will be in when it takes the command. Reads
        only what never changes, so it may run beside command() and sample() (the
        simulator plans in the subscriber thread, outside its physics lock). points:
        [(time_from_start, positions, velocities|None[, accelerations])]. TrajectoryError
        on a bad command."""
        if not points:
            raise TrajectoryError('empty trajectory (no points)')
        parsed = []
        last_t = -math.inf
        for k, point in enumerate(points):
            tfs, pos, vel = point[:3]
            acc = point[3] if len(point) > 3 else None
            tfs = float(tfs)
            pos = np.asarray(pos, dtype=float)
            if not math.isfinite(tfs) or tfs < 0:
                raise TrajectoryError('point %d: bad time_from_start %r' % (k, tfs))
            if tfs < last_t:
                raise TrajectoryError('point %d: time_from_start goes backwards' % k)
            last_t = tfs
            if pos.shape != (self.n,) or not np.isfinite(pos).all():
                raise TrajectoryError('point %d: positions must be %d finite numbers' % (k, self.n))
            if self._limits is not None and ((pos < self._limits[0]) | (pos > self._limits[1])).any():
                raise TrajectoryError('point %d: positions outside the joint limits' % k)
            vel = self._vector(vel, k, 'velocities')
            if vel is not None:
                vel = np.minimum(np.maximum(vel, -self.vmax), self.vmax)    # np.clip's values
            acc = self._accelerations(acc, k) if vel is not None else None
            parsed.append((tfs, pos, vel, acc))
        # Segment k (point k - 1 -> k) in time from the start, assuming point 0 keeps its
        # accelerations; command() checks that assumption and shifts these in time.
        segments, ends, accels = [None], [parsed[0][0]], [parsed[0][3]]
        shift = 0.0
        for k in range(1, len(parsed)):
            _, q_prev, v_prev, _ = parsed[k - 1]
            seg, t1, shift, acc = self._segment(
                ends[-1], q_prev, self._zeros_if_none(v_prev), self._zeros_if_none(accels[-1]),
                parsed[k], 0.0, shift)
            segments.append(seg)
            ends.append(t1)
            accels.append(acc)
        return Plan(parsed, segments, ends, accels)

    def _zeros_if_none(self, value):
        return np.zeros(self.n) if value is None else value

    def _segment(self, t_prev, q_prev, v_prev, a_prev, point, start, shift):
        """The segment from the state (t_prev, q_prev, v_prev, a_prev) to a parsed point
        due at start + its time_from_start + shift: (segment, its end, the shift after it,
        the point's accelerations as followed: None where it has none or they were let go)."""
        tfs, pos, vel, acc = point
        t1 = max(start + tfs + shift, t_prev)
        v0 = None if vel is None else v_prev
        a0 = None if acc is None else a_prev
        seg = (t_prev, t1, q_prev, pos, v0, vel, a0, acc,
               None if vel is None else self._reach_limits, None)
        T = t1 - t_prev
        if vel is None and (q_prev == pos).all():
            ratio = 0.0
        else:
            ratio = _peak_ratio(seg, self.vmax)
        if ratio > 1.0 + 1e-9 and acc is not None:   # float noise of a plan at the limits
            # Accelerations the speed limits cannot follow in this time (stretching it
            # only widens their swing): the cubic through the same points instead.
            acc = None
            seg = seg[:6] + (None, None, seg[8], None)
            ratio = _peak_ratio(seg, self.vmax)
        if ratio > 1.0:
            # Stretch until the segment respects every speed limit.
            if vel is None:
                T_new = float(np.max(np.abs(pos - q_prev) / self.vmax))
            else:
                T_new = _stretched(seg, max(T, 1e-3), self.vmax)
            shift += T_new - T
            seg = _retimed(seg, T_new)
            t1 = t_prev + T_new
        return seg, t1, shift, acc

    def command(self, now, points, start_time=None):
        """Replace the trajectory from its start on (until then the current one goes on).
        points: a Plan from plan(), or the points plan() takes. Raises TrajectoryError (and
        keeps the old trajectory) on a bad command. Returns the time at which the last
        point will be reached."""
        plan = points if isinstance(points, Plan) else self.plan(points)
        # None alone means now: a start that is 0 or less is a time like any other (a
        # past stamp on a cell younger than its age played in full, later was refused).
        start = now if start_time is None else float(start_time)
        # Points already in the past are dropped, as the JTC does.
        first = bisect.bisect_left(plan.points, now, key=lambda pt: start + pt[0])
        if first == len(plan.points):
            raise TrajectoryError('trajectory ends in the past')
        self.sample(now)   # the desired state we start from
        t_prev = max(now, start)
        if t_prev > now:
            kept, (q_prev, v_prev, a_prev) = self._cut(t_prev)
            if not kept:                  # nothing under way: hold at rest until the start
                self.qd, self.qdd = np.zeros(self.n), np.zeros(self.n)
        else:
            kept = []
            q_prev, v_prev, a_prev = self.q.copy(), self.qd.copy(), self.qdd.copy()
        if self.max_accel is not None:
            a_prev = np.minimum(np.maximum(a_prev, -self.max_accel), self.max_accel)
        # From the current state up to the first point the plan starts from alike (it
        # assumed a point's accelerations as this state's segments follow them), then the
        # plan's segments, shifted to this start.
        shift = 0.0
        segments = []
        for k in range(first, len(plan.points)):
            seg, t_prev, shift, acc = self._segment(t_prev, q_prev, v_prev, a_prev,
                                                    plan.points[k], start, shift)
            segments.append(seg)
            _, q_prev, vel, _ = plan.points[k]
            v_prev, a_prev = self._zeros_if_none(vel), self._zeros_if_none(acc)
            if k + 1 < len(plan.points) and (acc is None) == (plan.accels[k] is None):
                offset = t_prev - plan.ends[k]
                segments.extend((s[0] + offset, s[1] + offset) + s[2:]
                                for s in plan.segments[k + 1:])
                t_prev = plan.ends[-1] + offset
                break
        self.segments = kept + segments
        self.end_time = t_prev
        return t_prev

    def sample(self, t):
        """Advance to time t; returns (q_desired, qd_desired)."""
        while self.segments:
            seg = self.segments[0]
            t0, t1 = seg[0], seg[1]
            if t < t0:
                return self.q, self.qd
            if t >= t1:
                self.segments.pop(0)
                self.q = seg[3].copy()
                # at rest after the last point, and until a later start
                rest = not self.segments or self.segments[0][0] > t1
                self.qd = np.zeros(self.n) if (seg[5] is None or rest) else seg[5].copy()
                self.qdd = np.zeros(self.n) if (seg[7] is None or rest) else seg[7].copy()
                continue
            self.q, self.qd, self.qdd = _state(seg, t)
            return self.q, self.qd
        self.qd = np.zeros(self.n)
        self.qdd = np.zeros(self.n)
        return self.q, self.qd
