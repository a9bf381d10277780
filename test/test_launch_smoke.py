"""Every top-level launch file, started as the README and docs/ pages show (defaults, then each
documented arg value), reaches its purpose within a time limit: the cube placed, the drone
landed after its flight, the sender publishing. A private master per case;
test/launch_check.py watches the graph. RViz itself (rviz:=true) only parses here:
test_rviz_screenshot.py draws it under Xvfb."""
import os
import subprocess
import sys
import time

import pytest

from leap_teleop.hands.gestures.datasets import data_dir
from tools.bench import ros_processes

# needs a ROS master, a simulator, a subprocess or a build: not in make check
pytestmark = pytest.mark.integration

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
CHECK = os.path.join(HERE, 'launch_check.py')
GESTURES = os.path.join(ROOT, 'config', 'gestures')


def wait_for_run_id(env, timeout=30.0):
    """Block until a roslaunch has set /run_id: a second roslaunch started before that
    sets its own and the first one then quits (run_id mismatch)."""
    import xmlrpc.client
    master = xmlrpc.client.ServerProxy(env['ROS_MASTER_URI'])
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if master.hasParam('/launch_smoke', '/run_id')[2]:
            return
        time.sleep(0.1)
    raise AssertionError('no roslaunch set /run_id in %.0f s' % timeout)


def run_launches(tmp_path, launches, check_args, timeout, others=(), env=None,
                 clean_exit=False):
    """Start each `roslaunch leap_teleop ARGS...` (in order) under one private master and
    run launch_check.py with `check_args` (and the commands `others`, after the launches);
    returns its output, asserts it succeeded. `env`: the environment to run in (default
    this process's, e.g. an install space's); the launches run in tmp_path. `clean_exit`:
    also assert that each launch, stopped with SIGINT as Ctrl-C does, ends with status 0
    within 30 s and no node died or needed more than SIGINT."""
    procs, logs, stops = [], [], []
    with ros_processes.ros_master(env) as env:
        env = dict(env, ROS_LOG_DIR=str(tmp_path / 'log'), PWD=str(tmp_path))
        try:
            checker = subprocess.Popen([sys.executable, CHECK, '--timeout', str(timeout)]
                                       + check_args, env=env, stdout=subprocess.PIPE,
                                       stderr=subprocess.STDOUT, text=True)
            for i, args in enumerate(launches):
                if i:
                    wait_for_run_id(env)
                log = tmp_path / ('roslaunch_%d.log' % i)
                logs.append(log)
                procs.append(subprocess.Popen(['roslaunch', 'leap_teleop'] + args, env=env,
                                              cwd=str(tmp_path), stdout=open(log, 'wb'),
                                              stderr=subprocess.STDOUT, start_new_session=True))
            for cmd in others:
                procs.append(subprocess.Popen(cmd, env=env, stdout=subprocess.DEVNULL,
                                              stderr=subprocess.STDOUT, start_new_session=True))
            out, _ = checker.communicate(timeout=timeout + 30)
        finally:
            for proc in reversed(procs):
                running = proc.poll() is None
                if running and not ros_processes.interrupt_group(proc, 30):
                    running = None
                stops.append((proc.args, running, proc.returncode))
    tails = '\n'.join('--- %s\n%s' % (log, log.read_text(errors='replace')[-3000:]) for log in logs)
    assert checker.returncode == 0, '%s\n%s' % (out, tails)
    if clean_exit:
        for (args, running, code), log in zip(reversed(stops[-len(logs):]), logs):
            text = log.read_text(errors='replace')
            how = {False: 'had ended before SIGINT', None: 'still up 30 s after SIGINT'}
            assert running and code == 0, '%s %s, status %s\n%s' % (
                args, how.get(running, 'stopped'), code, tails)
            for sign in ('process has died', 'escalating to SIG', 'Traceback'):
                assert sign not in text, '%s: %r in its log\n%s' % (args, sign, tails)
    print(out)
    return out


