"""Launch files read as XML (no master, no process): every launch file with a `source` arg
takes the hand source and recognition args sender.launch has, with its defaults, and hands
them to it."""
import os
import re
import xml.etree.ElementTree as ET

import numpy as np
import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
LAUNCH = os.path.join(ROOT, 'launch')

# The hand source args (README: "Every launch file with `source:=` takes the same hand
# source args"). leap_motion.launch once lacked the camera ones: mirror:=true was ignored.
SOURCE_ARGS = ('source', 'script', 'recording', 'video', 'device', 'mirror',
               'annotated_image_topic', 'camera_config', 'loop')
OWN_DEFAULT = {'script'}        # each launch file plays its own gesture script
# The recognition args: a user's model and bindings reach the sender from any of them.
RECOGNITION_ARGS = ('gesture_model', 'keypoint_model', 'gesture_bindings')


def launch_args(name):
    root = ET.parse(os.path.join(LAUNCH, name)).getroot()
    return {a.get('name'): a for a in root.findall('arg')}


def sender_include_args(name):
    """{arg: value} that `name` hands to sender.launch."""
    root = ET.parse(os.path.join(LAUNCH, name)).getroot()
    [include] = [i for i in root.iter('include') if i.get('file', '').endswith('/sender.launch')]
    return {a.get('name'): a.get('value') for a in include.findall('arg')}


def runs_commands(name):
    """Whether loading `name` runs a <param command=> (ur10_sim --urdf: a process)."""
    text = open(os.path.join(LAUNCH, name)).read()
    return 'command="' in text.replace('command="load"', '') or any(
        runs_commands(inc) for inc in re.findall(r'\$\(find leap_teleop\)/launch/(\w+\.launch)', text))


SOURCE_LAUNCHES = sorted(f for f in os.listdir(LAUNCH) if f.endswith('.launch')
                         and f != 'sender.launch' and 'source' in launch_args(f))


def test_the_source_args_are_the_senders_source_args():
    sender = launch_args('sender.launch')
    assert set(SOURCE_ARGS) <= set(sender)
    # A new sender arg documented as being for a source must join the list (and so every file).
    for_a_source = {name for name, a in sender.items()
                    if re.search(r'(^|for the )\w+ sources?\b', a.get('doc') or '')}
    assert for_a_source <= set(SOURCE_ARGS), for_a_source - set(SOURCE_ARGS)
    assert {'leap_motion.launch', 'ardrone.launch', 'ur10_single.launch'} <= set(SOURCE_LAUNCHES)


@pytest.mark.parametrize('name', SOURCE_LAUNCHES)
def test_every_launch_file_with_a_source_takes_the_same_source_args(name):
    sender, args, passed = launch_args('sender.launch'), launch_args(name), sender_include_args(name)
    assert [a for a in SOURCE_ARGS + RECOGNITION_ARGS if a not in args] == [], name
    for arg in SOURCE_ARGS + RECOGNITION_ARGS:
        if arg not in OWN_DEFAULT:
            assert args[arg].get('default') == sender[arg].get('default'), (name, arg)
        assert passed.get(arg) == '$(arg %s)' % arg, (name, arg)


CAMERA_ARGS = ['source:=webcam', 'mirror:=true', 'annotated_image_topic:=/camera/annotated']


@pytest.mark.parametrize('name', [
    pytest.param(f, marks=pytest.mark.integration) if runs_commands(f) else f
    for f in ['sender.launch'] + SOURCE_LAUNCHES])
