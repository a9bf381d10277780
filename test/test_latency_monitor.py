"""latency_monitor: the per-stage input-age table from /diagnostics (pure part and the
command)."""
import os
import socket
import subprocess
import sys
import time

import pytest

from leap_teleop.control.input_age import (
    CommandWaits,
    InputAgeWindow,
    LatencyBoard,
    StageAges,
    age_rows,
    age_table,
)
from tools.bench.ros_processes import ros_master, spawn_node, stop_spawned

SCRIPTS = os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', 'scripts')


def test_rows_read_back_what_the_window_reports():
    w = InputAgeWindow(window_s=10.0)
    for i in range(100):
        w.add(1.0 + i * 0.01, 1.0 + i * 0.01 - 0.004 - (0.02 if i == 99 else 0.0))
    [(name, stage, p50, p99, n)] = age_rows('ur10_1/ur10_arm: teleop', w.diagnostic_values(2.0))
    assert name == 'ur10_1/ur10_arm: teleop' and stage == 'command' and n == 100
    assert p50 == pytest.approx(4.0, abs=0.05) and 4.0 < p99 <= 24.0


def test_a_sender_status_gives_one_row_per_stage():
    ages = StageAges(('recognized', 'published'))
    for i in range(50):
        ages.add('recognized', 1.0 + i * 0.01 + 0.001, 1.0 + i * 0.01)
        ages.add('published', 1.0 + i * 0.01 + 0.0015, 1.0 + i * 0.01)
    values = [('frames', '50')] + ages.diagnostic_values(2.0)
    rows = age_rows('leap_sender: hand stages', values)
    assert [(r[1], r[4]) for r in rows] == [('recognized', 50), ('published', 50)]
    assert rows[0][2] == pytest.approx(1.0) and rows[1][2] == pytest.approx(1.5)


def test_a_status_without_input_age_is_no_row_and_empty_windows_read_na():
    assert age_rows('camera: fps', [('fps', '30')]) == []
    [row] = age_rows('drone_pilot: pilot', InputAgeWindow().diagnostic_values(5.0))
    assert row == ('drone_pilot: pilot', 'command', None, None, 0)
    text = age_table([row, ('ur10_1/ur10_arm: teleop', 'command', 4.0, 9.5, 120)])
    lines = text.splitlines()
    assert 'p50 ms' in lines[0] and 'stage' in lines[0] and len(lines) == 3
    assert lines[1].startswith('drone_pilot: pilot') and 'n/a' in lines[1]
    assert lines[2].split()[-4:] == ['command', '4.0', '9.5', '120']


def test_the_table_is_in_data_path_order_and_the_board_forgets_silent_nodes():
    board = LatencyBoard(stale_after_s=5.0)
    arm = InputAgeWindow()
    arm.add(10.0, 9.99)
    sender = StageAges(('recognized', 'published'))
    sender.add('recognized', 10.0, 9.998)
    sender.add('published', 10.0, 9.997)
    assert board.on_status('ur10_1/ur10_arm: teleop', arm.diagnostic_values(10.0), 10.0)
    assert board.on_status('leap_sender: hand stages', sender.diagnostic_values(10.0), 10.0)
    assert not board.on_status('camera: fps', [('fps', '30')], 10.0)
    stages = [line.split()[-4] for line in board.table().splitlines()[1:]]
    assert stages == ['recognized', 'published', 'command']
    assert board.notes(12.0) == ['capture -> stage, p50 / p99:',
                                 'leap_sender published: 3.0 / 3.0 ms',
                                 'ur10_1/ur10_arm command: 10.0 / 10.0 ms']
    assert board.on_status('leap_sender: hand stages', sender.diagnostic_values(14.0), 14.0)
    assert [r[0] for r in board.rows(16.0)] == ['leap_sender: hand stages'] * 2
    assert board.notes(30.0) == []


