"""Every installed script starts by name through rosrun and explains itself with --help
(no master needed): rosrun finds exactly one of each, so it never stops to ask which."""
import os
import shutil
import subprocess

import pytest

SCRIPTS = sorted(os.listdir(os.path.join(os.path.dirname(os.path.dirname(
    os.path.abspath(__file__))), 'scripts')))


@pytest.mark.skipif(shutil.which('rosrun') is None, reason='rosrun not on PATH')
@pytest.mark.parametrize('script', SCRIPTS)
def test_rosrun_script_help(script):
    run = subprocess.run(['rosrun', 'leap_teleop', script, '--help'], stdin=subprocess.DEVNULL,
                         capture_output=True, text=True, timeout=60)
    assert run.returncode == 0, run.stdout + run.stderr
    assert run.stdout.startswith('usage:'), run.stdout
    assert 'non-unique' not in run.stdout and 'loop detected' not in run.stderr, run.stderr
