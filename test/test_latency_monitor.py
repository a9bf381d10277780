"""latency_monitor: the input-age table from /diagnostics (pure part and the command)."""
import os
import subprocess
import sys

import pytest

from leap_teleop.control.input_age import InputAgeWindow, age_row, age_table
from tools.bench.ros_processes import ros_master, spawn_node, stop_spawned

SCRIPTS = os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', 'scripts')


def test_rows_read_back_what_the_window_reports():
    w = InputAgeWindow(window_s=10.0)
    for i in range(100):
        w.add(1.0 + i * 0.01, 1.0 + i * 0.01 - 0.004 - (0.02 if i == 99 else 0.0))
    name, p50, p99, n = age_row('/ur10_1/ur10_arm: teleop', w.diagnostic_values(2.0))
    assert name == '/ur10_1/ur10_arm: teleop' and n == 100
    assert p50 == pytest.approx(4.0, abs=0.05) and 4.0 < p99 <= 24.0


def test_a_status_without_input_age_is_no_row_and_empty_windows_read_na():
    assert age_row('/camera: fps', [('fps', '30')]) is None
    row = age_row('/drone_pilot: pilot', InputAgeWindow().diagnostic_values(5.0))
    assert row == ('/drone_pilot: pilot', None, None, 0)
    text = age_table([row, ('/ur10_1/ur10_arm: teleop', 4.0, 9.5, 120)])
    lines = text.splitlines()
    assert 'p50 ms' in lines[0] and len(lines) == 3
    assert lines[1].startswith('/drone_pilot: pilot') and 'n/a' in lines[1]
    assert lines[2].split()[-3:] == ['4.0', '9.5', '120']


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
    assert 'capture -> command' in p.stdout and 'drone_pilot' in p.stdout, p.stdout


def test_main_takes_its_arguments_without_the_program_name():
    from leap_teleop.ros.latency_monitor import main
    with pytest.raises(SystemExit) as e:
        main(['--no-such-option'])       # refused by the parser, before any ROS call
    assert e.value.code == 2
