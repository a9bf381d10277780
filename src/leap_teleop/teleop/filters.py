"""Small signal filters for hand input."""
import math

import numpy as np


class LowPass:
    """First-order low-pass on vectors with a cutoff in Hz, robust to uneven sampling.
    cutoff <= 0 passes input through."""

    def __init__(self, cutoff_hz):
        self.cutoff_hz = float(cutoff_hz)
        self.value = None
        self._t = None

    def reset(self, value=None, t=None):
        self.value = None if value is None else np.array(value, dtype=float)
        self._t = t

    def update(self, x, t):
        x = np.asarray(x, dtype=float)
        if self.value is None or self.cutoff_hz <= 0 or self._t is None:
            self.value, self._t = x.copy(), t
            return self.value
        dt = max(0.0, t - self._t)
        self._t = t
        alpha = 1.0 - math.exp(-2.0 * math.pi * self.cutoff_hz * dt)
        self.value = self.value + alpha * (x - self.value)
        return self.value