# (id, launches, checker args, time limit s): the documented commands and values (README, docs/).
CASES = [
    ('ur10_single', [['ur10_single.launch']],
     ['--cube', 'ur10_1:cube_red'], 120),
    # The left hand drives the arm, as README shows it (no script: the launch picks
    # ur10_pick_place_dual.yaml, whose left hand there is; its cube is the other cell's): its
    # leapcobotleft reaches the arm, which arms on the thumbs-up. The check must not
    # subscribe to the hand topic: the sender would take it for the arm.
    ('ur10_single_hand_left', [['ur10_single.launch', 'hand:=left']],
     ['--armed', 'ur10_1'], 90),
    # ur10_dual.launch with its defaults is the demo's arm half: test_demo.py runs it (and
    # test_the_demo_runs_ur10_dual_launch_with_its_defaults keeps it so).
    # ardrone.launch with its defaults flies in drone_flight.test (and, Ctrl-C included,
    # inside the demo).
    # The leap_motion driver's stand-in: its Human, filtered Human and markers.
    ('leap_motion', [['leap_motion.launch']],
     ['--topic', '/leap_motion/leap_device:leap_teleop/DriverHuman',
      '--topic', '/leap_motion/filtered_values:leap_teleop/DriverHuman',
      '--topic', '/leap_motion/visualization_marker_array:visualization_msgs/MarkerArray',
      '--topic', '/leapmotion/data:leap_teleop/leapros'], 60),
    # Its sender's hands reach both pilots, which command both drones up, each pilot's lines
    # naming its drone; both whole flights through the same launch file are drone_dual.test's.
    ('ardrone_dual', [['ardrone_dual.launch']],
     ['--rosout', 'drone1/drone_pilot: takeoff', '--rosout', 'drone2/drone_pilot: takeoff',
      '--rosout', 'drone2/drone_pilot: tilt mode, following the left hand',
      '--topic', '/drone1/ardrone/takeoff:std_msgs/Empty',
      '--topic', '/drone2/ardrone/takeoff:std_msgs/Empty',
      '--topic', '/drone1/ardrone/navdata:leap_teleop/Navdata',
      '--topic', '/drone2/ardrone/navdata:leap_teleop/Navdata'], 120),
    # Next to a real driver: launch_check stands in for it (navdata, takeoff, land).
    ('ardrone_sim_false', [['ardrone.launch', 'sim:=false']],
     ['--driver', '--navdata', '/ardrone/navdata', '--topic', '/ardrone/takeoff:std_msgs/Empty',
      '--topic', '/ardrone/land:std_msgs/Empty'], 90),
    # Real robots: ur10_arm.launch per arm next to a robot (here the simulated one) and a
    # sender, each its own launch; the sim's speed, not the real-robot 0.05 rad/s default.
    # The hand reaches the arm and the arm's commands the robot across the three; the whole
    # pick and place through the same three files is ur10_single's (ur10_single.launch
    # includes them).
    ('ur10_arm', [['ur10_sim.launch'], ['ur10_arm.launch', 'max_joint_speed:=1.0'],
                  ['sender.launch', 'script:=' + os.path.join(GESTURES, 'ur10_pick_place_single.yaml'),
                   'sides:=[right]', 'wait_for_subscribers:=true']],
     ['--armed', 'ur10_1', '--moved', 'ur10_1'], 120),
]


@pytest.mark.rostest
@pytest.mark.parametrize('launches, check_args, timeout', [c[1:] for c in CASES],
                         ids=[c[0] for c in CASES])
def test_launch_reaches_its_purpose(launches, check_args, timeout, tmp_path):
    run_launches(tmp_path, launches, check_args, timeout, clean_exit=True)


@pytest.mark.rostest
def test_an_arm_fed_the_other_hands_type_says_so(tmp_path):
    # hand:=left pointed at a topic that carries leapcobotright (an original one-arm bag):
    # rospy drops the connection silently; the arm node names both types.
    run_launches(tmp_path, [['ur10_single.launch', 'sender:=false', 'hand:=left',
                             'topic:=/leapmotion/data']],
                 ['--rosout', 'carries leap_teleop/leapcobotright, but this arm (hand left) '
                  'reads leap_teleop/leapcobotleft'], 60,
                 others=[['rostopic', 'pub', '-r', '10', '/leapmotion/data',
                          'leap_teleop/leapcobotright', '{}']])


