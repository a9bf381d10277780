"""The UR10 work cell as the ur10_sim node runs it, without ROS: its ~parameters, the queue
of planned commands the physics loop applies, the lock around the physics, what is due
each step (joint states, object poses, /clock, in sim time), pacing to the wall clock,
snapshots drawn from copied poses."""
import collections
import math
import threading
from dataclasses import dataclass

from leap_teleop.control.input_age import CommandWaits
from leap_teleop.params import Param
from leap_teleop.sim_runtime import (
    MAX_LAG_S,
    Every,
    RealtimePacer,
    pace_factor,
    release_snapshot_path,
    snapshot_path,
)
from leap_teleop.ur10.config import DEFAULT_CELL_CONFIG, read_cell_config
from leap_teleop.ur10.kinematics import JOINT_NAMES
from leap_teleop.ur10.model import GRIPPER_JOINT
from leap_teleop.ur10.snapshot import SnapshotRenderer
from leap_teleop.ur10.trajectory import TrajectoryError

RUNNER_PARAMS = {
    'config': Param(DEFAULT_CELL_CONFIG, 'cell YAML: a path or a file name in config/',
                    empty_ok=False, path=True),
    'gui': Param(False, 'open the PyBullet GUI window (needs a display)'),
    'realtime_factor': Param(1.0, 'sim speed vs wall time; 0 = as fast as possible (other '
                                  'than 1 only with /use_sim_time)', ge=0.0, le=100.0),
    # joint_states feed the arm nodes' joint watchdog: at least 10 Hz.
    'joint_state_rate': Param(125.0, 'joint_states rate per arm (UR CB3 controller; at most '
                                     'the cell\'s physics_hz)',
                              unit='Hz', ge=10.0, le=1000.0),
    # rospy drops the oldest of a subscriber's queue when its writer thread stalls: in
    # alternated soaks with a load burst, 20 lost joint states in all three runs, 100 in none
    'joint_states_queue_size': Param(100, 'joint_states messages queued per subscriber',
                                     ge=1, le=2000),
    'object_pose_rate': Param(30.0, '~object_poses rate (at most the cell\'s physics_hz)',
                              unit='Hz', gt=0.0, le=1000.0),
    'clock_rate': Param(240.0, '/clock rate with /use_sim_time (at most the physics rate)',
                        unit='Hz', ge=10.0, le=10000.0),
    'snapshot_dir': Param('', 'where ~snapshot writes PNGs (default ROS_HOME or /tmp)'),
    'snapshot_size': Param([640, 480], 'snapshot width, height', unit='px', length=2,
                           ge=16, le=4096),
}

MAX_PENDING = 100               # commands queued for the physics loop (bounded)
TROUBLE_S = 10.0                # wall s the cell's status stays WARN after a dropped or refused command
SNAPSHOT_TIMEOUT = 30.0         # s for one picture (the first one starts the renderer)
# A command stamped to start further ahead than this is most likely a wrong stamp (a stale
# or foreign clock): it is followed as the JTC would, from then on, but said so.
FAR_START_S = 5.0
# Command kind: (topic in the arm's namespace, the joints a command names).
KINDS = {'arm': ('arm_controller/command', tuple(JOINT_NAMES)),
         'gripper': ('gripper/command', (GRIPPER_JOINT,))}


@dataclass
class CellTick:
    """What one physics step has to publish (None / False: not due this step)."""
    time: float
    joint_states: dict = None       # {arm: (q, qd, gripper, gripper velocity)}
    object_poses: tuple = None      # (UR10Cell.object_poses(), {cube: arm holding it})
    clock: bool = False


