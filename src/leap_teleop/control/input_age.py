"""Age of the hand input at each stage of the pipeline, over a sliding time window, no ROS.

A consuming node (arm, pilot) adds one sample per command it sends that follows hand
input: the command's time minus the capture stamp of that input. The sender adds one per
hand frame at each of its stages (recognized, published) through StageAges. A simulator
adds, per robot, how long each command waited before its physics applied it (CommandWaits).
`summary()` gives the median and 99th percentile over the last `window_s` seconds, for
/diagnostics; LatencyBoard reads those values back into one row per (node, stage).
"""
import array
import math
import re
import time

import numpy as np


class InputAgeWindow:
    """Ages in a fixed ring of `max_samples` (time, age) slots: add() stores two floats
    and moves a counter, so a hot thread can feed it at a few hundred hertz, and a
    reader on another thread (diagnostics) copies the ring without a lock and without
    holding the interpreter for long (a long hold delays the hot thread's next frame).
    One writer thread per window."""

    def __init__(self, window_s=10.0, max_samples=8192, stage=None, label=None):
        """stage: None for a consumer's commands (keys 'input age p50 ...'), else the
        stage's name (keys 'input age (recognized) p50 ...'); label replaces the keys'
        'input age ...' prefix for a window of another quantity."""
        if not (math.isfinite(window_s) and window_s > 0):
            raise ValueError('window_s must be a positive number of seconds, not %r'
                             % (window_s,))
        self.window_s = float(window_s)
        self.stage = stage
        self._label = label or ('input age' if stage is None else 'input age (%s)' % stage)
        self._size = int(max_samples)
        self._times = array.array('d', bytes(8 * self._size))
        self._ages = array.array('d', bytes(8 * self._size))
        self._times_view = np.frombuffer(self._times)
        self._ages_view = np.frombuffer(self._ages)
        self._added = 0
        self.last_stamp = 0.0          # capture stamp of the input behind the latest sample

    def add(self, now, input_stamp):
        """One command at `now` acting on input captured at `input_stamp` (same clock, s).
        Unstamped input (<= 0) or a non-finite time is not a sample; returns the age or None."""
        if not (input_stamp > 0 and math.isfinite(input_stamp) and math.isfinite(now)):
            return None
        age = now - input_stamp
        i = self._added % self._size
        # age before time: a reader racing this write sees the slot's old time (outside
        # its window, or a recent sample's) with a real age, never a made-up one
        self._ages[i] = age
        self._times[i] = now
        self._added += 1
        self.last_stamp = input_stamp
        return age

    def clear(self):
        """Forget every sample (never beside add(): on the writer's thread or under its
        lock)."""
        self._added = 0

    def ages(self, now):
        """The ages (s, an array) of the samples taken in the last window_s seconds up to
        `now` (samples from after `now` belong to a clock that has since jumped back)."""
        k = min(self._added, self._size)
        times = self._times_view[:k].copy()
        ages = self._ages_view[:k].copy()
        keep = (times >= now - self.window_s) & (times <= now + 1e-6)
        return ages[keep]

    def summary(self, now):
        """(p50 s, p99 s, samples) over the last window_s seconds; (None, None, 0) if empty."""
        ages = self.ages(now)
        if not len(ages):
            return None, None, 0
        p50, p99 = np.percentile(ages, [50, 99])
        return float(p50), float(p99), len(ages)

    def diagnostic_values(self, now):
        """[(key, text)] for a DiagnosticStatus: the window's p50 / p99 in ms."""
        p50, p99, n = self.summary(now)

        def fmt(s):
            return 'n/a' if s is None else '%.1f' % (1000.0 * s)
        values = [('%s p50 (ms, last %g s)' % (self._label, self.window_s), fmt(p50)),
                  ('%s p99 (ms, last %g s)' % (self._label, self.window_s), fmt(p99)),
                  ('%s samples' % self._label, str(n))]
        if self.stage is None and self._label == 'input age':      # a consumer's commands
            values.append(('input stamp of the last command', '%.6f' % self.last_stamp))
        return values


