"""Joint trajectory following the way ros_control's JointTrajectoryController does it.

A command is a list of points (time_from_start, positions[, velocities[,
accelerations]]). It replaces whatever was being followed: the new trajectory starts
from the current *desired* state (position, velocity, acceleration) at the command's
start time and reaches each point at its time_from_start. As in the JTC, segments between
points with positions only are linear, with positions and velocities cubic (Hermite),
with accelerations too quintic, so a trajectory whose first point carries a velocity
continues the motion without a jump in velocity. Unlike a bare JTC, segments too fast for
the joint speed limits are stretched in time (and every later point shifted by the same
amount), so the desired velocity never exceeds the limits. After the last point the
desired state holds it.
"""
import math

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


def _quintic(q0, q1, v0, v1, a0, a1, T, s):
    """Position, velocity, acceleration at s in [0, 1] of the quintic of duration T
    matching position, velocity and acceleration at both ends."""
    dq = q1 - q0
    c3 = (20 * dq - (8 * v1 + 12 * v0) * T - (3 * a0 - a1) * T * T) / (2 * T ** 3)
    c4 = (-30 * dq + (14 * v1 + 16 * v0) * T + (3 * a0 - 2 * a1) * T * T) / (2 * T ** 4)
    c5 = (12 * dq - 6 * (v1 + v0) * T - (a0 - a1) * T * T) / (2 * T ** 5)
    t = s * T
    q = q0 + t * (v0 + t * (a0 / 2 + t * (c3 + t * (c4 + t * c5))))
    v = v0 + t * (a0 + t * (3 * c3 + t * (4 * c4 + t * 5 * c5)))
    a = a0 + t * (6 * c3 + t * (12 * c4 + t * 20 * c5))
    return q, v, a


def _state(seg, t):
    t0, t1, q0, q1, v0, v1, a0, a1 = seg
    T = t1 - t0
    s = min(max((t - t0) / T, 0.0), 1.0) if T > 0 else 1.0
    if v0 is None:
        return q0 + (q1 - q0) * s, (q1 - q0) / T if T > 0 else np.zeros_like(q0), \
            np.zeros_like(q0)
    if a0 is None:
        return _hermite(q0, q1, v0, v1, T, s)
    return _quintic(q0, q1, v0, v1, a0, a1, T, s)


_SAMPLES = np.linspace(0.0, 1.0, 21)


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
    return max(float(np.max(np.abs(_state(seg, t0 + s * T)[1]) / vmax)) for s in _SAMPLES[1:])


def _retimed(seg, T):
    t0 = seg[0]
    return (t0, t0 + T) + tuple(seg[2:])


class TrajectoryFollower:
    """Desired joint state over time for n joints with per-joint speed limits."""

    def __init__(self, q0, max_speed, lower=None, upper=None):
        self.q = np.array(q0, dtype=float)
        self.n = len(self.q)
        self.vmax = np.broadcast_to(np.asarray(max_speed, dtype=float), (self.n,)).copy()
        if (lower is None) != (upper is None):
            raise ValueError('joint limits: give both lower and upper, or neither')
        self.lower = None if lower is None else np.asarray(lower, dtype=float)
        self.upper = None if upper is None else np.asarray(upper, dtype=float)
        self._limits = None if lower is None else (self.lower - 1e-9, self.upper + 1e-9)
        self.qd = np.zeros(self.n)
        self.qdd = np.zeros(self.n)
        self.segments = []     # (t0, t1, q0, q1, v0|None, v1|None, a0|None, a1|None)
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

    def command(self, now, points, start_time=None):
        """Replace the trajectory. points: [(time_from_start, positions, velocities|None
        [, accelerations])]. Raises TrajectoryError (and keeps the old trajectory) on a
        bad command. Returns the time at which the last point will be reached."""
        if not points:
            raise TrajectoryError('empty trajectory (no points)')
        start = now if start_time is None or start_time <= 0 else float(start_time)
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
            acc = self._vector(acc, k, 'accelerations') if vel is not None else None
            parsed.append((start + tfs, pos, vel, acc))
        # Points already in the past are dropped, as the JTC does.
        parsed = [pt for pt in parsed if pt[0] >= now] or None
        if parsed is None:
            raise TrajectoryError('trajectory ends in the past')
        self.sample(now)   # the desired state we start from
        t_prev = max(now, start)
        q_prev, v_prev, a_prev = self.q.copy(), self.qd.copy(), self.qdd.copy()
        shift = 0.0
        segments = []
        for t_abs, pos, vel, acc in parsed:
            t1 = max(t_abs + shift, t_prev)
            v0 = None if vel is None else v_prev
            a0 = None if acc is None else a_prev
            seg = (t_prev, t1, q_prev, pos, v0, vel, a0, acc)
            T = t1 - t_prev
            if vel is None and (q_prev == pos).all():
                ratio = 0.0
            else:
                ratio = _peak_ratio(seg, self.vmax)
            if ratio > 1.0:
                # Stretch until the segment respects every speed limit.
                if vel is None:
                    T_new = float(np.max(np.abs(pos - q_prev) / self.vmax))
                else:
                    T_new = max(T, 1e-3)
                    for _ in range(100):      # bounded: a start above the limit never fits
                        if _peak_ratio(_retimed(seg, T_new), self.vmax) <= 1.0 + 1e-9:
                            break
                        T_new *= 1.1
                shift += T_new - T
                seg = _retimed(seg, T_new)
                t1 = t_prev + T_new
            segments.append(seg)
            t_prev, q_prev = t1, pos
            v_prev = np.zeros(self.n) if vel is None else vel
            a_prev = np.zeros(self.n) if acc is None else acc
        self.segments = segments
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
                last = not self.segments
                self.qd = np.zeros(self.n) if (seg[5] is None or last) else seg[5].copy()
                self.qdd = np.zeros(self.n) if (seg[7] is None or last) else seg[7].copy()
                continue
            self.q, self.qd, self.qdd = _state(seg, t)
            return self.q, self.qd
        self.qd = np.zeros(self.n)
        self.qdd = np.zeros(self.n)
        return self.q, self.qd
