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
* if commands stop (the node dies) the robot decelerates to rest by itself;
* once a plan has ended, the joints rest where it brought them until measured joints
  received after its end are passed in (`received`): older ones show where a robot whose
  states stopped was, not where it went on to, and a plan from them drove it back.

The correction is min(gain * |e|, sqrt(2 a |e|)): proportional near the goal and no faster
than it can still stop at the goal with the acceleration limit. With joint limits, a joint
heading for one goes no faster than its plan still comes to rest short of it: no point
is ever past a limit (a point clipped to it while moving on is one the controller can
only follow by going beyond and back). With a `lead`, the error is
taken to the goal extrapolated that far ahead along its own velocity: the joints, which
need time to change speed within the acceleration bound, start toward where the goal is
heading instead of where it was (a short prediction; 0 = none). With `reach_fast`, the
first point's velocity is reached at the acceleration bound (every joint together) and
held to the horizon, instead of spread evenly over it.
"""

import math

import numpy as np


def _floats(x, n):
    """x (one number or n numbers) as a list of n floats."""
    a = np.asarray(x, dtype=float)
    return a.tolist() if a.shape == (n,) else np.broadcast_to(a, (n,)).tolist()


class JointServo:
    """The arithmetic runs joint by joint in plain floats (the arm runs it every control
    period, and numpy's per-call cost on 6 numbers is most of it), in the order and with
    the tie rules of the numpy expressions in the comments, so that it gives their floats."""

    def __init__(self, max_speed, max_accel, horizon=0.024, gain=10.0, lower=None, upper=None,
                 lead=0.0, reach_fast=False):
        self.max_speed = np.asarray(max_speed, dtype=float)
        self.max_accel = np.asarray(max_accel, dtype=float)
        self.horizon = float(horizon)
        self.gain = float(gain)
        self.lead = float(lead)
        self.reach_fast = bool(reach_fast)
        self.lower, self.upper = lower, upper
        # A lower bound (per joint or one) for speeding up only, while max_accel still allows
        # harder braking (a lowered limit coming down): no joint gains a speed it could not
        # shed at this bound, nor moves toward its goal faster than it can stop there at it,
        # the goal's own speed included. None: max_accel for both, and no such cap.
        self.speedup_accel = None
        self.cap_binding = False    # that cap held a joint back in the last track()
        # (t0, q0, v0, vA, t1, h, t_stop), q0 v0 vA tuples of floats: to vA by t1, on to h,
        # then to rest.
        self._plan = None
        # The last plan once it has ended, while the measured joints passed in are older
        # than its end: its rest is the joints' pose, not those (a robot whose states
        # stopped went on along it, and a plan from them drove it back).
        self._ended = None
        # When the measured joints passed in were received (None: unknown, taken as now).
        self.received = None

    def reset(self):
        """Forget the plan (the next call starts from the measured joints, at rest)."""
        self._plan = self._ended = None

    @property
    def moving(self):
        return self._plan is not None

    def _ended_plan(self):
        """The plan that has ended, as long as the measured joints are older than its end
        (forgotten once they are not)."""
        plan = self._ended
        if plan is not None and (self.received is None
                                 or self.received >= plan[0] + plan[5] + plan[6]):
            plan = self._ended = None
        return plan

    def _state(self, t, q_measured):
        """state_at as lists of floats."""
        plan = self._plan
        if plan is None:
            if self._ended is not None and self._ended_plan() is not None:
                return self._planned(self._ended, math.inf)     # its rest
            q = np.asarray(q_measured, dtype=float).tolist()
            return q, [0.0] * len(q)
        tau = max(t - plan[0], 0.0)
        if tau - plan[5] >= plan[6]:
            # at rest: later calls follow the measured joints received since
            self._plan, self._ended = None, plan
        return self._planned(plan, tau)

    def state_at(self, t, q_measured):
        """(q, v) the last plan commands at time t; the measured joints at rest when
        there is no plan or it has ended (its rest while they are older than its end)."""
        if self._plan is None and (self._ended is None or self._ended_plan() is None):
            return np.array(q_measured, dtype=float), np.zeros(len(q_measured))
        q, v = self._state(t, q_measured)
        return np.array(q), np.array(v)

    @staticmethod
    def _planned(plan, tau):
        """(q, v) of `plan` tau s after its start, as lists."""
        t0, q0, v0, vA, t1, h, t_stop = plan
        if tau <= t1:
            # a = (vA - v0) / t1; q0 + v0 * tau + 0.5 * a * tau * tau, v0 + a * tau
            n = len(q0)
            q, v, j = [0.0] * n, [0.0] * n, 0
            for x, u, w in zip(q0, v0, vA):
                a = (w - u) / t1
                q[j] = x + u * tau + 0.5 * a * tau * tau
                v[j] = u + a * tau
                j += 1
            return q, v
        q1 = [x + 0.5 * (u + w) * t1 for x, u, w in zip(q0, v0, vA)]
        if tau <= h:
            return [y + w * (tau - t1) for y, w in zip(q1, vA)], list(vA)
        qA = [y + w * (h - t1) for y, w in zip(q1, vA)]
        if tau - h >= t_stop:                           # at rest (exactly)
            return [y + 0.5 * w * t_stop for y, w in zip(qA, vA)], [0.0] * len(vA)
        tau2 = tau - h
        # dec = vA / t_stop; qA + vA * tau2 - 0.5 * dec * tau2 * tau2, vA - dec * tau2
        q, v = [], []
        for y, w in zip(qA, vA):
            dec = w / t_stop
            q.append(y + w * tau2 - 0.5 * dec * tau2 * tau2)
            v.append(w - dec * tau2)
        return q, v

    def planned_at(self, t):
        """(q) the last plan commands at time t, or None without one or once it has come to
        rest by then; leaves the plan as it is."""
        plan = self._plan
        if plan is None or t - plan[0] - plan[5] >= plan[6]:
            return None
        return np.array(self._planned(plan, max(t - plan[0], 0.0))[0])

    def rest(self, q_measured):
        """Where the last plan brings the joints to rest (the measured joints when there is
        none, or it has ended and they are not older than its end), leaving the plan as it is."""
        plan = self._plan
        if plan is None:
            if self._ended is None or self._ended_plan() is None:
                return np.array(q_measured, dtype=float)
            return np.array(self._planned(self._ended, math.inf)[0])
        return np.array(self._planned(plan, plan[5] + plan[6])[0])

    def reach(self, t, q_measured):
        """(lo, hi): per joint, the extremes of the positions the last plan commands from
        time t until it rests (the measured joints when there is none). Its segments are
        constant accelerations, so a joint turns back at most once, in the first."""
        plan = self._plan
        if plan is None and (self._ended is None or (plan := self._ended_plan()) is None):
            q = np.array(q_measured, dtype=float)
            return q, q.copy()
        t0, q0, v0, vA, t1, h, t_stop = plan
        start = max(t - t0, 0.0)
        taus = [start, t1, h, h + t_stop]
        for u, w in zip(v0, vA):
            a = (w - u) / t1
            if a != 0.0:
                turn = -u / a                      # where v crosses 0 in segment 1
                if 0.0 < turn < t1:
                    taus.append(turn)
        qs = np.array([self._planned(plan, tau)[0] for tau in taus if tau >= start])
        return qs.min(axis=0), qs.max(axis=0)

    def _limits(self, n):
        return None if self.lower is None else (_floats(self.lower, n), _floats(self.upper, n))

    @staticmethod
    def _inside(q, v, limits):
        """q (and v when given) as arrays, q clipped to the limits (NaN to the lower one)
        and the velocity of each clipped joint 0. A last resort: plans stop short of them."""
        if limits is not None:
            for x, lo, hi in zip(q, *limits):
                if not lo < x < hi:
                    break
            else:
                limits = None
        if limits is None:
            return np.array(q) if v is None else (np.array(q), np.array(v))
        q, v = list(q), None if v is None else list(v)
        for j, (x, lo, hi) in enumerate(zip(q, *limits)):
            y = m if (m := x if x > lo else lo) < hi else hi
            if y != x:                                      # (NaN too)
                q[j] = y
                if v is not None:
                    v[j] = 0.0
        return np.array(q) if v is None else (np.array(q), np.array(v))

    def _plan_points(self, now, q, v, vA, h, t1=None, limits=None, accel=None, t_stop=None):
        """Plan (q, v) at now -> vA at now + t1 (constant acceleration; t1 = h when not
        given) -> (qA, vA) at now + h -> rest at accel (default max_accel; t_stop: its
        time when known); its trajectory points. q, v, vA: lists."""
        t1 = h if t1 is None or t1 > h - 1e-9 else t1
        n = len(q)
        q1 = [x + 0.5 * (u + w) * t1 for x, u, w in zip(q, v, vA)]
        qA = [y + w * (h - t1) for y, w in zip(q1, vA)]
        if t_stop is None:
            t_stop = max([abs(w) / a for w, a in zip(vA, accel or _floats(self.max_accel, n))])
        self._plan = (now, tuple(q), tuple(v), tuple(vA), max(t1, 1e-9), h, t_stop)
        self._ended = None
        limits = limits or self._limits(n)
        points = [(t1, *self._inside(q1, vA, limits))] if t1 < h else []
        if t_stop <= 1e-9:
            return points + [(h, self._inside(qA, None, limits), np.zeros(n))]
        qS = [y + 0.5 * w * t_stop for y, w in zip(qA, vA)]
        return points + [(h, *self._inside(qA, vA, limits)),
                         (h + t_stop, self._inside(qS, None, limits), np.zeros(n))]

    def _short_of_limits(self, q, v, vA, accel, limits, h):
        """vA (changed in place) slowed down, by at most a * h, where the plan would come
        to rest past a joint limit; returns the plan's t_stop (None when it changed).
        Every joint brakes over the slowest one's t_stop, to q + (v + vA) h / 2 +
        vA t_stop / 2 (t1 = h; with reach_fast at most q + vA h + vA t_stop / 2 once
        |vA| > |v|); slowing joints down never lengthens t_stop. A joint that cannot slow
        down enough for it (another one sped up) has every joint brake harder, to a t_stop
        it can take."""
        t_stop = max([abs(w) / a for w, a in zip(vA, accel)])
        fast = self.reach_fast
        allow, j, same = math.inf, 0, True
        for x, u, w, a, lo, hi in zip(q, v, vA, accel, *limits):
            if w > 0.0:
                room = hi - x
            elif w < 0.0:
                room, u, w = x - lo, -u, -w
            else:
                j += 1
                continue
            cap = (2.0 * room - u * h) / (h + t_stop)
            if fast and cap > u:
                cap = 2.0 * room / (2.0 * h + t_stop)
            if w > cap:
                slowest = u - a * h
                if cap < slowest and slowest > 0.0:
                    t = (2.0 * room - (u + slowest) * h) / slowest
                    allow = t if t < allow else allow
                    w = slowest
                elif cap > 0.0:
                    w = cap
                elif u * h > 2.0 * room:
                    # Even at rest by the horizon it would pass the limit (a plan braked
                    # faster than over a horizon): it turns back within it, at u^2 h /
                    # (2 (u - w)) from x.
                    w = u - u * u * h / (2.0 * room) if room > 0.0 else slowest
                    w = w if w > slowest else slowest
                else:
                    w = 0.0
                vA[j] = w if vA[j] > 0.0 else -w
                same = False
            j += 1
        if same:
            return t_stop
        if allow < t_stop:
            allow = allow if allow > 0.0 else 0.0
            j = 0
            for u, w, a in zip(v, vA, accel):
                top = a * allow
                if w > top:
                    vA[j] = top if top > u - a * h else u - a * h
                elif w < -top:
                    vA[j] = -top if -top < u + a * h else u + a * h
                j += 1
        return None

    def track(self, now, q_measured, goal, goal_velocity=None):
        """Trajectory points [(time_from_start, q, qd)] heading for `goal`, from now."""
        q, v = self._state(now, q_measured)
        n = len(q)
        ff = [0.0] * n if goal_velocity is None else _floats(goal_velocity, n)
        lead, gain, horizon = self.lead, self.gain, self.horizon
        accel = _floats(self.max_accel, n)
        capped = self.speedup_accel is not None
        up = _floats(np.minimum(self.speedup_accel, self.max_accel), n) if capped else accel
        vA, j, binding = [0.0] * n, 0, False
        for g, f, x, u, a, b, top in zip(_floats(goal, n), ff, q, v, accel, up,
                                         _floats(self.max_speed, n)):
            # e = goal + ff * lead - q; correction = np.sign(e) * np.minimum(gain * |e|,
            # np.sqrt(2 b |e|)); v_des = clip(ff + correction, -max_speed, max_speed);
            # vA = v + clip(v_des - v, -a horizon, a horizon), a speed-up at most b horizon
            # (b = a unless speedup_accel is set)
            e = g + f * lead - x
            mag = abs(e)
            near, far = gain * mag, math.sqrt(2.0 * b * mag)
            m = near if near < far else far
            v_des = f + (m if e > 0 else -m if e < 0 else 0.0 * m)
            if capped:
                # the goal's own speed included, no faster toward it than b can stop at it
                # (it may stop at any moment; after the ramp, braking is at b)
                held = min(v_des, far) if e > 0 else max(v_des, -far) if e < 0 else 0.0
                binding = binding or held != v_des
                v_des = held
            v_des = v_des if v_des > -top else -top
            v_des = v_des if v_des < top else top
            step = a * horizon
            dv = v_des - u
            dv = dv if dv > -step else -step
            w = u + (dv if dv < step else step)
            if b < a and abs(w) > abs(u):           # speeding up: at b only
                w = max(-abs(u) - b * horizon, min(abs(u) + b * horizon, w))
            vA[j] = w
            j += 1
        self.cap_binding = binding
        limits = self._limits(n)
        t_stop = None if limits is None else self._short_of_limits(q, v, vA, accel, limits,
                                                                   horizon)
        t1 = None
        if self.reach_fast:
            # Reach vA as soon as the acceleration bound allows (every joint together),
            # then hold it to the horizon: the velocity lags the goal's by ~t1/2 instead
            # of horizon/2. A short first segment (>= 1 ms) keeps the points apart.
            t1 = max(max([abs(w - u) / (b if abs(w) > abs(u) else a)
                          for w, u, a, b in zip(vA, v, accel, up)]), 1e-3)
        return self._plan_points(now, q, v, vA, horizon, t1, limits, accel, t_stop)

    def stop(self, now, q_measured, min_duration=0.05, max_accel=None):
        """Points that bring the joints to rest as fast as the acceleration limit
        (max_accel, default the servo's) allows: a hold where the commanded motion can
        stop, never a jump back; at rest there until min_duration at the least."""
        q, v = self._state(now, q_measured)
        n = len(q)
        accel = _floats(self.max_accel if max_accel is None else max_accel, n)
        t_stop = max([abs(u) / a for u, a in zip(v, accel)])
        limits = self._limits(n)
        if t_stop <= 1e-9:
            self._plan = None
            return [(min_duration, self._inside(q, None, limits), np.zeros(n))]
        t1 = 0.0
        if limits is not None:
            # Every joint brakes over the slowest one's t_stop: one that would come to rest
            # past a limit so stops first, at the full deceleration, and the others slow
            # down at it meanwhile (which only shortens their way; the total time stays).
            t1 = max([abs(u) / a for x, u, a, lo, hi in zip(q, v, accel, *limits)
                      if not lo - x <= 0.5 * u * t_stop <= hi - x] or [0.0])
        if t1 > 0.0:
            vA = [u - a * t1 if u > a * t1 else u + a * t1 if u < -a * t1 else 0.0
                  for u, a in zip(v, accel)]
            points = self._plan_points(now, q, v, vA, t1, None, limits, accel)
        else:
            points = self._plan_points(now, q, v, [0.0] * n, t_stop, None, limits)
        if points[-1][0] < min_duration:
            # it lasted |v| / a: 16 ms at 0.05 rad/s, nanoseconds from a nearly still arm
            points.append((min_duration, points[-1][1].copy(), np.zeros(n)))
        return points
