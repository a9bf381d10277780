"""Launch files read as XML (no master, no process): every launch file with a `source` arg
takes the hand source and recognition args sender.launch has, with its defaults, and hands
them to it."""
import os
import re
import xml.etree.ElementTree as ET

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
