"""CellRunner and --urdf: what the ur10_sim node runs, without a master."""
import numpy as np
import pytest

from leap_teleop.params import check_params
from leap_teleop.ur10 import cell_runner, trajectory
from leap_teleop.ur10.cell_runner import KINDS, RUNNER_PARAMS, CellRunner
from leap_teleop.ur10.config import CellConfigError, load_config
from leap_teleop.ur10.kinematics import HOME_Q, JOINT_NAMES
from leap_teleop.ur10.model import build_urdf, print_urdf, urdf_from_args

# needs a ROS master, a simulator, a subprocess or a build: not in make check
pytestmark = pytest.mark.integration

ARM = 'ur10_1'


class RosTimeStub:
    """The ROS clock command stamps are read against."""
    now = 1000.0

    def __call__(self):
        return self.now


@pytest.fixture
def rejected():
    return []


def make(rejected, use_sim_time=True, **values):
    p = check_params(RUNNER_PARAMS, dict({'realtime_factor': 0.0}, **values))
    return CellRunner(p, use_sim_time, RosTimeStub(), lambda *why: rejected.append(why))


@pytest.fixture
def runner(rejected):
    r = make(rejected)
    yield r
    r.close()


def test_command_kinds_name_the_controllers_joints():
    assert KINDS['arm'] == ('arm_controller/command', tuple(JOINT_NAMES))
    assert KINDS['gripper'] == ('gripper/command', ('finger_joint',))


def test_each_arm_reports_how_long_its_commands_waited_for_the_physics(runner):
    q = np.array(HOME_Q) + [0.1, 0, 0, 0, 0, 0]
    for _ in range(3):
        runner.queue(ARM, 'arm', [(0.5, q, None)], 0.0)
        runner.step()
    runner.queue(ARM, 'arm', [(0.5, [np.nan] * 6, None)], 0.0)     # refused: no sample
    runner.step()
    p50, p99, n = runner.command_waits.windows[ARM].summary(runner.command_waits.clock())
    assert n == 3 and 0.0 <= p50 <= p99 < 1.0
    assert set(runner.command_waits.windows) == set(runner.cell.arm_names)
    runner.reset()                                  # waits from before a reset are gone
    assert runner.command_waits.windows[ARM].summary(runner.command_waits.clock())[2] == 0
    runner.queue(ARM, 'arm', [(0.5, q, None)], 0.0)
    runner.step()
    assert runner.command_waits.windows[ARM].summary(runner.command_waits.clock())[2] == 1


def test_commands_a_later_one_replaces_before_they_begin_are_not_planned(runner, rejected, monkeypatch):
    # The physics step applies every queued command: ten 10,000-point ones held it (and
    # joint_states, /clock) for a minute, though each replaced the one before at once.
    planned = []
    real = runner.cell.command_arm
    monkeypatch.setattr(runner.cell, 'command_arm', lambda arm, plan, start: planned.append(
        plan.points[0][0]) or real(arm, plan, start))
    q = runner.cell.joint_state(ARM)[0]
    t = runner.ros_time()
    runner.queue(ARM, 'arm', [(0.1, q, None)], 0.0)            # replaced by the next
    runner.queue(ARM, 'arm', [(0.2, q, None)], t + 5.0)        # starts later than the next
    runner.queue(ARM, 'arm', [(0.3, q, None)], 0.0)            # now: replaces both above
    runner.queue(ARM, 'arm', [(0.4, q, None)], t + 1.0)        # starts later: kept
    runner.queue(ARM, 'gripper', [(0.5, [0.1], None)], 0.0)    # another controller: kept
    runner.step()
    assert planned == [0.3, 0.4] and runner.superseded_commands == 2
    assert dict(runner.report(0)[2])['commands replaced before they began'] == 2
    # A later command the cell refuses replaces nothing: what it would have replaced runs.
    planned.clear()
    bad = q.copy()
    bad[2] = 4.0                                              # the elbow beyond +-pi
    runner.queue(ARM, 'arm', [(0.6, q, None)], t)
    runner.queue(ARM, 'arm', [(0.7, q, None)], t)
    runner.queue(ARM, 'arm', [(0.8, bad, None)], t)             # refused as it is queued
    runner.queue(ARM, 'arm', [(0.9, q, None)], t - 100.0)       # refused: over by now
    runner.step()
    assert planned == [0.9, 0.7] and runner.superseded_commands == 3
    assert len(rejected) == 2 and runner.cell.arm(ARM).arm_follower.active


