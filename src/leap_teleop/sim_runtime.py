"""How both simulator nodes run their physics loop, without ROS: pacing to the wall clock,
sim-time schedules for what they publish, and where their snapshots go."""
import itertools
import os
import time


def pace_factor(factor, use_sim_time):
    """(the real-time factor to run at, a warning or None): any factor but 1 only makes
    sense with /use_sim_time; without it the sim runs in real time instead. Every other node
    keeps wall time then: at 4x, a trajectory timed for 1 s ran in 0.25 s of theirs, the
    joints at 4 times their speed limits."""
    if factor != 1.0 and not use_sim_time:
        return 1.0, ('realtime_factor %g without /use_sim_time: running in real time instead '
                     '(the other nodes keep wall time)' % factor)
    return float(factor), None


# How far behind its schedule a simulation may sprint to catch up. In wall time the
# physics must keep up with the world's clock (a stall is made good within half a second);
# under /use_sim_time the simulation is the clock: a sprint would move everyone's time on
# by as much at once (every consumer then sees its input that much late, and an input
# gap that long), so after a stall longer than a few steps it simply runs on slower.
MAX_LAG_S = {False: 0.5, True: 0.02}


class RealtimePacer:
    """Holds a simulation at `factor` x wall time: `wait(sim_time)` after each step sleeps
    until the wall clock has caught up. More than `max_lag` s behind (a loaded machine; see
    MAX_LAG_S), it starts counting afresh instead of sprinting to catch up. factor 0 = as
    fast as possible (it only yields, so callbacks get in). on_behind(lag) hears of each
    fresh start, so a simulation that stalled can say so."""

    def __init__(self, factor, sim_time, max_lag=MAX_LAG_S[False], clock=time.monotonic,
                 sleep=time.sleep, on_behind=None):
        self.factor, self.max_lag = float(factor), max_lag
        self.clock, self.sleep = clock, sleep
        self.on_behind = on_behind      # on_behind(s behind) when it starts counting afresh
        self.restart(sim_time)

    def restart(self, sim_time):
        self.t0_wall, self.t0_sim = self.clock(), sim_time

    def wait(self, sim_time):
        """Sleep until `sim_time` is due; returns how long that was (< 0: behind)."""
        if self.factor <= 0:
            self.sleep(0)
            return 0.0
        delay = self.t0_wall + (sim_time - self.t0_sim) / self.factor - self.clock()
        if delay > 0:
            self.sleep(delay)
        elif delay < -self.max_lag:
            self.restart(sim_time)
            if self.on_behind is not None:
                self.on_behind(-delay)
        return delay


class Every:
    """Due at `start`, then once per `period` of sim time. A step more than a period late is
    one tick, not a burst of catch-up ones: the schedule starts again from its time."""

    def __init__(self, period, start):
        self.period, self.next = float(period), start

    def due(self, t):
        if t < self.next - 1e-9:
            return False
        self.next = max(self.next + self.period, t)
        return True


class SendGate:
    """At most once per `period` since the last send (`sent(now)`); a clock that went back
    (a reset, a bag played again) opens it at once. period None = always closed."""

    def __init__(self, period):
        self.period, self.last = period, None

    def open(self, now):
        return self.period is not None and (
            self.last is None or now < self.last or now - self.last >= self.period)

    def sent(self, now):
        self.last = now


def snapshot_path(folder, name, sim_time):
    """Where a snapshot taken at `sim_time` goes: `folder`, else ROS_HOME, else /tmp
    (created when missing), as NAME_<sim time>.png, or NAME_<sim time>_<n>.png when that
    name is taken: sim time starts at 0 again with each run of a simulator, and two pictures
    can fall in one step. The name is reserved as an empty file that the picture then
    fills, so callers at the same time never share one and no file is ever replaced;
    release_snapshot_path(path) when the picture could not be taken. OSError when the
    folder cannot be written."""
    folder = folder or os.environ.get('ROS_HOME') or '/tmp'
    os.makedirs(folder, exist_ok=True)
    stem = os.path.join(folder, '%s_%08.3f' % (name, sim_time))
    for n in itertools.count():
        path = '%s_%d.png' % (stem, n) if n else stem + '.png'
        try:
            with open(path, 'xb'):
                return path
        except FileExistsError:
            continue


PNG_END = b'IEND\xaeB`\x82'     # the last chunk of every whole PNG file


def release_snapshot_path(path):
    """Remove the file snapshot_path reserved when no whole picture was written to it
    (empty, or cut short: a renderer killed while writing, as at shutdown)."""
    try:
        with open(path, 'rb') as f:
            f.seek(0, os.SEEK_END)
            size = f.tell()
            f.seek(max(size - len(PNG_END), 0))
            whole = size > 0 and f.read() == PNG_END
        if not whole:
            os.remove(path)
    except OSError:          # gone already, or not ours to remove: nothing to give back
        pass