def test_the_camera_and_recognition_args_reach_the_senders_parameters(name, tmp_path):
    # roslaunch's own loader, as --dump-params runs it
    import roslaunch.config
    import roslaunch.xmlloader
    camera = tmp_path / 'camera.yaml'
    camera.write_text('width: 320\n')
    config = roslaunch.config.ROSLaunchConfig()
    loader = roslaunch.xmlloader.XmlLoader(resolve_anon=False)
    loader.ignore_unset_args = False
    loader.load(os.path.join(LAUNCH, name), config, verbose=False,
                argv=['roslaunch'] + CAMERA_ARGS + ['camera_config:=%s' % camera]
                + ['%s:=/tmp/mine_%s' % (a, a) for a in RECOGNITION_ARGS])
    params = {k: v.value for k, v in config.params.items()}
    assert params['/leap_sender/source'] == 'webcam'
    assert params['/leap_sender/mirror'] is True
    assert params['/leap_sender/annotated_image_topic'] == '/camera/annotated'
    assert params['/leap_sender/width'] == 320
    for a in RECOGNITION_ARGS:                     # a user's model and bindings, from any of them
        assert params['/leap_sender/' + a] == '/tmp/mine_' + a
    # The arms name the bound gestures in their state lines: the same bindings reach them.
    arms = [k[:-len('hand')] for k in params if k.endswith('/ur10_arm/hand')]
    assert bool(arms) == name.startswith('ur10_'), (name, arms)
    for arm in arms:
        assert params[arm + 'gesture_bindings'] == '/tmp/mine_gesture_bindings', arm


@pytest.mark.integration
def test_every_ros_package_package_xml_names_is_there():
    # diagnostic_updater's module came with Debian's python3 package, its package.xml with
    # the -dev one that tools/debian-packages.txt lacked: rospack did not know it.
    import subprocess
    root = ET.parse(os.path.join(ROOT, 'package.xml')).getroot()
    names = sorted({e.text.strip() for e in root if e.tag.endswith('depend')
                    and not e.text.strip().startswith('python3-')})
    missing = [n for n in names if subprocess.run(['rospack', 'find', n], capture_output=True,
                                                  timeout=60).returncode != 0]
    assert len(names) > 20 and missing == [], missing


def load_params(name, argv):
    """{key: value} of the parameters `roslaunch name argv...` sets (its loader, no master)."""
    import roslaunch.config
    import roslaunch.xmlloader
    config = roslaunch.config.ROSLaunchConfig()
    loader = roslaunch.xmlloader.XmlLoader(resolve_anon=False)
    loader.ignore_unset_args = False
    loader.load(os.path.join(LAUNCH, name), config, verbose=False, argv=['roslaunch'] + list(argv))
    return {k: v.value for k, v in config.params.items()}


# A launch arg's default once overrode the same key in config:= (roslaunch applies a node's
# <param> over its <rosparam load>): a max_joint_speed lowered there did not reach the arm.
CONFIG_CASES = [
    ('ur10_arm.launch', '', {'max_joint_speed': 0.02, 'max_joint_accel': 0.2, 'mode': 'joystick',
                             'orientation': 'yaw', 'gripper_mode': 'proportional'},
     '/ur10_1/ur10_arm/', {'max_joint_speed': 0.1, 'mode': 'imitation'}),
    ('ardrone.launch', 'drone_pilot', {'mode': 'paper'}, '/drone_pilot/', {'mode': 'tilt'}),
    ('ardrone.launch', 'ardrone_sim', {'gui': True, 'front_rate': 0.0, 'bottom_rate': 1.0},
     '/ardrone_sim/', {'gui': False, 'front_rate': 2.0}),
    ('ardrone_sim.launch', 'ardrone_sim', {'gui': True, 'front_rate': 0.0, 'realtime_factor': 2.0},
     '/ardrone_sim/', {'gui': False, 'realtime_factor': 1.0}),
    ('ardrone_dual.launch', 'ardrone_sim', {'gui': True, 'front_rate': 0.0, 'bottom_rate': 1.0},
     '/drone2/ardrone_sim/', {'front_rate': 3.0}),
]