class StageAges:
    """One InputAgeWindow per stage, fed from the hot thread (one writer) and read on
    another (diagnostics) without a lock."""

    def __init__(self, stages, window_s=10.0, max_samples=8192):
        self.windows = {stage: InputAgeWindow(window_s, max_samples, stage=stage)
                        for stage in stages}

    def add(self, stage, now, input_stamp):
        """Input captured at `input_stamp` reached `stage` at `now` (same clock, s); an
        unknown stage is no sample."""
        window = self.windows.get(stage)
        if window is not None:
            window.add(now, input_stamp)

    def summary(self, now):
        """{stage: (p50 s, p99 s, samples)} over each window."""
        return {stage: w.summary(now) for stage, w in self.windows.items()}

    def diagnostic_values(self, now):
        """Every stage's window values, in the order the stages were given."""
        return [kv for w in self.windows.values() for kv in w.diagnostic_values(now)]


class CommandWaits:
    """How long each robot's commands waited in a simulator between their receipt and the
    physics step that applied them, one window per robot (keys 'command wait (ur10_1) p50
    ...'). The commands carry no capture stamp, so this is the stage after 'command', not
    an input age. Times on its own monotonic clock; one writer thread."""

    def __init__(self, robots, window_s=10.0, clock=time.monotonic):
        self.clock = clock
        self.windows = {r: InputAgeWindow(window_s, label='command wait (%s)' % r)
                        for r in robots}

    def add(self, robot, received, applied):
        """A command of `robot` received at `received`, applied at `applied` (this clock)."""
        window = self.windows.get(robot)
        if window is not None:
            window.add(applied, received)

    def clear(self):
        """Forget every robot's samples (never beside add())."""
        for w in self.windows.values():
            w.clear()

    def diagnostic_values(self, _now=None):
        """Every robot's window values (the caller's clock is not this one: ignored)."""
        now = self.clock()
        return [kv for w in self.windows.values() for kv in w.diagnostic_values(now)]


# The stages in data-path order; 'command' is a consumer's (keys without a stage name);
# 'applied' rows are a simulator's command waits, measured from the command's receipt.
STAGES = ('recognized', 'published', 'command', 'applied')
_KEY = re.compile(r'^(?P<what>input age|command wait)(?: \((?P<stage>[^()]+)\))? '
                  r'(?:(?P<field>p50|p99) \(ms\b.*|samples)$')


def age_rows(name, values):
    """[(name, stage, p50 ms, p99 ms, samples)] from one diagnostic status's (key, value)
    pairs as diagnostic_values writes them, one per stage it reports (a command wait is
    stage 'applied', its robot added to the name); [] when it carries neither."""
    got = {}
    for key, value in values:
        m = _KEY.match(key)
        if m is None:
            continue
        if m.group('what') == 'command wait':
            row_key = ('%s %s' % (name, m.group('stage') or ''), 'applied')
        else:
            row_key = (name, m.group('stage') or 'command')
        row = got.setdefault(row_key, {})
        if m.group('field'):
            row[m.group('field')] = _ms(value)
        else:
            try:
                row['n'] = int(value)
            except (TypeError, ValueError):
                row['n'] = 0
    return [(row_name, stage, row.get('p50'), row.get('p99'), row.get('n', 0))
            for (row_name, stage), row in got.items()]


def _ms(text):
    try:
        x = float(text)
    except (TypeError, ValueError):
        return None            # 'n/a': no sample in the window
    return x if math.isfinite(x) else None


def _path_order(row):
    """Stage in data-path order (another stage's name after 'command', before the
    simulator's 'applied' rows, which close the table), then node."""
    name, stage = row[0], row[1]
    rank = STAGES.index(stage) if stage in STAGES else STAGES.index('applied') - 0.5
    return (rank, stage, name)


