"""Joint servo: a moving joint goal -> short trajectories with continuous velocity.

Each control period the servo plans from the state it last commanded (position and
velocity at `now`, as the controller is following it) to a first point `horizon` s
later, whose velocity moves toward the goal's velocity plus a correction of the
remaining error, changed by at most max_accel * horizon and capped at max_speed; a
second point brings the joints to rest with the same deceleration bound. So:

* velocity is continuous from command to command (the controller starts every new
  trajectory from its current desired state, and our first point continues it);
* no joint accelerates faster than max_accel (segments are constant-acceleration
  parabolas, which the controller's cubic Hermite reproduces exactly);
* if commands stop (the node dies) the robot decelerates to rest by itself.

The correction is min(gain * |e|, sqrt(2 a |e|)): proportional near the goal and no faster
than it can still stop at the goal with the acceleration limit. With a `lead`, the error is
taken to the goal extrapolated that far ahead along its own velocity: the joints, which
need time to change speed within the acceleration bound, start toward where the goal is
heading instead of where it was (a short prediction; 0 = none). With `reach_fast`, the
first point's velocity is reached at the acceleration bound (every joint together) and
held to the horizon, instead of spread evenly over it.
"""

import numpy as np


class JointServo:
    def __init__(self, max_speed, max_accel, horizon=0.024, gain=10.0, lower=None, upper=None,
                 lead=0.0, reach_fast=False):
        self.max_speed = np.asarray(max_speed, dtype=float)
        self.max_accel = np.asarray(max_accel, dtype=float)
        self.horizon = float(horizon)
        self.gain = float(gain)
        self.lead = float(lead)
        self.reach_fast = bool(reach_fast)
        self.lower, self.upper = lower, upper
        self._plan = None      # (t0, q0, v0, vA, t1, h, t_stop): to vA by t1, on to h, rest

    def reset(self):
        """Forget the plan (the next call starts from the measured joints, at rest)."""
        self._plan = None

    @property
    def moving(self):
        return self._plan is not None

    def state_at(self, t, q_measured):
        """(q, v) the last plan commands at time t; the measured joints at rest when
        there is no plan or it has ended."""
        plan = self._plan
        if plan is None:
            return np.array(q_measured, dtype=float), np.zeros(len(q_measured))
        tau = max(t - plan[0], 0.0)
        if tau - plan[5] >= plan[6]:
            self._plan = None      # at rest: later calls follow the measured joints
        return self._planned(plan, tau)

    @staticmethod
    def _planned(plan, tau):
        """(q, v) of `plan` tau s after its start."""
        t0, q0, v0, vA, t1, h, t_stop = plan
        if tau <= t1:
            a = (vA - v0) / t1
            return q0 + v0 * tau + 0.5 * a * tau * tau, v0 + a * tau
        q1 = q0 + 0.5 * (v0 + vA) * t1
        if tau <= h:
            return q1 + vA * (tau - t1), vA.copy()
        qA = q1 + vA * (h - t1)
        if tau - h >= t_stop:                           # at rest (exactly)
            return qA + 0.5 * vA * t_stop, np.zeros_like(vA)
        tau2 = tau - h
        dec = vA / t_stop
        return qA + vA * tau2 - 0.5 * dec * tau2 * tau2, vA - dec * tau2

    def reach(self, t, q_measured):
        """(lo, hi): per joint, the extremes of the positions the last plan commands from
        time t until it rests (the measured joints when there is none). Its segments are
        constant accelerations, so a joint turns back at most once, in the first."""
        if self._plan is None:
            q = np.array(q_measured, dtype=float)
            return q, q.copy()
        t0, q0, v0, vA, t1, h, t_stop = self._plan
        start = max(t - t0, 0.0)
        taus = [start, t1, h, h + t_stop]
        a = (vA - v0) / t1
        with np.errstate(divide='ignore', invalid='ignore'):
            turns = np.where(a != 0.0, -v0 / a, -1.0)      # where v crosses 0 in segment 1
        taus += [float(x) for x in turns if 0.0 < x < t1]
        qs = np.array([self._planned(self._plan, tau)[0] for tau in taus if tau >= start])
        return qs.min(axis=0), qs.max(axis=0)

    def _clip(self, q):
        # np.clip's values; its wrapper costs more than the arithmetic on 6 joints.
        return q if self.lower is None else np.minimum(np.maximum(q, self.lower), self.upper)

    def _plan_points(self, now, q, v, vA, h, t1=None):
        """Plan (q, v) at now -> vA at now + t1 (constant acceleration; t1 = h when not
        given) -> (qA, vA) at now + h -> rest; its trajectory points."""
        t1 = h if t1 is None or t1 > h - 1e-9 else t1
        q1 = q + 0.5 * (v + vA) * t1
        qA = q1 + vA * (h - t1)
        t_stop = float((np.abs(vA) / self.max_accel).max())
        self._plan = (now, q.copy(), v.copy(), vA.copy(), max(t1, 1e-9), h, t_stop)
        points = [(t1, self._clip(q1), vA.copy())] if t1 < h else []
        if t_stop <= 1e-9:
            return points + [(h, self._clip(qA), np.zeros(vA.shape))]
        qS = qA + 0.5 * vA * t_stop
        return points + [(h, self._clip(qA), vA.copy()),
                         (h + t_stop, self._clip(qS), np.zeros(vA.shape))]

    def track(self, now, q_measured, goal, goal_velocity=None):
        """Trajectory points [(time_from_start, q, qd)] heading for `goal`, from now."""
        q, v = self.state_at(now, q_measured)
        ff = 0.0 if goal_velocity is None else np.asarray(goal_velocity, dtype=float)
        e = np.asarray(goal, dtype=float) + ff * self.lead - q
        mag = np.abs(e)
        correction = np.sign(e) * np.minimum(self.gain * mag,
                                             np.sqrt(2.0 * self.max_accel * mag))
        v_des = np.minimum(np.maximum(ff + correction, -self.max_speed), self.max_speed)
        step = self.max_accel * self.horizon
        vA = v + np.minimum(np.maximum(v_des - v, -step), step)
        t1 = None
        if self.reach_fast:
            # Reach vA as soon as the acceleration bound allows (every joint together),
            # then hold it to the horizon: the velocity lags the goal's by ~t1/2 instead
            # of horizon/2. A short first segment (>= 1 ms) keeps the points apart.
            t1 = max(float((np.abs(vA - v) / self.max_accel).max()), 1e-3)
        return self._plan_points(now, q, v, vA, self.horizon, t1)

    def stop(self, now, q_measured, min_duration=0.05, max_accel=None):
        """Points that bring the joints to rest as fast as the acceleration limit
        (max_accel, default the servo's) allows: a hold where the commanded motion can
        stop, never a jump back."""
        q, v = self.state_at(now, q_measured)
        accel = self.max_accel if max_accel is None else np.asarray(max_accel, dtype=float)
        t_stop = float((np.abs(v) / accel).max())
        if t_stop <= 1e-9:
            self._plan = None
            return [(min_duration, self._clip(q), np.zeros(q.shape))]
        return self._plan_points(now, q, v, np.zeros(v.shape), t_stop)
