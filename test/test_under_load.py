"""tools.under_load: the command runs beside spinning hogs, its status comes back, and
the hogs are gone afterwards."""
import json
import subprocess
import sys

import pytest

from tools import under_load

# A command that measures its siblings (the hogs, children of the same parent).
MEASURE = r'''
import json, os, psutil
parent = psutil.Process(os.getppid())
hogs = [p for p in parent.children() if p.pid != os.getpid()]
for p in hogs:
    p.cpu_percent(None)
psutil.Process().cpu_percent(None)
import time; time.sleep(1.0)
print(json.dumps({'pids': [p.pid for p in hogs], 'cpu': [p.cpu_percent(None) for p in hogs]}))
'''


def test_the_command_runs_beside_busy_hogs_which_stop_after_it():
    out = subprocess.run([sys.executable, '-m', 'tools.under_load', '--hogs', '1', '--',
                          sys.executable, '-c', MEASURE], capture_output=True, text=True,
                         timeout=60)
    assert out.returncode == 0, out.stderr
    seen = json.loads(next(line for line in out.stdout.splitlines() if line.startswith('{')))
    # Spinning: a core's worth on an idle machine, less beside other work (47 % seen
    # beside the rest of make test), and near 0 if it slept.
    assert len(seen['pids']) == 1 and seen['cpu'][0] > 20.0, seen
    import psutil
    assert not any(psutil.pid_exists(pid) and psutil.Process(pid).status() != 'zombie'
                   for pid in seen['pids'])
    assert 'exited 0' in out.stdout


def test_the_commands_exit_status_is_returned():
    assert under_load.main(['--hogs', '0', '--', sys.executable, '-c', 'raise SystemExit(3)']) == 3


def test_no_command_or_a_bad_hog_count_is_refused(capsys):
    with pytest.raises(SystemExit):
        under_load.main(['--hogs', '1'])
    with pytest.raises(SystemExit):
        under_load.main(['--hogs', '-1', '--', 'true'])
    assert 'no command' in capsys.readouterr().err


def test_a_missing_program_is_a_clear_error(capsys):
    assert under_load.main(['--hogs', '0', '--', '/nonexistent/program']) == 127
    assert 'cannot run /nonexistent/program' in capsys.readouterr().err
