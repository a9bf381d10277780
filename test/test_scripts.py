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


# A bad ~param ends the node at start-up: exit status 1 and one fatal line naming it.
BAD_PARAMS = [
    ('sender.py', ['_source:=recording'], 'needs ~recording'),
    ('sender.py', ['_source:=telepathy'], 'telepathy'),
    ('sender.py', ['_leap_xyz:=[1,2]'], 'leap_xyz must be 3 numbers'),
    ('sender.py', ['_queue_size:=-3'], 'queue_size must be an integer >= 0'),
    ('ur10_arm.py', ['_hand:=middle'], 'hand must be right or left'),
    ('hand_markers.py', ['_max_rate:=fast'], 'fast'),
    ('drone_subscriber.py', ['_mode:=loop'], 'mode must be tilt or paper'),
    ('drone_subscriber.py', ['_flip_type:=42'], 'flip_type'),
    ('ur10_sim.py', ['_realtime_factor:=-1'], 'realtime_factor must be >= 0'),
    ('ardrone_sim.py', ['_looprate:=0'], 'looprate must be > 0'),
    ('ardrone_sim.py', ['_realtime_factor:=nan'], '~realtime_factor = '),
]


@pytest.fixture(scope='module')
def master():
    from leap_teleop.bench import harness
    with harness.ros_master() as env:
        yield env


@pytest.mark.skipif(shutil.which('rosrun') is None, reason='rosrun not on PATH')
@pytest.mark.parametrize('script, args, says', BAD_PARAMS)
def test_bad_parameter_ends_the_node_with_a_clear_error(master, script, args, says):
    # its own node name: a _param:=value stays on the master under the node's name
    name = '__name:=bad_param_%d' % BAD_PARAMS.index((script, args, says))
    run = subprocess.run(['rosrun', 'leap_teleop', script, name] + args, env=master,
                         stdin=subprocess.DEVNULL, capture_output=True, text=True, timeout=60)
    out = run.stdout + run.stderr
    assert run.returncode == 1, out
    assert 'bad parameter' in out and says in out, out
    assert 'Traceback' not in out, out
