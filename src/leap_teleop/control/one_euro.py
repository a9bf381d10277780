"""The One Euro filter (Casiez, Roussel, Vogel, CHI 2012) on vectors.

An exponential low-pass whose cutoff rises with the signal's speed:

    alpha(fc, dt) = 1 / (1 + tau / dt),  tau = 1 / (2 pi fc)
    dx_hat  = lowpass((x - x_hat_prev) / dt, alpha(d_cutoff, dt))
    fc      = min_cutoff + beta * |dx_hat|
    x_hat   = lowpass(x, alpha(fc, dt))

Still (|dx| small): cutoff min_cutoff, strong smoothing, no jitter. Moving: cutoff grows
with speed, little lag. One cutoff for the whole vector (from the norm of its filtered
derivative), so a 3-D path keeps its direction. Also used on rotation vectors: a
rotation since the origin is small and continuous, unlike Euler angles.
"""
import math

import numpy as np


def smoothing_factor(cutoff_hz, dt):
    """alpha of a first-order low-pass with this cutoff for one sample after dt s."""
    tau = 1.0 / (2.0 * math.pi * cutoff_hz)
    return 1.0 / (1.0 + tau / dt)


class OneEuroFilter:
    """min_cutoff_hz <= 0 passes input through. beta: Hz of extra cutoff per unit/s of
    speed (units of the signal). d_cutoff_hz: cutoff of the speed estimate."""

    def __init__(self, min_cutoff_hz=1.0, beta=0.0, d_cutoff_hz=1.0):
        if not (math.isfinite(min_cutoff_hz) and math.isfinite(beta) and beta >= 0
                and math.isfinite(d_cutoff_hz) and d_cutoff_hz > 0):
            raise ValueError('One Euro filter: need finite min_cutoff, beta >= 0, d_cutoff > 0')
        self.min_cutoff_hz = float(min_cutoff_hz)
        self.beta = float(beta)
        self.d_cutoff_hz = float(d_cutoff_hz)
        self.value = None
        self.derivative = None
        self._t = None

    @property
    def speed(self):
        """|filtered derivative|, units of the signal per s."""
        d = self.derivative
        if d is None:
            return 0.0
        # A plain sum of squares, as _update3 takes it: not np.linalg.norm or d.dot(d),
        # whose BLAS kernels round differently on CPUs that fuse multiply-adds.
        if d.shape == (3,):
            d0, d1, d2 = d.tolist()
            return math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
        if d.ndim == 1:
            return math.sqrt(float(np.sum(d * d)))
        return math.sqrt(float(np.sum(d * d)))

    def reset(self, value=None, t=None):
        """Start over from value (None: from the next sample), at rest."""
        self.value = None if value is None else np.array(value, dtype=float)
        self.derivative = None if value is None else np.zeros_like(self.value)
        self._t = t

    def update(self, x, t):
        x = np.asarray(x, dtype=float)
        if self.value is None or self.min_cutoff_hz <= 0 or self._t is None:
            self.value, self._t = x.copy(), t
            self.derivative = np.zeros_like(self.value)
            return self.value
        dt = t - self._t
        if dt <= 0.0:
            return self.value      # same or older time: nothing new to weigh
        self._t = t
        if x.shape == (3,) and self.value.shape == (3,) and self.derivative.shape == (3,):
            return self._update3(x.tolist(), dt)
        raw = (x - self.value) / dt
        self.derivative = self.derivative + smoothing_factor(self.d_cutoff_hz, dt) * (
            raw - self.derivative)
        cutoff = self.min_cutoff_hz + self.beta * self.speed
        self.value = self.value + smoothing_factor(cutoff, dt) * (x - self.value)
        return self.value

    def _update3(self, x, dt):
        """update() of a 3-vector in plain floats (the arm filters its palm and rotation
        every control period): the numpy expressions above, element by element."""
        (x0, x1, x2), (v0, v1, v2) = x, self.value.tolist()
        d0, d1, d2 = self.derivative.tolist()
        a = smoothing_factor(self.d_cutoff_hz, dt)
        d0 = d0 + a * ((x0 - v0) / dt - d0)
        d1 = d1 + a * ((x1 - v1) / dt - d1)
        d2 = d2 + a * ((x2 - v2) / dt - d2)
        self.derivative = np.array([d0, d1, d2])
        b = smoothing_factor(self.min_cutoff_hz + self.beta * math.sqrt(d0 * d0 + d1 * d1 + d2 * d2),
                             dt)
        self.value = np.array([v0 + b * (x0 - v0), v1 + b * (x1 - v1), v2 + b * (x2 - v2)])
        return self.value