def age_table(rows):
    """The rows as a fixed-width text table in data-path order (stage, then node); a
    simulator's command waits ('applied') under a heading of their own."""
    def cell(x):
        return '%8.1f' % x if x is not None else '     n/a'

    def heading(title):
        return '%-36s %-10s %8s %8s %8s' % (title, 'stage', 'p50 ms', 'p99 ms', 'samples')
    lines, waits = [heading('capture -> stage (input age)')], False
    for name, stage, p50, p99, n in sorted(rows, key=_path_order):
        if stage == 'applied' and not waits:
            waits = True
            lines.append(heading('command -> applied (simulator)'))
        lines.append('%-36s %-10s %s %s %8d' % (name[:36], stage[:10], cell(p50), cell(p99), n))
    return '\n'.join(lines)


def node_name(status_name):
    """'ur10_1/ur10_arm: teleop' -> 'ur10_1/ur10_arm' (diagnostic_updater's names)."""
    return status_name.split(': ', 1)[0]


# A report heard by ROS time only stays on the board this long by wall time.
STOPPED_CLOCK_S = 60.0


class LatencyBoard:
    """The latest row of each (node, stage), as heard on /diagnostics, for a table, an
    overlay or a marker. on_status() and the readers may run on different threads: each
    update replaces the dict, readers take it whole."""

    def __init__(self, stale_after_s=5.0):
        self.stale_after_s = float(stale_after_s)
        self._rows = {}              # (status name, stage) -> (row, time heard)

    def on_status(self, name, values, now):
        """One DiagnosticStatus's name and (key, value) pairs; True if it had input ages."""
        rows = age_rows(name, values)
        if rows:
            new = dict(self._rows)
            for row in rows:
                new[row[0], row[1]] = (row, now)
            self._rows = new
        return bool(rows)

    def rows(self, now=None):
        """Every row (those not heard for stale_after_s dropped when `now` is given)."""
        return [row for row, heard in self._rows.values()
                if now is None or self._fresh(heard, now)]

    def _fresh(self, heard, now):
        """Heard within stale_after_s, by one clock (numbers) or, for tuples of readings
        (wall time first, as on_status got them), by wall time or by another clock within
        STOPPED_CLOCK_S of wall time: neither a slow simulation (reports a second of ROS
        time apart) nor a /clock looped back (a report 'heard' in the future) decides
        alone, and a /clock that stopped (a bag at its end, a paused simulator) keeps the
        last figures for a minute, not for ever."""
        if isinstance(now, tuple):
            wall = now[0] - heard[0]
            return 0.0 <= wall <= self.stale_after_s or (wall <= STOPPED_CLOCK_S and any(
                0.0 <= n - h <= self.stale_after_s for n, h in zip(now[1:], heard[1:])))
        return 0.0 <= now - heard <= self.stale_after_s

    def table(self, now=None):
        return age_table(self.rows(now))

    def summary_lines(self, now=None, stages=STAGES):
        """Short lines, data-path order: 'ur10_1/ur10_arm command 12.3 / 20.1 ms'."""
        lines = []
        for name, stage, p50, p99, n in sorted(self.rows(now), key=_path_order):
            if stage not in stages:
                continue
            if p50 is None and p99 is None:
                lines.append('%s %s: no samples' % (node_name(name), stage))
            else:       # another node's status may carry one figure only, or 'n/a'
                lines.append('%s %s: %s / %s ms' % (node_name(name), stage, *(
                    'n/a' if x is None else '%.1f' % x for x in (p50, p99))))
        return lines

    def notes(self, now=None):
        """What the camera overlay and the RViz text show: a title, then the sender's
        published and each consumer's command rows; [] when nothing reports."""
        lines = self.summary_lines(now, stages=('published', 'command'))
        return ['capture -> stage, p50 / p99:'] + lines if lines else []