def test_a_long_command_is_planned_as_it_is_queued_not_in_the_physics_step(runner, monkeypatch):
    # Planning 10,000 points took 0.15-0.4 s; in step(), under the physics lock, it held the
    # physics and every arm's joint_states that long.
    home = np.array(HOME_Q)
    points = [(0.01 * k, home + [0.2 * np.sin(0.01 * k), 0, 0, 0, 0, 0], None)
              for k in range(1, 1001)]
    ratios = []
    real = trajectory._peak_ratio
    monkeypatch.setattr(trajectory, '_peak_ratio', lambda seg, vmax: ratios.append(seg) or real(seg, vmax))
    runner.queue(ARM, 'arm', points, 0.0)
    queued = len(ratios)
    runner.step()
    assert queued >= 999 and len(ratios) - queued <= 1
    runner.cell.run(10.5)
    assert runner.cell.joint_state(ARM)[0][0] == pytest.approx(points[-1][1][0], abs=1e-3)


def test_the_cell_warns_for_a_while_after_a_dropped_or_refused_command(runner, monkeypatch):
    now = [100.0]
    monkeypatch.setattr(runner.command_waits, 'clock', lambda: now[0])
    monkeypatch.setattr(cell_runner, 'MAX_PENDING', 1)
    level, summary, values = runner.report(0)
    assert level == 'ok' and summary == 'arms ur10_1'
    assert dict(values) == {'commands rejected': 0, 'commands dropped (physics loop behind)': 0,
                            'commands replaced before they began': 0}
    runner.queue(ARM, 'gripper', [(0.1, [0.1], None)], 0.0)
    runner.queue(ARM, 'gripper', [(0.2, [0.1], None)], 0.0)       # drops the first
    now[0] += 1.0
    level, summary, values = runner.report(0)
    assert level == 'warn' and 'refused or dropped' in summary
    assert dict(values)['commands dropped (physics loop behind)'] == 1
    now[0] += cell_runner.TROUBLE_S - 0.5
    assert runner.report(0)[0] == 'warn'
    now[0] += 1.0
    assert runner.report(0)[0] == 'ok'                              # nothing new since
    assert runner.report(3)[0] == 'warn'                            # three refused
    now[0] += cell_runner.TROUBLE_S + 0.1
    assert runner.report(3)[0] == 'ok'


def test_queued_commands_apply_at_the_next_step_stamped_in_ros_time(runner):
    q = np.array(HOME_Q) + [0.2, 0, 0, 0, 0, 0]
    assert not runner.queue(ARM, 'arm', [(0.5, q, None)], 0.0)
    assert not runner.queue(ARM, 'gripper', [(0.2, [0.4], None)], 0.0)
    runner.step()
    assert not runner.pending
    runner.cell.run(1.5)
    q_now, _, knuckle, _ = runner.cell.joint_state(ARM)
    assert q_now[0] == pytest.approx(q[0], abs=1e-3) and knuckle == pytest.approx(0.4, abs=0.02)
    # A start stamped 2 s ahead of the ROS clock starts 2 s ahead in cell time.
    back = np.array(HOME_Q)
    runner.queue(ARM, 'arm', [(0.5, back, None)], runner.ros_time.now + 2.0)
    runner.step()
    runner.cell.run(1.5)
    assert runner.cell.joint_state(ARM)[0][0] == pytest.approx(q[0], abs=1e-3)   # not yet
    runner.cell.run(1.5)
    assert runner.cell.joint_state(ARM)[0][0] == pytest.approx(back[0], abs=1e-3)


def test_a_refused_command_is_reported_and_the_arm_keeps_its_trajectory(runner, rejected):
    runner.queue(ARM, 'arm', [], 0.0)                  # no points: the follower refuses it
    runner.step()
    assert len(rejected) == 1 and rejected[0][:2] == (ARM, 'arm')
    assert 'empty trajectory' in str(rejected[0][2])


def test_a_stalled_loop_drops_the_oldest_commands(runner, monkeypatch):
    monkeypatch.setattr(cell_runner, 'MAX_PENDING', 3)
    drops = [runner.queue(ARM, 'gripper', [(0.1 * (i + 1), [0.1], None)], 0.0) for i in range(5)]
    assert drops == [False, False, False, True, True] and runner.dropped_commands == 2
    assert [p[2].points[0][0] for p in runner.pending] == pytest.approx([0.3, 0.4, 0.5])
    runner.reset()
    assert not runner.pending


@pytest.fixture
def dual_runner(rejected):
    r = make(rejected, config='ur10_dual_cell.yaml')
    yield r
    r.close()