@pytest.mark.parametrize('name, block, keys, prefix, args', CONFIG_CASES)
def test_a_config_file_key_reaches_the_node_and_an_explicit_arg_wins(name, block, keys, prefix, args,
                                                                    tmp_path):
    import yaml
    config = tmp_path / 'mine.yaml'
    config.write_text(yaml.safe_dump({block: keys} if block else keys))
    params = load_params(name, ['config:=%s' % config])
    assert {k: params[prefix + k] for k in keys} == keys
    params = load_params(name, ['config:=%s' % config] + ['%s:=%s' % kv for kv in args.items()])
    assert {k: params[prefix + k] for k in args} == args
    for k in set(keys) - set(args):
        assert params[prefix + k] == keys[k], k


def test_the_launch_files_own_values_still_apply_without_config_keys(tmp_path):
    # config/ur10_teleop.yaml carries the real-robot limits; a config without them: the node's
    arm = load_params('ur10_arm.launch', [])
    assert (arm['/ur10_1/ur10_arm/max_joint_speed'], arm['/ur10_1/ur10_arm/max_joint_accel'],
            arm['/ur10_1/ur10_arm/mode']) == (0.05, 0.5, 'imitation')
    empty = tmp_path / 'empty.yaml'
    empty.write_text('scale: 1.5\n')
    arm = load_params('ur10_arm.launch', ['config:=%s' % empty])
    assert '/ur10_1/ur10_arm/max_joint_speed' not in arm and arm['/ur10_1/ur10_arm/scale'] == 1.5
    drone = load_params('ardrone.launch', [])
    assert drone['/drone_pilot/mode'] == 'tilt' and '/ardrone_sim/front_rate' not in drone
    sender = load_params('sender.launch', [])
    assert sender['/leap_sender/shutdown_on_end'] is False       # the node's own default: True
    assert '/leap_sender/device' not in sender and '/leap_sender/rate' not in sender


@pytest.mark.integration
def test_the_simulations_keep_their_own_arm_limits_and_camera_rates():
    # ur10_single / ur10_dual pass sim_max_joint_* explicitly; demo passes the drone's rates
    for name, arms in (('ur10_single.launch', ['ur10_1']), ('ur10_dual.launch', ['ur10_1', 'ur10_2'])):
        params = load_params(name, [])
        for arm in arms:
            assert params['/%s/ur10_arm/max_joint_speed' % arm] == 1.0, name
            assert params['/%s/ur10_arm/max_joint_accel' % arm] == 3.14159, name
    params = load_params('demo.launch', ['ur10:=false'])
    assert (params['/drone/ardrone_sim/front_rate'], params['/drone/ardrone_sim/bottom_rate']) == (2.0, 0.0)


CAMERA_CONFIG = {'rate': 10.0, 'loop': True, 'realtime': False, 'freq': 0.1, 'mirror': True,
                 'device': '/dev/video2', 'shutdown_on_end': True, 'width': 320}


@pytest.mark.parametrize('name', [
    pytest.param(f, marks=pytest.mark.integration) if runs_commands(f) else f
    for f in ['sender.launch'] + SOURCE_LAUNCHES])
def test_every_camera_config_key_reaches_the_sender_and_an_explicit_arg_wins(name, tmp_path):
    # Keys sender.launch also has args for once kept those args' defaults instead.
    import yaml
    camera = tmp_path / 'camera.yaml'
    camera.write_text(yaml.safe_dump(CAMERA_CONFIG))
    params = load_params(name, ['source:=video', 'camera_config:=%s' % camera])
    assert {k: params['/leap_sender/' + k] for k in CAMERA_CONFIG} == CAMERA_CONFIG
    params = load_params(name, ['source:=video', 'camera_config:=%s' % camera, 'mirror:=false',
                                'device:=1', 'loop:=false'])
    assert (params['/leap_sender/mirror'], params['/leap_sender/device'],
            params['/leap_sender/loop'], params['/leap_sender/rate']) == (False, '1', False, 10.0)