@pytest.mark.rostest
def test_an_arm_waiting_for_its_joints_names_wrong_types_on_both_inputs(tmp_path):
    # It waits for its joints before it listens to the hand: without the watches, a robot
    # publishing another type there left it waiting with only "waiting for joint_states",
    # and a hand topic of the other side's type went unnamed until the joints came. Its
    # lines name the arm's namespace, so the two arms of a dual cell are told apart.
    run_launches(tmp_path, [['ur10_arm.launch']],
                 ['--rosout', 'ur10_1/ur10_arm: /ur10_1/joint_states carries std_msgs/String, but '
                  'this arm reads sensor_msgs/JointState',
                  '--rosout', 'ur10_1/ur10_arm: /leapmotion/data_right carries leap_teleop/leapcobotleft, '
                  'but this arm (hand right) reads leap_teleop/leapcobotright'], 60,
                 others=[['rostopic', 'pub', '-r', '10', '/ur10_1/joint_states',
                          'std_msgs/String', '{}'],
                         ['rostopic', 'pub', '-r', '10', '/leapmotion/data_right',
                          'leap_teleop/leapcobotleft', '{}']])


@pytest.mark.rostest
def test_sender_launch_plays_a_recording(tmp_path):
    recording = os.path.join(data_dir(), 'grab.json.lz')
    assert os.path.isfile(recording), recording
    run_launches(tmp_path, [['sender.launch', 'source:=recording', 'recording:=' + recording]],
                 ['--topic', '/leapmotion/hand_right:leap_teleop/Hand',
                  '--topic', '/leapmotion/data_right:leap_teleop/leapcobotright',
                  '--count', '240'], 60)


@pytest.mark.rostest
def test_record_launch_records_a_running_sender(tmp_path):
    bag = tmp_path / 'session.bag'
    # record.launch runs until Ctrl-C: run_launches stops it, which closes the bag.
    run_launches(tmp_path, [['record.launch', 'output:=%s' % bag],
                            ['sender.launch', 'leapros_topic:=leapmotion/data']],
                 ['--topic', '/leapmotion/hand_right:leap_teleop/Hand', '--count', '300'], 60)
    import rosbag
    with rosbag.Bag(str(bag)) as b:
        info = b.get_type_and_topic_info().topics
    for topic, msg_type in (('/leapmotion/data_right', 'leap_teleop/leapcobotright'),
                            ('/leapmotion/data', 'leap_teleop/leapros'),
                            ('/leapmotion/gestures', 'leap_teleop/GestureEvent'),
                            ('/tf_static', 'tf2_msgs/TFMessage')):
        assert topic in info, sorted(info)
        assert info[topic].msg_type == msg_type
        assert info[topic].message_count > 0
    assert info['/leapmotion/data_right'].message_count >= 300


DOCUMENTED_VALUES = [
    # (launch, args, nodes that must be in it): every arg value README, docs/ or the launch
    # docs name, parsed by roslaunch itself.
    ('ur10_dual.launch', ['rviz:=true'], {'/rviz', '/hand_markers', '/leap_sender'}),
    ('ur10_single.launch', ['rviz:=true'], {'/rviz', '/hand_markers', '/leap_sender'}),
    ('ardrone.launch', ['rviz:=true'], {'/rviz', '/hand_markers', '/ardrone_sim'}),
    ('ur10_dual.launch', ['sender:=false'], {'/ur10_1/ur10_arm', '/ur10_2/ur10_arm'}),
    ('ardrone.launch', ['sender:=false'], {'/drone_pilot', '/ardrone_sim'}),
    ('ur10_single.launch', ['sender:=false', 'hand:=left'], {'/ur10_1/ur10_arm'}),
    ('demo.launch', [], {'/leap_sender', '/drone/leap_sender', '/drone/ardrone_sim'}),
    ('ur10_sim.launch', ['rviz:=true'], {'/rviz', '/ur10_sim'}),
    ('ur10_dual_sim.launch', [], {'/ur10_sim', '/ur10_1/robot_state_publisher'}),
    ('ardrone_sim.launch', [], {'/ardrone_sim'}),
    ('replay.launch', ['bag:=/tmp/x.bag'], {'/gesture_player'}),
    ('leap_motion.launch', ['rviz:=true'], {'/rviz', '/leap_sender'}),
    ('leap_motion.launch', ['source:=recording', 'recording:=/tmp/x.json.lz', 'leap:=true',
                            'enable_filter:=false', 'visualizer:=false', 'human:=false',
                            'leapros:=false'], {'/leap_sender'}),
    ('record.launch', [], {'/gesture_recorder'}),
]