def test_a_stalled_loop_drops_a_later_trajectory_not_a_gripper_goal(dual_runner, monkeypatch):
    # The oldest command of any arm went: a gripper goal, which the arm node sends once,
    # dropped for the trajectories streaming after it, and the gripper never closed.
    runner = dual_runner
    monkeypatch.setattr(cell_runner, 'MAX_PENDING', 3)
    other = [a for a in runner.cell.arm_names if a != ARM][0]
    q = list(HOME_Q)
    runner.queue(ARM, 'gripper', [(0.1, [0.8], None)], 0.0)
    runner.queue(other, 'arm', [(0.1, q, None)], 0.0)
    for i in range(4):
        runner.queue(ARM, 'arm', [(0.1 * (i + 1), q, None)], 0.0)
    kinds = [(arm, kind) for arm, kind, *_ in runner.pending]
    assert kinds == [(ARM, 'gripper'), (other, 'arm'), (ARM, 'arm')] and runner.dropped_commands == 3
    assert runner.pending[2][2].points[-1][0] == pytest.approx(0.4)     # the newest kept
    runner.queue(other, 'gripper', [(0.1, [0.8], None)], 0.0)      # none of its own: a trajectory
    assert [(arm, kind) for arm, kind, *_ in runner.pending] == [
        (ARM, 'gripper'), (ARM, 'arm'), (other, 'gripper')]


def test_a_rate_above_the_physics_rate_is_said_at_start_up(rejected):
    # ~joint_state_rate took 1000 Hz and gave 240, one per physics step, silently.
    r = make(rejected, joint_state_rate=1000.0)
    try:
        assert r.start_warnings == ["~joint_state_rate 1000 Hz is above the cell's physics_hz "
                                    "240: published once per physics step, 240 Hz"]
        ticks = [r.step() for _ in range(240)]
        assert sum(t.joint_states is not None for t in ticks) == 240
    finally:
        r.close()
    r = make(rejected)
    try:
        assert r.start_warnings == []
    finally:
        r.close()
    for use_sim_time in (False, True):          # no /clock without sim time: no warning
        r = make(rejected, use_sim_time=use_sim_time, clock_rate=1000.0)
        try:
            assert [w.split()[0] for w in r.start_warnings if w.startswith('~')] == (
                ['~clock_rate'] if use_sim_time else [])
        finally:
            r.close()


def test_ticks_carry_what_is_due_at_its_rate(rejected):
    r = make(rejected, joint_state_rate=120.0, object_pose_rate=30.0, clock_rate=60.0)
    try:
        ticks = [r.step() for _ in range(240)]             # 1 s at 240 Hz
    finally:
        r.close()
    steps = {what: [round(t.time * 240) for t in ticks if getattr(t, what)]
             for what in ('joint_states', 'object_poses', 'clock')}
    # Due at the first step, then once per period (the schedules count from t = 0).
    assert steps['joint_states'][:4] == [1, 2, 4, 6] and len(steps['joint_states']) == 121
    assert steps['object_poses'][:3] == [1, 8, 16] and len(steps['object_poses']) == 31
    assert steps['clock'][:3] == [1, 4, 8] and len(steps['clock']) == 61
    assert set(ticks[0].joint_states) == {ARM}
    poses, grasped = ticks[0].object_poses
    assert set(poses) == {'cube_red', 'cube_green', 'cube_blue'} and grasped == {}
    assert ticks[-1].time == pytest.approx(1.0)


def test_no_clock_without_sim_time(rejected):
    r = make(rejected, use_sim_time=False, realtime_factor=1.0)
    try:
        assert not any(r.step().clock for _ in range(10))
        assert r.factor == 1.0 and r.pace_warning is None
    finally:
        r.close()


def test_run_publishes_every_step_until_stopped(runner):
    ticks = []
    runner.run(ticks.append, lambda: len(ticks) >= 48)
    assert len(ticks) == 48 and ticks[-1].time == pytest.approx(0.2)


def test_snapshots_in_one_step_or_a_later_run_never_replace_a_picture(rejected, tmp_path):
    # Named by sim time alone, the second picture of a step, or one a later run took at the
    # same sim time (each run starts at 0), replaced the first; both answers named one file.
    import os
    folder = tmp_path / 'snaps'
    paths = []
    for _ in range(2):                                       # two runs of the simulator
        r = make(rejected, snapshot_dir=str(folder), snapshot_size=[32, 24])
        try:
            for _ in range(2):
                r.step()
            paths += [r.snapshot(), r.snapshot()]            # twice in one step
        finally:
            r.close()
    assert len(set(paths)) == 4 and sorted(os.listdir(folder)) == sorted(map(os.path.basename, paths))
    assert paths[0] == str(folder / 'ur10_sim_0000.008.png')
    for path in paths:
        with open(path, 'rb') as f:
            assert f.read(8) == b'\x89PNG\r\n\x1a\n'