def test_the_monitors_table_drops_a_node_that_stopped_reporting(monkeypatch):
    """A dead arm's last numbers once stayed in every refresh, as if it were alive."""
    import rospy
    from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue

    from leap_teleop.ros.latency_monitor import LatencyMonitor
    arm = InputAgeWindow()
    arm.add(10.0, 9.99)
    status = DiagnosticStatus(name='ur10_1/ur10_arm: teleop', values=[
        KeyValue(k, str(v)) for k, v in arm.diagnostic_values(10.0)])
    now = [10.0]
    monkeypatch.setattr(rospy, 'get_time', lambda: 1000.0 - now[0])   # not its clock
    monitor = LatencyMonitor(subscribe=False, clock=lambda: now[0])
    monitor.on_diagnostics(DiagnosticArray(status=[status]))
    now[0] = 12.0
    assert 'ur10_1/ur10_arm' in monitor.table()
    now[0] = 21.5                           # stale after 5 s
    assert 'ur10_1/ur10_arm' not in monitor.table()
    assert monitor.table().startswith('capture -> stage')


def test_a_simulators_command_waits_are_rows_of_their_own_after_the_commands():
    clock = [50.0]
    waits = CommandWaits(('ur10_1', 'ur10_2'), clock=lambda: clock[0])
    for i in range(40):
        waits.add('ur10_1', 40.0 + i * 0.1, 40.0 + i * 0.1 + 0.002)
    waits.add('ur10_9', 49.0, 49.5)                   # not a robot of this cell: no sample
    values = waits.diagnostic_values(123456.0)      # another clock's now: ignored
    assert not any(k.startswith('input age') for k, _ in values)
    rows = age_rows('ur10_sim: cell', values)
    assert [(r[0], r[1], r[4]) for r in rows] == [('ur10_sim: cell ur10_1', 'applied', 40),
                                                  ('ur10_sim: cell ur10_2', 'applied', 0)]
    assert rows[0][2] == pytest.approx(2.0) and rows[1][2] is None
    board = LatencyBoard()
    arm = InputAgeWindow()
    arm.add(10.0, 9.99)
    board.on_status('ur10_sim: cell', values, 10.0)
    board.on_status('ur10_1/ur10_arm: teleop', arm.diagnostic_values(10.0), 10.0)
    lines = board.table().splitlines()
    assert lines[0].startswith('capture -> stage') and lines[1].split()[-4] == 'command'
    assert lines[2].startswith('command -> applied (simulator)')
    assert [line.split()[:4] for line in lines[3:]] == [
        ['ur10_sim:', 'cell', 'ur10_1', 'applied'], ['ur10_sim:', 'cell', 'ur10_2', 'applied']]
    assert board.notes(10.0) == ['capture -> stage, p50 / p99:',
                                 'ur10_1/ur10_arm command: 10.0 / 10.0 ms']
    # Any robot name between the brackets; a stage of another name stays among the ages.
    assert age_rows('sim: cell', [('command wait (cell/arm_2) samples', '3')]) == [
        ('sim: cell cell/arm_2', 'applied', None, None, 3)]
    text = age_table(rows + [('filter: hands', 'filtered', 1.0, 2.0, 5)])
    assert [line.split()[0] for line in text.splitlines()] == [
        'capture', 'filter:', 'command', 'ur10_sim:', 'ur10_sim:']


@pytest.mark.integration
def test_the_command_prints_the_pilots_row_from_a_running_node():
    with ros_master() as env:
        pilot = spawn_node(env, [sys.executable, os.path.join(SCRIPTS, 'drone_pilot.py')])
        try:
            p = subprocess.run([sys.executable, os.path.join(SCRIPTS, 'latency_monitor'),
                                '--once', '--timeout', '60'], env=env, capture_output=True,
                               text=True, timeout=120)
        finally:
            stop_spawned(pilot)
    assert p.returncode == 0, p.stderr[-2000:]
    assert 'capture -> stage' in p.stdout and 'drone_pilot' in p.stdout, p.stdout


def test_a_report_is_stale_only_when_wall_and_ros_time_both_say_so():
    # Timed on wall time alone, a simulation at 0.1x (reports a second of ROS time apart)
    # lost its rows; on ROS time alone, a /clock looped back kept a silent node's for ever.
    board = LatencyBoard()
    arm = InputAgeWindow()
    arm.add(10.0, 9.99)
    board.on_status('ur10_1/ur10_arm: teleop', arm.diagnostic_values(10.0), (100.0, 10.0))
    assert board.rows((108.0, 10.8))                   # slow simulation: 0.8 s of ROS time
    assert board.rows((101.0, 2.0))                    # looped back, heard 1 s ago
    assert not board.rows((108.0, 2.0))                # looped back, silent for 8 s
    assert not board.rows((108.0, 18.0))               # silent on both clocks
    assert board.rows((108.0, 14.0)) and not board.rows((108.0, 15.5))