def _rotation_columns(q):
    """World coordinates of a frame's x, y, z axes, rotated by q = (x, y, z, w)."""
    x, y, z, w = q
    return ((1 - 2 * (y * y + z * z), 2 * (x * y + z * w), 2 * (x * z - y * w)),
            (2 * (x * y - z * w), 1 - 2 * (x * x + z * z), 2 * (y * z + x * w)),
            (2 * (x * z + y * w), 2 * (y * z - x * w), 1 - 2 * (x * x + y * y)))


def test_leap_motion_launch_turns_leap_hands_as_the_driver_and_sender_launch_as_rep_103():
    # The driver publishes world -> leap_hands 90 deg about x, which its RViz config's view
    # expects; sender.launch's REP 103 turn showed the hands side-on there.
    from leap_teleop.hands.sender_params import SENDER_PARAMS, leap_rotation
    key = '/leap_sender/leap_rotation_xyzw'
    raw = load_params('leap_motion.launch', [])[key]
    assert raw == [0.707, 0, 0, 0.707]
    q = leap_rotation(SENDER_PARAMS['leap_rotation_xyzw'].check('leap_rotation_xyzw', raw))
    # Leap x (user's right) -> world x, y (up) -> z, z (toward the user) -> -y
    np.testing.assert_allclose(_rotation_columns(q), ((1, 0, 0), (0, 0, 1), (0, -1, 0)), atol=1e-9)
    assert key not in load_params('sender.launch', [])          # the node's REP 103 default
    default = leap_rotation(SENDER_PARAMS['leap_rotation_xyzw'].default)
    np.testing.assert_allclose(_rotation_columns(default), ((0, -1, 0), (0, 0, 1), (-1, 0, 0)),
                               atol=1e-9)
    mine = load_params('leap_motion.launch', ['leap_rotation:=[0, 0, 0, 1]'])[key]
    assert mine == [0, 0, 0, 1]


@pytest.mark.parametrize('name, arg, flag', [('replay.launch', 'bag', None),
                                             ('record.launch', 'output', '-O'),
                                             ('record.launch', 'output_prefix', '-o')])
def test_rosbag_reads_a_relative_bag_from_where_roslaunch_ran(name, arg, flag, monkeypatch, tmp_path):
    # rosbag runs in ROS_HOME: bag:=one_arm.bag beside the user was not found
    import roslaunch.config
    import roslaunch.xmlloader

    def node_args(value):
        config = roslaunch.config.ROSLaunchConfig()
        roslaunch.xmlloader.XmlLoader(resolve_anon=False).load(
            os.path.join(LAUNCH, name), config, verbose=False,
            argv=['roslaunch', '%s:=%s' % (arg, value)])
        (node,) = [n for n in config.nodes if n.package == 'rosbag']
        return node.args.split()

    monkeypatch.setenv('PWD', str(tmp_path))
    args = node_args('one_arm.bag')
    assert str(tmp_path / 'one_arm.bag') in args
    assert '/abs/two.bag' in node_args('/abs/two.bag')
    if flag:
        assert args[args.index(flag) + 1] == str(tmp_path / 'one_arm.bag')


def test_the_drone_launch_waits_for_no_hand_its_pilot_may_not_read():
    # The pilot reads the hand its config's side names; a wait for hand_right never ended
    # with side: left
    wait = load_params('ardrone.launch', [])['/leap_sender/wait_topics']
    assert 'leapmotion/gestures' in wait and not [t for t in wait if 'hand_' in t]


def test_rviz_keeps_the_config_files_odom_in_world(tmp_path):
    # rviz:=true set the arg's default [1, 0, 0] over the file's
    import yaml
    config = tmp_path / 'mine.yaml'
    config.write_text(yaml.safe_dump({'ardrone_sim': {'odom_in_world': [2.0, 0.5, 0.0]}}))
    params = load_params('ardrone.launch', ['config:=%s' % config, 'rviz:=true'])
    assert params['/ardrone_sim/odom_in_world'] == [2.0, 0.5, 0.0]
    params = load_params('ardrone.launch', ['config:=%s' % config, 'rviz:=true',
                                            'odom_in_world:=[0.0, 1.0, 0.0]'])
    assert params['/ardrone_sim/odom_in_world'] == [0.0, 1.0, 0.0]


