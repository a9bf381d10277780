"""Age of the input behind each command, over a sliding time window, no ROS.

A consuming node (arm, pilot) adds one sample per command it sends that follows hand
input: the command's time minus the capture stamp of that input. `summary()` gives the
median and 99th percentile over the last `window_s` seconds, for /diagnostics.
"""
import collections
import math

import numpy as np


class InputAgeWindow:
    def __init__(self, window_s=10.0, max_samples=5000):
        if not (math.isfinite(window_s) and window_s > 0):
            raise ValueError('window_s must be a positive number of seconds, not %r'
                             % (window_s,))
        self.window_s = float(window_s)
        self._samples = collections.deque(maxlen=int(max_samples))   # (time, age s)
        self.last_stamp = 0.0          # capture stamp of the input behind the latest sample

    def add(self, now, input_stamp):
        """One command at `now` acting on input captured at `input_stamp` (same clock, s).
        Unstamped input (<= 0) or a non-finite time is not a sample; returns the age or None."""
        if not (input_stamp > 0 and math.isfinite(input_stamp) and math.isfinite(now)):
            return None
        age = now - input_stamp
        self._samples.append((now, age))
        self.last_stamp = input_stamp
        return age

    def _recent(self, now):
        while self._samples and (self._samples[0][0] < now - self.window_s
                                 or self._samples[0][0] > now + 1e-6):
            self._samples.popleft()        # old, or from before the clock jumped back
        return [age for _, age in self._samples]

    def summary(self, now):
        """(p50 s, p99 s, samples) over the last window_s seconds; (None, None, 0) if empty."""
        ages = self._recent(now)
        if not ages:
            return None, None, 0
        p50, p99 = np.percentile(ages, [50, 99])
        return float(p50), float(p99), len(ages)

    def diagnostic_values(self, now):
        """[(key, text)] for a DiagnosticStatus: the window's p50 / p99 in ms."""
        p50, p99, n = self.summary(now)

        def fmt(s):
            return 'n/a' if s is None else '%.1f' % (1000.0 * s)
        return [('input age p50 (ms, last %g s)' % self.window_s, fmt(p50)),
                ('input age p99 (ms, last %g s)' % self.window_s, fmt(p99)),
                ('input age samples', str(n)),
                ('input stamp of the last command', '%.6f' % self.last_stamp)]


def age_row(name, values):
    """(name, p50 ms, p99 ms, samples) from one diagnostic status's (key, value) pairs as
    diagnostic_values writes them; None when the status carries no input age."""
    got = {}
    for key, value in values:
        for field in ('p50', 'p99'):
            if key.startswith('input age %s' % field):
                got[field] = _ms(value)
        if key == 'input age samples':
            try:
                got['n'] = int(value)
            except (TypeError, ValueError):
                got['n'] = 0
    if not got:
        return None
    return name, got.get('p50'), got.get('p99'), got.get('n', 0)


def _ms(text):
    try:
        x = float(text)
    except (TypeError, ValueError):
        return None            # 'n/a': no sample in the window
    return x if math.isfinite(x) else None


def age_table(rows):
    """The rows as a fixed-width text table, sorted by name."""
    def cell(x):
        return '%8.1f' % x if x is not None else '     n/a'
    lines = ['%-44s %8s %8s %8s' % ('capture -> command (input age)', 'p50 ms', 'p99 ms',
                                    'samples')]
    for name, p50, p99, n in sorted(rows):
        lines.append('%-44s %s %s %8d' % (name[:44], cell(p50), cell(p99), n))
    return '\n'.join(lines)
