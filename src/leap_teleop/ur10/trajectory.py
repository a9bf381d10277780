"""Joint trajectory following the way ros_control's JointTrajectoryController does it.

A command is a list of points (time_from_start, positions[, velocities]). It replaces
whatever was being followed: the new trajectory starts from the current *desired*
state at the command's start time and reaches each point at its time_from_start.
Segments whose points carry velocities are cubic Hermite, otherwise linear (as the JTC
does for position-only points); accelerations are ignored. Unlike a bare JTC, segments
too fast for the joint speed limits are stretched in time (and every later point shifted
by the same amount), so the desired velocity never exceeds the limits. After the last
point the desired state holds it.
"""
import math

import numpy as np


class TrajectoryError(ValueError):
    """A command that cannot be followed (the caller keeps the old trajectory)."""


def _hermite(q0, q1, v0, v1, T, s):
    """Position and velocity at s in [0, 1] of a cubic Hermite of duration T."""
    s2, s3 = s * s, s * s * s
    h00, h10, h01, h11 = 2 * s3 - 3 * s2 + 1, s3 - 2 * s2 + s, -2 * s3 + 3 * s2, s3 - s2
    d00, d10, d01, d11 = 6 * s2 - 6 * s, 3 * s2 - 4 * s + 1, -6 * s2 + 6 * s, 3 * s2 - 2 * s
    q = h00 * q0 + h10 * T * v0 + h01 * q1 + h11 * T * v1
    v = (d00 * q0 + d10 * T * v0 + d01 * q1 + d11 * T * v1) / T
    return q, v


_SAMPLES = np.linspace(0.0, 1.0, 21)


def _peak_ratio(q0, q1, v0, v1, T, vmax):
    """max over joints and samples of |v| / vmax for a segment of duration T."""
    if v0 is None:
        return float(np.max(np.abs(q1 - q0) / (T * vmax))) if T > 0 else math.inf
    if T <= 0:
        return math.inf
    peak = 0.0
    for s in _SAMPLES:
        _, v = _hermite(q0, q1, v0, v1, T, s)
        peak = max(peak, float(np.max(np.abs(v) / vmax)))
    return peak


class TrajectoryFollower:
    """Desired joint state over time for n joints with per-joint speed limits."""

    def __init__(self, q0, max_speed, lower=None, upper=None):
        self.q = np.array(q0, dtype=float)
        self.n = len(self.q)
        self.vmax = np.broadcast_to(np.asarray(max_speed, dtype=float), (self.n,)).copy()
        self.lower = None if lower is None else np.asarray(lower, dtype=float)
        self.upper = None if upper is None else np.asarray(upper, dtype=float)
        self.qd = np.zeros(self.n)
        self.segments = []     # (t0, t1, q0, q1, v0 or None, v1 or None)
        self.end_time = -math.inf

    def hold(self, q=None):
        """Drop the trajectory and hold q (default: the current desired position)."""
        if q is not None:
            self.q = np.array(q, dtype=float)
        self.qd = np.zeros(self.n)
        self.segments = []
        self.end_time = -math.inf

    @property
    def active(self):
        return bool(self.segments)

    def command(self, now, points, start_time=None):
        """Replace the trajectory. points: [(time_from_start, positions, velocities|None)].
        Raises TrajectoryError (and keeps the old trajectory) on a bad command.
        Returns the time at which the last point will be reached."""
        if not points:
            raise TrajectoryError('empty trajectory (no points)')
        start = now if start_time is None or start_time <= 0 else float(start_time)
        parsed = []
        last_t = -math.inf
        for k, (tfs, pos, vel) in enumerate(points):
            tfs = float(tfs)
            pos = np.asarray(pos, dtype=float)
            if not math.isfinite(tfs) or tfs < 0:
                raise TrajectoryError('point %d: bad time_from_start %r' % (k, tfs))
            if tfs < last_t:
                raise TrajectoryError('point %d: time_from_start goes backwards' % k)
            last_t = tfs
            if pos.shape != (self.n,) or not np.all(np.isfinite(pos)):
                raise TrajectoryError('point %d: positions must be %d finite numbers' % (k, self.n))
            if self.lower is not None and (np.any(pos < self.lower - 1e-9)
                                           or np.any(pos > self.upper + 1e-9)):
                raise TrajectoryError('point %d: positions outside the joint limits' % k)
            if vel is not None and len(vel):
                vel = np.asarray(vel, dtype=float)
                if vel.shape != (self.n,) or not np.all(np.isfinite(vel)):
                    raise TrajectoryError('point %d: velocities must be %d finite numbers'
                                          % (k, self.n))
                vel = np.clip(vel, -self.vmax, self.vmax)
            else:
                vel = None
            parsed.append((start + tfs, pos, vel))
        # Points already in the past are dropped, as the JTC does.
        parsed = [pt for pt in parsed if pt[0] >= now] or None
        if parsed is None:
            raise TrajectoryError('trajectory ends in the past')
        self.sample(now)   # the desired state we start from
        t_prev = max(now, start)
        q_prev, v_prev = self.q.copy(), self.qd.copy()
        shift = 0.0
        segments = []
        for t_abs, pos, vel in parsed:
            t1 = max(t_abs + shift, t_prev)
            v0 = None if vel is None else v_prev
            T = t1 - t_prev
            if np.all(q_prev == pos) and vel is None:
                ratio = 0.0
            else:
                ratio = _peak_ratio(q_prev, pos, v0, vel, T, self.vmax)
            if ratio > 1.0:
                # Stretch until the segment respects every speed limit.
                if vel is None:
                    T_new = float(np.max(np.abs(pos - q_prev) / self.vmax))
                else:
                    T_new = max(T, 1e-3)
                    while _peak_ratio(q_prev, pos, v0, vel, T_new, self.vmax) > 1.0 + 1e-9:
                        T_new *= 1.1
                shift += T_new - T
                t1 = t_prev + T_new
            segments.append((t_prev, t1, q_prev, pos, v0, vel))
            t_prev, q_prev = t1, pos
            v_prev = np.zeros(self.n) if vel is None else vel
        self.segments = segments
        self.end_time = t_prev
        return t_prev

    def sample(self, t):
        """Advance to time t; returns (q_desired, qd_desired)."""
        while self.segments:
            t0, t1, q0, q1, v0, v1 = self.segments[0]
            if t < t0:
                return self.q, self.qd
            if t >= t1:
                self.segments.pop(0)
                self.q = q1.copy()
                self.qd = np.zeros(self.n) if (v1 is None or not self.segments) else v1.copy()
                continue
            T = t1 - t0
            s = (t - t0) / T
            if v0 is None:
                self.q = q0 + (q1 - q0) * s
                self.qd = (q1 - q0) / T
            else:
                self.q, self.qd = _hermite(q0, q1, v0, v1, T, s)
            return self.q, self.qd
        self.qd = np.zeros(self.n)
        return self.q, self.qd