@pytest.mark.parametrize('name, node_type', [('sender.launch', 'sender.py'), ('ur10_arm.launch', 'ur10_arm.py')])
def test_a_respawned_node_waits_before_it_starts_again(name, node_type):
    # respawn:=true with a refused parameter restarted the node about once a second, for ever
    import roslaunch.config
    import roslaunch.xmlloader
    config = roslaunch.config.ROSLaunchConfig()
    roslaunch.xmlloader.XmlLoader(resolve_anon=False).load(
        os.path.join(LAUNCH, name), config, verbose=False, argv=['roslaunch', 'respawn:=true'])
    (node,) = [n for n in config.nodes if n.type == node_type]
    assert node.respawn and node.respawn_delay == 3.0


def resolved(params, node, key, default):
    """A node's topic parameter as rospy resolves it (relative to the node's namespace)."""
    value = params.get(node + '/' + key, default)
    return value if value.startswith('/') else node.rsplit('/', 1)[0] + '/' + value


@pytest.mark.parametrize('ns, argv', [
    ('', []),
    # Included inside a namespace, the pilots read absolute topics the sender did not publish.
    ('team', ['hand_topic_right:=/team/leapmotion/hand_right', 'hand_topic_left:=/team/leapmotion/hand_left',
              'gesture_topic:=/team/leapmotion/gestures']),
    # Without them the sender stays inside its namespace: two teams never fly each other's
    # drones (absolute defaults put both senders on /leapmotion/...).
    ('team', [])])
def test_the_dual_drone_pilots_read_the_topics_the_sender_publishes(ns, argv, tmp_path):
    wrapper = tmp_path / 'wrapper.launch'
    args = ''.join('<arg name="%s" value="%s"/>' % tuple(a.split(':=')) for a in argv)
    wrapper.write_text('<launch><group ns="%s"><include file="%s">%s</include></group></launch>'
                       % (ns or '/', os.path.join(LAUNCH, 'ardrone_dual.launch'), args))
    params = load_params(str(wrapper), [])
    sender = '/%sleap_sender' % (ns + '/' if ns else '')
    for drone, side in (('drone1', 'right'), ('drone2', 'left')):
        pilot = sender.replace('leap_sender', drone + '/drone_pilot')
        published = resolved(params, sender, 'hand_topic_' + side, 'leapmotion/hand_' + side)
        gestures = resolved(params, sender, 'gesture_topic', 'leapmotion/gestures')
        assert published.startswith(sender.replace('leap_sender', '')) and gestures.startswith(
            sender.replace('leap_sender', ''))
        meet = (resolved(params, pilot, 'hand_topic', ''), resolved(params, pilot, 'gesture_topic', '')) == (
            published, gestures)
        assert meet == (not ns or bool(argv))


@pytest.mark.parametrize('name', [
    pytest.param(f, marks=pytest.mark.integration) if runs_commands(f) else f
    for f in sorted(os.listdir(LAUNCH)) if f.endswith('.launch')])
def test_a_node_with_live_parameters_starts_from_a_cleared_namespace(name):
    # dynamic_reconfigure writes every live parameter back to the parameter server, where it
    # outlived the node: the next launch on the same master read the old ~filter_cutoff
    # instead of the driver's /filter_cutoff, and a value tuned live instead of the default.
    import roslaunch.config
    import roslaunch.xmlloader
    config = roslaunch.config.ROSLaunchConfig()
    roslaunch.xmlloader.XmlLoader(resolve_anon=False).load(
        os.path.join(LAUNCH, name), config, verbose=False, argv=['roslaunch', 'bag:=one_arm.bag'])
    live = [n for n in config.nodes if n.type in ('sender.py', 'ur10_arm.py', 'drone_pilot.py')]
    for node in live:
        assert node.namespace + node.name + '/' in config.clear_params, (name, node.name)