def test_a_report_on_a_stopped_ros_clock_drops_out_within_a_minute_of_wall_time():
    # A bag at its end or a paused simulator: ROS time stood still, so every report stayed
    # "heard 0 s ago" and the last figures were shown for ever.
    board = LatencyBoard()
    arm = InputAgeWindow()
    arm.add(10.0, 9.99)
    board.on_status('ur10_1/ur10_arm: teleop', arm.diagnostic_values(10.0), (100.0, 120.0))
    assert board.rows((130.0, 120.0))                  # a slow simulation: still shown
    assert not board.rows((170.0, 120.0))              # the clock stopped: gone


@pytest.mark.parametrize('p99', [None, 'n/a', 'inf', 'nan'])
def test_a_status_with_one_figure_is_a_line_not_a_crash(p99):
    # p50 without p99 raised TypeError in the camera overlay (ending the sender's hand
    # source) and in hand_markers' timer (ending its thread)
    board = LatencyBoard()
    values = [('input age p50 (ms)', '3.1'), ('input age samples', '20')]
    values += [] if p99 is None else [('input age p99 (ms)', p99)]
    assert board.on_status('ur10_1/ur10_arm: teleop', values, 1.0)
    assert board.notes(1.0) == ['capture -> stage, p50 / p99:', 'ur10_1/ur10_arm command: 3.1 / n/a ms']


def test_the_table_goes_on_when_the_ros_clock_jumps_back(monkeypatch, capsys):
    # rospy.sleep raised on a /clock looped back (a bag played again, sim time), which main
    # took for Ctrl-C: the table stopped silently with status 0.
    import types

    import rospy

    from leap_teleop.ros import latency_monitor as lm

    def moved_back(*_args):
        raise rospy.exceptions.ROSTimeMovedBackwardsException(1.0)
    tables = []
    heard = types.SimpleNamespace(wait=lambda timeout: True)
    monkeypatch.setattr(lm, 'master_problem', lambda timeout: ('http://x:1', None, False))
    monkeypatch.setattr(rospy, 'init_node', lambda *a, **kw: None)
    monkeypatch.setattr(rospy, 'sleep', moved_back)
    monkeypatch.setattr(rospy, 'is_shutdown', lambda: len(tables) >= 3)
    monkeypatch.setattr(lm.time, 'sleep', lambda s: None)
    monkeypatch.setattr(lm, 'LatencyMonitor', lambda: types.SimpleNamespace(
        heard=heard, table=lambda: tables.append(1) or 'capture -> stage'))
    assert lm.main([]) == 0
    assert len(tables) == 3 and capsys.readouterr().out.count('capture -> stage') == 3


def test_main_takes_its_arguments_without_the_program_name():
    from leap_teleop.ros.latency_monitor import main
    with pytest.raises(SystemExit) as e:
        main(['--no-such-option'])       # refused by the parser, before any ROS call
    assert e.value.code == 2


@pytest.fixture
def no_init_node(monkeypatch):
    # Without a master rospy.init_node retries forever: it must not be reached.
    import rospy

    def refuse(*_args, **_kw):
        raise AssertionError('init_node without a master: it would keep trying forever')
    monkeypatch.setattr(rospy, 'init_node', refuse)


@pytest.mark.parametrize('value', ['nan', '-1', '0', 'inf', '1e10'])
def test_a_timeout_that_is_not_a_positive_number_is_refused(value, capsys, no_init_node):
    from leap_teleop.ros.latency_monitor import main
    with pytest.raises(SystemExit) as e:
        main(['--once', '--timeout', value])     # nan was taken: "... in nan s"
    assert e.value.code == 2
    assert 'error: --timeout must be a number of seconds > 0' in capsys.readouterr().err


def closed_port():
    with socket.socket() as s:
        s.bind(('127.0.0.1', 0))
        return s.getsockname()[1]