@pytest.mark.parametrize('launch, args, nodes', DOCUMENTED_VALUES,
                         ids=['%s %s' % (c[0], ' '.join(c[1])) for c in DOCUMENTED_VALUES])
def test_documented_arg_values_parse(launch, args, nodes):
    # roslaunch's own loader, as `roslaunch --nodes` runs it, without a process per case
    import rosgraph.names
    import roslaunch.config
    import roslaunch.xmlloader
    config = roslaunch.config.ROSLaunchConfig()
    loader = roslaunch.xmlloader.XmlLoader(resolve_anon=False)
    loader.ignore_unset_args = False    # as roslaunch sets it: a missing arg is named
    loader.load(os.path.join(ROOT, 'launch', launch), config, argv=['roslaunch'] + args,
                verbose=False)
    names = {rosgraph.names.ns_join(n.namespace, n.name) for n in config.nodes}
    assert nodes <= names, sorted(names)


@pytest.mark.parametrize('hand', ['right', 'left'])
def test_ur10_single_plays_a_script_with_the_hand_it_drives(hand):
    # With hand:=left it played the one-arm session, which has only a right hand: the
    # sender published no left hand and the arm never armed.
    import roslaunch.config
    import roslaunch.xmlloader

    from leap_teleop.hands.sources.scripted import GestureScript
    config = roslaunch.config.ROSLaunchConfig()
    loader = roslaunch.xmlloader.XmlLoader(resolve_anon=False)
    loader.ignore_unset_args = False
    loader.load(os.path.join(ROOT, 'launch', 'ur10_single.launch'), config,
                argv=['roslaunch', 'hand:=' + hand], verbose=False)
    params = {k: v.value for k, v in config.params.items()}
    assert params['/leap_sender/sides'] == [hand]
    script = GestureScript.load(params['/leap_sender/script'])
    assert script.has_hand(hand), script.name


@pytest.fixture(scope='module')
def resolved():
    """launch file -> ({param: value}, {node names}) with its defaults, as roslaunch's
    loader resolves them (includes, args, param commands), each loaded once."""
    import rosgraph.names
    import roslaunch.config
    import roslaunch.xmlloader
    cache = {}

    def load(launch):
        if launch not in cache:
            config = roslaunch.config.ROSLaunchConfig()
            loader = roslaunch.xmlloader.XmlLoader(resolve_anon=False)
            loader.ignore_unset_args = False
            loader.load(os.path.join(ROOT, 'launch', launch), config, argv=['roslaunch'],
                        verbose=False)
            cache[launch] = ({name: p.value for name, p in config.params.items()},
                             {rosgraph.names.ns_join(n.namespace, n.name) for n in config.nodes})
        return cache[launch]
    return load


def test_the_demo_graph_gets_the_light_pictures_it_sets(resolved):
    # Its cameras once stayed at 5 Hz each: ardrone.launch set them after the demo did.
    params, _ = resolved('demo.launch')
    assert params['/drone/ardrone_sim/front_rate'] == 2.0
    assert params['/drone/ardrone_sim/bottom_rate'] == 0.0
    assert params['/ur10_sim/snapshot_size'] == [400, 300]


def test_the_demo_runs_ur10_dual_launch_with_its_defaults(resolved):
    # Outside the drone's namespace, demo.launch is ur10_dual.launch as a user starts it:
    # the same nodes and parameter values, plus the smaller snapshots the demo asks for.
    dual_params, dual_nodes = resolved('ur10_dual.launch')
    demo_params, demo_nodes = resolved('demo.launch')
    arms = {k: v for k, v in demo_params.items() if not k.startswith('/drone/')}
    assert arms.pop('/ur10_sim/snapshot_size') == [400, 300]
    assert arms == dual_params
    assert {n for n in demo_nodes if not n.startswith('/drone/')} == dual_nodes


def test_every_launch_file_is_covered():
    launches = {f for f in os.listdir(os.path.join(ROOT, 'launch')) if f.endswith('.launch')}
    run = {args[0] for c in CASES for args in c[1]} | {'sender.launch', 'record.launch',
                                                        'ur10_dual.launch'}
    parsed = {c[0] for c in DOCUMENTED_VALUES}
    # replay.launch runs in test_replay_remap.py, demo.launch (with ur10_dual.launch's
    # defaults in it) in test_demo.py.
    assert launches <= run | parsed, launches - run - parsed
    assert {'replay.launch', 'demo.launch'} <= parsed
