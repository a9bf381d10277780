"""Every installed script starts by name through rosrun and explains itself with --help
(no master needed): rosrun finds exactly one of each, so it never stops to ask which."""
import os
import shutil
import subprocess

import pytest

# needs a ROS master, a simulator, a subprocess or a build: not in make check
pytestmark = pytest.mark.integration


@pytest.fixture(autouse=True)
def rosrun_installed():
    # rosbash is in tools/debian-packages.txt: a setup without it is broken, not skipped.
    assert shutil.which('rosrun'), 'rosrun not on PATH (Debian package rosbash)'

SCRIPTS = sorted(os.listdir(os.path.join(os.path.dirname(os.path.dirname(
    os.path.abspath(__file__))), 'scripts')))


@pytest.mark.parametrize('script', SCRIPTS)
def test_rosrun_script_help(script):
    run = subprocess.run(['rosrun', 'leap_teleop', script, '--help'], stdin=subprocess.DEVNULL,
                         capture_output=True, text=True, timeout=60)
    assert run.returncode == 0, run.stdout + run.stderr
    assert run.stdout.startswith('usage:'), run.stdout
    assert 'non-unique' not in run.stdout and 'loop detected' not in run.stderr, run.stderr



@pytest.mark.parametrize('script, module', [('drone_pilot.py', 'drone_pilot'), ('sender.py', 'sender'),
                                            ('ur10_arm.py', 'ur10_arm')])
def test_help_marks_the_parameters_that_change_live(script, module):
    # --help named a Python constant (RECONFIGURABLE) and marked none of them
    import importlib
    live = importlib.import_module('leap_teleop.ros.nodes.' + module).RECONFIGURABLE
    run = subprocess.run(['rosrun', 'leap_teleop', script, '--help'], stdin=subprocess.DEVNULL,
                         capture_output=True, text=True, timeout=60)
    marked = {line.split()[0].lstrip('~') for line in run.stdout.splitlines()
              if line.startswith('  ~') and line.endswith(' (live)')}
    assert live and marked == set(live) and 'RECONFIGURABLE' not in run.stdout


# A bad ~param ends the node at start-up: exit status 1 and one fatal line naming it.
BAD_PARAMS = [
    ('sender.py', ['_source:=recording'], 'needs ~recording'),
    ('sender.py', ['_source:=telepathy'], "~source = 'telepathy': not one of the choices"),
    ('sender.py', ['_leap_xyz:=[1,2]'], '~leap_xyz = [1, 2]: 2 items'),
    ('sender.py', ['_queue_size:=-3'], '~queue_size = -3: out of range'),
    ('sender.py', ['_sides:=[middle]'], "~sides = ['middle']"),
    ('sender.py', ['_gesture_model:=/no/such/model.npz'], 'model.npz: cannot read a pose model'),
    ('sender.py', ['_gesture_bindings:=/no/such/bindings.yaml'], 'bindings.yaml: cannot read'),
    ('ur10_arm.py', ['_hand:=middle'], "~hand = 'middle': not one of the choices"),
    ('ur10_arm.py', ['_rate:=0'], '~rate = 0: out of range; allowed: a finite number >= 10'),
    ('ur10_arm.py', ['_status_rate:=0'], '~status_rate = 0: out of range'),
    ('ur10_arm.py', ['_dead_zone:=-5'], '~dead_zone = -5: out of range'),
    ('ur10_arm.py', ['_input_timeout:=.nan'], '~input_timeout = nan: not finite'),
    ('ur10_arm.py', ['_workspace_min:=[0, 0]'], '~workspace_min = [0, 0]: 2 items'),
    ('ur10_arm.py', ['_gesture_bindings:=/no/such/bindings.yaml'], 'bindings.yaml: cannot read'),
    ('hand_markers.py', ['_max_rate:=fast'], "~max_rate = 'fast': not a number"),
    ('hand_markers.py', ['_hand_topics:=[]'], '~hand_topics = []: 0 items'),
    ('hand_markers.py', ['_scale:=0'], '~scale = 0: out of range'),
    ('drone_pilot.py', ['_mode:=loop'], "~mode = 'loop': not one of the choices"),
    ('drone_pilot.py', ['_flip_type:=42'], '~flip_type = 42: out of range'),
    ('drone_pilot.py', ['_hand_timeout:=.nan'], '~hand_timeout = nan: not finite'),
    ('drone_pilot.py', ['_hand_timeout:=nan'], "~hand_timeout = 'nan': not a number"),
    ('drone_pilot.py', ['_land_after:=.inf'], '~land_after = inf: not finite'),
    ('drone_pilot.py', ['_land_after:=1000000.0'], '~land_after = 1000000.0: out of range'),
    ('drone_pilot.py', ['_navdata_timeout:=0'], '~navdata_timeout = 0: out of range'),
    ('ur10_sim.py', ['_realtime_factor:=-1'], '~realtime_factor = -1: out of range'),
    ('ur10_sim.py', ['_snapshot_size:=[640]'], '~snapshot_size = [640]: 1 items'),
    ('ardrone_sim.py', ['_looprate:=0'], '~looprate = 0: out of range'),
    ('ardrone_sim.py', ['_realtime_factor:=.nan'], '~realtime_factor = nan: not finite'),
    ('ardrone_sim.py', ['_path_length:=100000'], '~path_length = 100000: out of range'),
    # diagnostic_updater's own: once read on the control loop, where a bad one ended the node
    ('ur10_arm.py', ['_diagnostic_period:=abc'], "~diagnostic_period = 'abc': not a number"),
    ('drone_pilot.py', ['_diagnostic_period:=0'], '~diagnostic_period = 0: out of range'),
    ('sender.py', ['_diagnostic_period:=.nan'], '~diagnostic_period = nan: not finite'),
]


@pytest.fixture(scope='module')
def master():
    from tools.bench import ros_processes
    with ros_processes.ros_master() as env:
        yield env


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


def test_a_bad_parameter_line_names_the_node_with_its_namespace(master):
    # In a dual launch both arms said 'ur10_arm: bad parameter ...'.
    run = subprocess.run(['rosrun', 'leap_teleop', 'ur10_arm.py', '__ns:=/ur10_2', '__name:=ns_arm',
                          '_hand:=middle', '_deadzone_mm:=3'], env=master,
                         stdin=subprocess.DEVNULL, capture_output=True, text=True, timeout=60)
    out = run.stdout + run.stderr
    assert run.returncode == 1, out
    assert "ur10_2/ns_arm: bad parameter: ~hand = 'middle'" in out, out
    assert '~deadzone_mm is not a parameter of ur10_2/ns_arm' in out, out


def test_sender_with_one_side_given_as_a_string_runs(master):
    # _sides:=right is the string 'right': a list of one side, not a KeyError traceback.
    run = subprocess.run(['rosrun', 'leap_teleop', 'sender.py', '__name:=one_side',
                          '_sides:=right', '_realtime:=false'], env=master,
                         stdin=subprocess.DEVNULL, capture_output=True, text=True, timeout=60)
    out = run.stdout + run.stderr
    assert run.returncode == 0, out
    assert 'publishing right hands' in out and 'Traceback' not in out, out