def test_no_master_is_one_line_and_status_1(monkeypatch, capsys, no_init_node):
    from leap_teleop.ros.latency_monitor import main
    uri = 'http://127.0.0.1:%d' % closed_port()
    monkeypatch.setenv('ROS_MASTER_URI', uri)
    assert main(['--once', '--timeout', '2']) == 1
    err = capsys.readouterr().err
    assert err.startswith('latency_monitor: no ROS master at %s (' % uri) and err.count('\n') == 1


def test_a_master_that_does_not_answer_is_given_up_after_the_timeout(monkeypatch, capsys,
                                                                       no_init_node):
    from leap_teleop.ros.latency_monitor import main
    with socket.socket() as mute:         # accepts connections (backlog), never replies
        mute.bind(('127.0.0.1', 0))
        mute.listen(4)
        uri = 'http://127.0.0.1:%d' % mute.getsockname()[1]
        monkeypatch.setenv('ROS_MASTER_URI', uri)
        start = time.monotonic()
        assert main(['--once', '--timeout', '0.5']) == 1
        assert time.monotonic() - start < 5.0
    assert capsys.readouterr().err.startswith('latency_monitor: no ROS master at %s' % uri)
    assert socket.getdefaulttimeout() is None     # the check's timeout is not left behind


@pytest.mark.parametrize('server, says', [('http_501', '(HTTP 501'), ('html_200', '(ResponseError'),
                                           ('xmlrpc_no_getpid', '(<Fault 1')])
def test_a_server_that_answers_but_is_not_a_master_is_given_up_at_once(server, says, monkeypatch,
                                                                         capsys, no_init_node):
    # It answers, so waiting for it to become a master cannot help: the monitor used to
    # ask it again every 0.5 s for the whole timeout.
    import http.server
    import threading
    from xmlrpc.server import SimpleXMLRPCServer

    from leap_teleop.ros.latency_monitor import main

    class Quiet(http.server.BaseHTTPRequestHandler):
        def log_message(self, *_args):
            pass

    class Html(Quiet):
        def do_POST(self):
            self.rfile.read(int(self.headers.get('Content-Length', 0)))
            body = b'<html><body>hello</body></html>'
            self.send_response(200)
            self.send_header('Content-Length', str(len(body)))
            self.end_headers()
            self.wfile.write(body)
    if server == 'xmlrpc_no_getpid':
        srv = SimpleXMLRPCServer(('127.0.0.1', 0), logRequests=False)
    else:
        srv = http.server.HTTPServer(('127.0.0.1', 0), Html if server == 'html_200' else Quiet)
    threading.Thread(target=srv.serve_forever, daemon=True).start()
    try:
        uri = 'http://127.0.0.1:%d' % srv.server_address[1]
        monkeypatch.setenv('ROS_MASTER_URI', uri)
        start = time.monotonic()
        assert main(['--once', '--timeout', '20']) == 1
        assert time.monotonic() - start < 5.0
    finally:
        srv.shutdown()
        srv.server_close()
    err = capsys.readouterr().err
    assert err.startswith('latency_monitor: no ROS master at %s %s' % (uri, says)) and err.count('\n') == 1


def test_a_master_that_comes_up_within_the_timeout_is_waited_for(monkeypatch):
    # Started beside a roslaunch, the monitor gave up in 0.7 s on a master that came up
    # in 3, though --timeout promises to wait for it.
    import rospy

    import leap_teleop.ros.latency_monitor as lm
    asked = []

    def master_problem(timeout):
        asked.append(time.monotonic())
        return 'http://x:1', ('Connection refused' if len(asked) < 3 else None), True

    class Reached(Exception):
        pass

    def init_node(*_a, **_k):
        raise Reached()
    monkeypatch.setattr(lm, 'master_problem', master_problem)
    monkeypatch.setattr(rospy, 'init_node', init_node)
    with pytest.raises(Reached):
        lm.main(['--once', '--timeout', '10'])
    assert len(asked) == 3 and asked[-1] - asked[0] < 5.0


def test_ctrl_c_while_waiting_for_the_master_is_no_traceback(monkeypatch, no_init_node):
    import leap_teleop.ros.latency_monitor as lm

    def interrupted(timeout):
        raise KeyboardInterrupt()
    monkeypatch.setattr(lm, 'master_problem', interrupted)
    try:
        assert lm.main(['--once', '--timeout', '10']) == 1
    except KeyboardInterrupt:
        pytest.fail('Ctrl-C while waiting for the master raised out of main')