def test_a_failed_snapshot_leaves_no_empty_file(runner, tmp_path, monkeypatch):
    runner.p['snapshot_dir'] = str(tmp_path)

    def fails(*_args):
        raise RuntimeError('renderer gone')
    monkeypatch.setattr(runner.renderer, 'render', fails)
    with pytest.raises(RuntimeError, match='renderer gone'):
        runner.snapshot()
    assert list(tmp_path.iterdir()) == []


def test_urdf_from_args_is_the_arms_description():
    arm = load_config('ur10_dual_cell').arm('ur10_2')
    text = urdf_from_args(['--urdf', 'ur10_2', '--config', 'ur10_dual_cell'])
    assert text == build_urdf(arm.prefix, arm.base_xyz, arm.base_rpy)
    assert 'ur10_2_shoulder_pan_joint' in text
    with pytest.raises(CellConfigError, match="no arm 'no_such_arm'"):
        urdf_from_args(['--urdf', 'no_such_arm'])


BAD_CELLS = [
    # (file text or None for a missing file, what the one line says)
    (None, 'No such file or directory'),
    ('arms: [\n', 'not valid YAML (line 2: '),
    ('arms: [1]\n', 'an entry of the wrong shape'),
    ('arms:\n  - {base_xyz: [0, 0, 0]}\n', "an entry lacks 'name'"),
    ('arms:\n  - {name: ur10_1, base_xyz: [1, 2]}\n', 'base_xyz must be 3 numbers'),
    ('arms: []\n', 'needs a non-empty "arms" list'),
    ('arms:\n  - {name: ur10_1}\n', "no arm 'ur10_9' in the cell"),
    # cubes the physics cannot start from: one was dropped from the poses, or fell through
    # the table, or both were thrown apart
    ('arms:\n  - {name: ur10_9}\ncubes:\n  - {name: a, xyz: [0.7, 0]}\n  - {name: a, xyz: [0.7, 0.3]}\n',
     "cube names must be unique, 'a' twice"),
    ('arms:\n  - {name: ur10_9}\ncubes:\n  - {name: a, xyz: [0.7, 0, 0.74]}\n',
     "cube 'a' at z 0.740 m is inside the table top (0.750 m)"),
    ('arms:\n  - {name: ur10_9}\ncubes:\n  - {name: a, xyz: [0.7, 0, 0.72]}\n',    # wholly in it
     "cube 'a' at z 0.720 m is inside the table top (0.750 m)"),
    ('arms:\n  - {name: ur10_9}\ncubes:\n  - {name: a, xyz: [0.7, 0]}\n  - {name: b, xyz: [0.72, 0.01]}\n',
     "cubes 'a' and 'b' are inside each other"),
]


@pytest.mark.parametrize('text, why', BAD_CELLS, ids=[b[1] for b in BAD_CELLS])
def test_urdf_of_a_bad_cell_is_one_line_and_status_1(text, why, tmp_path, capsys):
    # Every sim launch runs --urdf for robot_description: it once ended in a traceback.
    path = tmp_path / 'cell.yaml'
    if text is not None:
        path.write_text(text)
    with pytest.raises(SystemExit) as e:
        print_urdf(['--urdf', 'ur10_9', '--config', str(path)])
    line = str(e.value.code)        # a str: Python prints it on stderr, status 1
    assert line.startswith('ur10_sim.py --urdf: cell config %s: ' % path) and why in line, line
    assert '\n' not in line and capsys.readouterr().out == ''


def test_the_node_reports_a_cell_that_is_not_yaml_as_a_bad_parameter(tmp_path):
    # start_node turns a ValueError into its one fatal line; a YAML error was a traceback.
    path = tmp_path / 'cell.yaml'
    path.write_text('arms: [\n')
    with pytest.raises(ValueError, match='not valid YAML'):
        make([], config=str(path))


def test_two_arms_on_one_base_are_refused_before_the_physics_throws_them_apart(tmp_path):
    # Accepted before: within seconds the joints read 8.7 rad and the cubes flew 50 m.
    path = tmp_path / 'cell.yaml'
    path.write_text('arms:\n  - {name: ur10_1, base_xyz: [0, 0, 0.75]}\n'
                    '  - {name: ur10_2, base_xyz: [0, 0.1, 0.75]}\n')
    with pytest.raises(ValueError, match='arms ur10_1 and ur10_2 touch at their home poses'):
        make([], config=str(path))


def test_the_nodes_urdf_mode_ends_in_the_one_line(capsys):
    from leap_teleop.ros.nodes.ur10_sim import main
    with pytest.raises(SystemExit) as e:
        main(['--urdf', 'ur10_9'])
    assert str(e.value.code).startswith('ur10_sim.py --urdf: cell config ')
    main(['--urdf', 'ur10_1'])
    assert 'ur10_1_shoulder_pan_joint' in capsys.readouterr().out
