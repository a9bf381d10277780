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
than it can still stop at the goal with the acceleration limit.
"""

import numpy as np


class JointServo:
    def __init__(self, max_speed, max_accel, horizon=0.032, gain=10.0, lower=None, upper=None):
        self.max_speed = np.asarray(max_speed, dtype=float)
        self.max_accel = np.asarray(max_accel, dtype=float)
        self.horizon = float(horizon)
        self.gain = float(gain)
        self.lower, self.upper = lower, upper
        self._plan = None      # (t0, q0, v0, vA, h, t_stop): parabola to t0 + h, then rest

    def reset(self):
        """Forget the plan (the next call starts from the measured joints, at rest)."""
        self._plan = None

    @property
    def moving(self):
        return self._plan is not None

    def state_at(self, t, q_measured):
        """(q, v) the last plan commands at time t; the measured joints at rest when
        there is no plan or it has ended."""
        if self._plan is None:
            return np.array(q_measured, dtype=float), np.zeros(len(q_measured))
        t0, q0, v0, vA, h, t_stop = self._plan
        tau = max(t - t0, 0.0)
        if tau <= h:
            a = (vA - v0) / h
            return q0 + v0 * tau + 0.5 * a * tau * tau, v0 + a * tau
        qA = q0 + 0.5 * (v0 + vA) * h
        tau2 = tau - h
        if tau2 >= t_stop:
            self._plan = None      # at rest: later calls follow the measured joints
            return qA + 0.5 * vA * t_stop, np.zeros_like(vA)
        dec = vA / t_stop
        return qA + vA * tau2 - 0.5 * dec * tau2 * tau2, vA - dec * tau2

    def _clip(self, q):
        return q if self.lower is None else np.clip(q, self.lower, self.upper)

    def _plan_points(self, now, q, v, vA, h):
        """Plan (q, v) at now -> (qA, vA) at now + h -> rest; its trajectory points."""
        qA = q + 0.5 * (v + vA) * h
        t_stop = float(np.max(np.abs(vA) / self.max_accel))
        self._plan = (now, q.copy(), v.copy(), vA.copy(), h, t_stop)
        if t_stop <= 1e-9:
            return [(h, self._clip(qA), np.zeros_like(vA))]
        qS = qA + 0.5 * vA * t_stop
        return [(h, self._clip(qA), vA.copy()), (h + t_stop, self._clip(qS), np.zeros_like(vA))]

    def track(self, now, q_measured, goal, goal_velocity=None):
        """Trajectory points [(time_from_start, q, qd)] heading for `goal`, from now."""
        q, v = self.state_at(now, q_measured)
        e = np.asarray(goal, dtype=float) - q
        mag = np.abs(e)
        correction = np.sign(e) * np.minimum(self.gain * mag,
                                             np.sqrt(2.0 * self.max_accel * mag))
        ff = 0.0 if goal_velocity is None else np.asarray(goal_velocity, dtype=float)
        v_des = np.clip(ff + correction, -self.max_speed, self.max_speed)
        step = self.max_accel * self.horizon
        vA = v + np.clip(v_des - v, -step, step)
        return self._plan_points(now, q, v, vA, self.horizon)

    def stop(self, now, q_measured, min_duration=0.05, max_accel=None):
        """Points that bring the joints to rest as fast as the acceleration limit
        (max_accel, default the servo's) allows: a hold where the commanded motion can
        stop, never a jump back."""
        q, v = self.state_at(now, q_measured)
        accel = self.max_accel if max_accel is None else np.asarray(max_accel, dtype=float)
        t_stop = float(np.max(np.abs(v) / accel))
        if t_stop <= 1e-9:
            self._plan = None
            return [(min_duration, self._clip(q), np.zeros_like(q))]
        return self._plan_points(now, q, v, np.zeros_like(v), t_stop)