class CellRunner:
    """UR10Cell behind one lock. Callbacks `queue` commands (bounded: when the loop stalls,
    older ones are dropped, the same controller's first: see _droppable); each `step`
    applies them, steps the physics and says what is due. `reject(arm, kind, why)` hears
    of a command the cell refused, `warn(arm, kind, what)` of one it takes but that starts
    over FAR_START_S ahead; `ros_time()` is the clock command stamps are in. command_waits
    keeps, per arm, how long its commands waited between queue() and the step that applied
    them (wall time)."""

    def __init__(self, p, use_sim_time, ros_time, reject, warn=None):
        from leap_teleop.ur10.cell import UR10Cell  # pybullet: after --help / --urdf
        self.p, self.ros_time, self.reject = p, ros_time, reject
        self.warn = warn or (lambda arm, kind, what: None)
        # Pictures come from the renderer process's own cell: this one, stepped, needs the
        # arms' visual meshes only for a GUI (they take ~0.5 s per arm to load).
        self.cell = UR10Cell(read_cell_config(p['config']), gui=bool(p['gui']),
                             visuals=bool(p['gui']))
        self.lock = threading.Lock()               # guards self.cell (physics)
        self.render_lock = threading.Lock()        # one snapshot at a time
        self.renderer = SnapshotRenderer(self.cell.config)
        self.pending = collections.deque()         # validated commands for the loop
        self._pending_lock = threading.Lock()      # queue() against the loop taking them
        self.dropped_commands = 0
        self.superseded_commands = 0              # replaced by a later one before they began
        self.command_waits = CommandWaits(self.cell.arm_names)
        self._counts_seen, self._trouble_at = (0, 0), -math.inf
        self.use_sim_time = use_sim_time
        self.factor, self.pace_warning = pace_factor(float(p['realtime_factor']),
                                                     use_sim_time)
        # what the node says once at start-up
        self.start_warnings = [w for w in [self.pace_warning] if w]
        hz = self.cell.config.physics_hz
        for name in ('joint_state_rate', 'object_pose_rate') + (
                ('clock_rate',) if use_sim_time else ()):     # no /clock without sim time
            if float(p[name]) > hz:
                self.start_warnings.append(
                    '~%s %g Hz is above the cell\'s physics_hz %g: published once per physics '
                    'step, %g Hz' % (name, float(p[name]), hz, hz))
        t = self.cell.time
        self.joint_states_due = Every(1.0 / float(p['joint_state_rate']), t)
        self.object_poses_due = Every(1.0 / float(p['object_pose_rate']), t)
        self.clock_due = Every(1.0 / float(p['clock_rate']), t)

    def queue(self, arm, kind, points, stamp):
        """Plan a validated command here, in the caller's thread, and queue the plan (stamp:
        ROS time s, 0 = start now); True when an older one had to be dropped for it (the
        loop is behind). A command the plan refuses is reported and not queued."""
        plan = self.cell.plan_arm if kind == 'arm' else self.cell.plan_gripper
        try:
            # Outside the physics lock: 10,000 points took 0.15-0.4 s to plan here, the
            # physics (and every arm's joint_states) stood still that long.
            points = plan(arm, points)
        except TrajectoryError as e:
            self.reject(arm, kind, e)
            return False
        with self._pending_lock:
            dropped = len(self.pending) >= MAX_PENDING
            if dropped:                            # the loop stalled: newer commands win
                del self.pending[self._droppable(arm, kind)]
                self.dropped_commands += 1
            self.pending.append((arm, kind, points, stamp, self.command_waits.clock()))
        return dropped

    def _droppable(self, arm, kind):
        """Where the command to drop for a new one of (arm, kind) sits in the full queue:
        the oldest of the same arm and controller, else the oldest that a later one of its
        own replaces, else the oldest trajectory (an arm node sends the next within 8 ms),
        else the oldest. A gripper goal is sent once, when it changes: dropped for another
        arm's trajectories, it was lost for good (the cube never released)."""
        keys = [c[:2] for c in self.pending]
        if (arm, kind) in keys:
            return keys.index((arm, kind))
        return next((i for i, k in enumerate(keys) if k in keys[i + 1:]),
                    next((i for i, k in enumerate(keys) if k[1] == 'arm'), 0))

    def _apply_pending(self):
        """Hand the commands queued before this step to the cell (lock held); those arriving
        meanwhile wait for the next step, so a burst of long commands cannot hold the
        physics (and joint_states) until it ends."""
        with self._pending_lock:
            batch = list(self.pending)
            self.pending.clear()
        # A command that a later one of the batch (same arm and controller) replaces
        # before it begins is not planned (ten 10,000-point ones held the physics for a
        # minute) - unless every such later one is refused: then it runs after all.
        waiting = {}                      # index -> indices of the later ones replacing it
        for i, (arm, kind, _, stamp, _) in enumerate(batch):
            later = {j for j in range(i + 1, len(batch)) if batch[j][:2] == (arm, kind)
                     and (batch[j][3] <= 0 or 0 < stamp and batch[j][3] <= stamp)}
            if later:
                waiting[i] = later
        refused = []
        for i in range(len(batch)):
            if i not in waiting and not self._apply(batch[i]):
                refused.append(i)
            while refused:                # the commands waiting on a refused one, in order
                j = refused.pop()
                for k in sorted(waiting):
                    waiting[k].discard(j)
                    if not waiting[k]:
                        del waiting[k]
                        if not self._apply(batch[k]):
                            refused.append(k)
        self.superseded_commands += len(waiting)

    def _apply(self, command):
        """One queued (planned) command to the cell; False when it refuses it (reported):
        by now only for ending in the past."""
        arm, kind, points, stamp, received = command
        cell = self.cell
        # A stamped start in ROS time -> cell time; 0 = now.
        start = None if stamp <= 0 else cell.time + (stamp - self.ros_time())
        follow = cell.command_arm if kind == 'arm' else cell.command_gripper
        try:
            follow(arm, points, start)
            self.command_waits.add(arm, received, self.command_waits.clock())
        except TrajectoryError as e:
            self.reject(arm, kind, e)
            return False
        if start is not None and start - cell.time > FAR_START_S:
            self.warn(arm, kind, 'starts in %.0f s (header.stamp %.3f, the clock %.3f); '
                      'until then the arm goes on with what it was doing, then holds'
                      % (start - cell.time, stamp, self.ros_time()))
        return True

    def step(self):
        """Apply the queued commands, step the physics once; a CellTick of what is due."""
        cell = self.cell
        with self.lock:
            self._apply_pending()
            cell.step()
            tick = CellTick(cell.time)
            if self.joint_states_due.due(tick.time):
                tick.joint_states = {a: cell.joint_state(a) for a in cell.arm_names}
            if self.object_poses_due.due(tick.time):
                tick.object_poses = (cell.object_poses(),
                                     {c: a for a in cell.arm_names
                                      for c in [cell.grasped(a)] if c is not None})
        tick.clock = self.use_sim_time and self.clock_due.due(tick.time)
        return tick

    def run(self, publish, stopped, on_behind=None):
        """step() then publish(tick) until stopped(); paced to ~realtime_factor.
        on_behind(lag) hears of each time the loop fell more than MAX_LAG_S behind."""
        pacer = RealtimePacer(self.factor, self.cell.time, MAX_LAG_S[bool(self.use_sim_time)],
                              on_behind=on_behind)
        while not stopped():
            tick = self.step()
            publish(tick)
            pacer.wait(tick.time)

    def reset(self):
        with self.lock:
            with self._pending_lock:
                self.pending.clear()
            self.cell.reset()
            self.command_waits.clear()      # waits from before the reset say nothing now

    def report(self, rejected):
        """The cell's /diagnostics (level, summary, values); `rejected` counts the commands
        refused so far (the node's and the cell's). WARN for TROUBLE_S (wall clock) after a
        command was refused or dropped: a count alone is easy to miss in a monitor. One
        caller thread (the diagnostics timer)."""
        now = self.command_waits.clock()
        dropped = self.dropped_commands          # the subscriber threads count on
        counts = (rejected, dropped)
        if counts != self._counts_seen:
            self._counts_seen, self._trouble_at = counts, now
        summary = 'arms %s' % ', '.join(self.cell.arm_names)
        trouble = now - self._trouble_at < TROUBLE_S
        if trouble:
            summary += '; commands refused or dropped in the last %g s' % TROUBLE_S
        return ('warn' if trouble else 'ok'), summary, [
            ('commands rejected', rejected),
            ('commands dropped (physics loop behind)', dropped),
            ('commands replaced before they began', self.superseded_commands)]

    def snapshot(self):
        """The path of a PNG of the cell now. Only the poses are copied under the physics
        lock; a renderer process draws them, so a slow render never delays joint_states.
        OSError, ValueError, TypeError, RuntimeError or TimeoutError when it cannot be."""
        w, h = self.p['snapshot_size']
        with self.lock:
            t, state = self.cell.time, self.cell.pose_state()
        path = snapshot_path(self.p['snapshot_dir'], 'ur10_sim', t)
        try:
            with self.render_lock:
                self.renderer.render(state, path, w, h, SNAPSHOT_TIMEOUT)
        except BaseException:
            release_snapshot_path(path)          # no empty file for a failed picture
            raise
        return path

    def close(self):
        with self.lock:
            self.cell.close()
        self.renderer.close()
