"""The leap_motion driver's filter node, as a pure second-order low-pass (Butterworth,
bilinear transform). Pure numpy: testable without ROS.

`cutoff` is the driver's filter_cutoff c = cot(pi * f_c / f_s): c = 1 puts the cut-off at a
quarter of the frame rate; larger c smooths more (the driver's default is 4). Each key (a
hand, say) filters a vector of coordinates; its first sample sets the history, so the output
starts at the input instead of rising from 0.
"""
import math

import numpy as np

DEFAULT_CUTOFF = 4.0


class LowPass:
    def __init__(self, cutoff=DEFAULT_CUTOFF):
        self.set_cutoff(cutoff)
        self._state = {}

    def set_cutoff(self, cutoff):
        """ValueError unless cutoff is a finite number > 0. A lower cutoff (less smoothing)
        starts each key's next sample from the old filter's last output, at rest: the old
        history under the lighter coefficients rang, 5x the hand's own steps. A higher one
        keeps the history (smooth as it is; at rest it stalled a moving hand)."""
        c = float(cutoff)
        if not (math.isfinite(c) and c > 0.0):
            raise ValueError('cutoff must be a finite number > 0, got %r' % (cutoff,))
        gain = 1.0 + c * c + math.sqrt(2.0) * c
        # One assignment (c, b on x[n] + 2 x[n-1] + x[n-2], a1 on y[n-1], a2 on y[n-2]): a
        # live change comes on another thread than the frames, and a frame filtered with a
        # new b and old a's has a gain other than 1.
        self._coefficients = (c, 1.0 / gain, (2.0 - 2.0 * c * c) / gain,
                              (1.0 - math.sqrt(2.0) * c + c * c) / gain)
        self.cutoff = c

    def reset(self, key=None):
        """Forget one key's history (all keys when None)."""
        if key is None:
            self._state.clear()
        else:
            self._state.pop(key, None)

    def __call__(self, key, values):
        """The filtered copy of `values` (any shape of floats) for `key`. A key whose shape
        changes starts over."""
        x = np.asarray(values, dtype=float)
        coefficients = self._coefficients       # read once: a live change may come meanwhile
        st = self._state.get(key)
        if st is None or st[0].shape != x.shape:
            # x1, x2, y1, y2, and the coefficients they were filtered with
            self._state[key] = [x.copy(), x.copy(), x.copy(), x.copy(), coefficients]
            return x.copy()
        x1, x2, y1, y2, used = st
        if used is not coefficients and coefficients[0] < used[0]:
            x1 = x2 = y2 = y1       # a lighter filter: at rest where the old one was
        _, b, a1, a2 = coefficients
        y = b * (x + 2.0 * x1 + x2) - a1 * y1 - a2 * y2
        self._state[key] = [x, x1, y, y1, coefficients]
        return y
