"""leap_teleop in a user's catkin workspace, next to another package, the way a ROS user
builds it (the one slower test; a few minutes on two cores):

* catkin_lint (-W2 --strict) finds no problem;
* `catkin_make` builds it next to `leap_motion` (the classic driver's message package, with
  a leapros consumer), `catkin_make run_tests` targets run a rostest and the pytest suite
  (narrowed to the message tests) with passing results, `catkin_make install` installs it,
  and from the install space alone every launch file resolves with its defaults (its
  includes, args, rosparam files and param commands; every node it names is installed;
  every absolute path into the install space a parameter names exists), the launch files
  that together start every node type (INSTALLED_RUNS) start (a private master each, headless), show a sign of life of
  their own (SIGNS_OF_LIFE) and stop cleanly on Ctrl-C, and the installed sender feeds
  the classic consumer its leapros;
* `catkin build` (catkin-tools) builds the same sources in a second workspace.

Builds run in a clean environment (Debian's ROS under /usr, the venv's python with the
dependencies first on PATH): nothing of the project's own .ws leaks in.
PYTHON_EXECUTABLE is the venv's python, as tools/setup.sh sets it.
"""
import json
import os
import re
import shlex
import shutil
import signal
import subprocess
import sys
import textwrap

import pytest
from test_launch_smoke import run_launches

from tools.bench.ros_processes import free_port

# needs a ROS master, a simulator, a subprocess or a build: not in make check
pytestmark = pytest.mark.integration

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
PYTHON = sys.executable
LEAPROS_MD5 = 'e37447f7532c765d6c587f418fd5dd03'


def package_files():
    """The package as a clone has it: what git tracks or would track."""
    out = subprocess.run(['git', '-C', ROOT, 'ls-files', '--cached', '--others',
                          '--exclude-standard'], stdout=subprocess.PIPE, text=True, check=True)
    return [f for f in out.stdout.splitlines() if os.path.isfile(os.path.join(ROOT, f))]


def copy_package(dst):
    for rel in package_files():
        os.makedirs(os.path.dirname(os.path.join(dst, rel)), exist_ok=True)
        shutil.copy2(os.path.join(ROOT, rel), os.path.join(dst, rel))


def write_leap_motion(dst):
    """The classic driver's message package: leapros written from the classic field list
    (not from our copy), and a consumer that reads it as leap_motion/leapros."""
    fingers = ('thumb', 'index', 'middle', 'ring', 'pinky')
    bones = ('metacarpal', 'proximal', 'intermediate', 'distal', 'tip')
    fields = ['Header header', 'geometry_msgs/Vector3 direction', 'geometry_msgs/Vector3 normal',
              'geometry_msgs/Point palmpos', 'geometry_msgs/Vector3 ypr'] + [
        'geometry_msgs/Point %s_%s' % (f, b) for f in fingers for b in bones]
    files = {
        'package.xml': """
            <?xml version="1.0"?>
            <package format="2">
              <name>leap_motion</name><version>0.0.1</version>
              <description>classic leapros message and consumer</description>
              <maintainer email="user@example.com">user</maintainer><license>BSD</license>
              <buildtool_depend>catkin</buildtool_depend>
              <build_depend>message_generation</build_depend>
              <exec_depend>message_runtime</exec_depend>
              <depend>std_msgs</depend><depend>geometry_msgs</depend>
              <exec_depend>rospy</exec_depend>
            </package>""",
        'CMakeLists.txt': """
            cmake_minimum_required(VERSION 3.0.2)
            project(leap_motion)
            find_package(catkin REQUIRED COMPONENTS geometry_msgs message_generation std_msgs)
            add_message_files(FILES leapros.msg)
            generate_messages(DEPENDENCIES geometry_msgs std_msgs)
            catkin_package(CATKIN_DEPENDS geometry_msgs message_runtime std_msgs)
            catkin_install_python(PROGRAMS scripts/listener.py
              DESTINATION ${CATKIN_PACKAGE_BIN_DESTINATION})""",
        'msg/leapros.msg': '\n'.join(fields),
        'scripts/listener.py': """
            #!/usr/bin/env python3
            # A classic consumer: leapros on leapmotion/data; prints what it got, exits 0.
            import rospy
            from leap_motion.msg import leapros
            rospy.init_node('leapros_listener')
            msgs = []
            rospy.Subscriber('leapmotion/data', leapros, msgs.append, queue_size=1000)
            deadline = rospy.get_time() + 60
            while len(msgs) < 100 and rospy.get_time() < deadline and not rospy.is_shutdown():
                rospy.sleep(0.1)
            hands = [m for m in msgs if m.palmpos.y > 0]
            print('leapros', leapros._md5sum, len(msgs), len(hands),
                  max((m.palmpos.y for m in hands), default=0),
                  max((abs(m.ypr.y) for m in hands), default=0))
            raise SystemExit(0 if len(hands) >= 50 else 1)""",
    }
    for rel, text in files.items():
        path = os.path.join(dst, rel)
        os.makedirs(os.path.dirname(path), exist_ok=True)
        with open(path, 'w') as f:
            f.write(textwrap.dedent(text).lstrip() + '\n')
    os.chmod(os.path.join(dst, 'scripts', 'listener.py'), 0o755)


def clean_env(tmp_path):
    """Only Debian's ROS and the python environment with the package's dependencies (the
    venv's bin first on PATH, as a user's python with them installed): no sourced
    workspace."""
    return {'PATH': '%s:/usr/local/bin:/usr/bin:/bin' % os.path.dirname(PYTHON),
            'HOME': os.environ.get('HOME', '/root'),
            'LANG': 'C.UTF-8', 'ROS_HOME': str(tmp_path / 'ros_home'),
            'ROS_LOG_DIR': str(tmp_path / 'ros_log'), 'ROS_HOSTNAME': '127.0.0.1',
            'ROS_IP': '127.0.0.1', 'LEAPJS_DATA': os.environ.get('LEAPJS_DATA', ''),
            'HANDS_DATA': os.environ.get('HANDS_DATA', ''),
            'PYTHONDONTWRITEBYTECODE': '1'}


def sh(cmd, env, cwd, timeout=900, setup=None):
    """Run a bash command (after sourcing `setup`); returns stdout+stderr, asserts success."""
    script = ('source %s && ' % setup if setup else '') + cmd
    proc = subprocess.run(['bash', '-c', script], env=env, cwd=str(cwd), timeout=timeout,
                          stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    assert proc.returncode == 0, '%s failed (%d):\n%s' % (cmd, proc.returncode, proc.stdout[-6000:])
    return proc.stdout


def installed_env(env, setup):
    """`env` with the install space's setup.bash sourced."""
    out = subprocess.run(['bash', '-c', 'source %s && env -0' % setup], env=env,
                         stdout=subprocess.PIPE, check=True).stdout.decode()
    return dict(item.split('=', 1) for item in out.split('\0') if '=' in item)


def gesture_bag(path):
    """A short bag of right-hand leapcobot frames, as record.launch writes."""
    import rosbag
    import rospy

    from leap_teleop.msg import leapcobotright
    with rosbag.Bag(str(path), 'w') as bag:
        for i in range(60):
            stamp = rospy.Time(1000, 0) + rospy.Duration(i / 30.0)
            msg = leapcobotright()
            msg.header.stamp = stamp
            bag.write('/leapmotion/data_right', msg, stamp)
    return str(path)


# Per launch file started from the install space (defaults): what shows it is running, in
# launch_check.py's terms: the demo's arms, drone and sender; the driver-compatible
# topics; a recorder subscribed; a replayed bag's frames; the drone simulator alone; the
# arm node alone, waiting for a robot (stopped in that wait).
SIGNS_OF_LIFE = {
    'ardrone_sim.launch': ['--topic', '/ardrone/navdata:leap_teleop/Navdata'],
    'demo.launch': ['--topic', '/ur10_2/joint_states:sensor_msgs/JointState',
                    '--topic', '/drone/ardrone/navdata:leap_teleop/Navdata',
                    '--topic', '/leapmotion/hand_left:leap_teleop/Hand'],
    'leap_motion.launch': ['--topic', '/leap_motion/leap_device:leap_teleop/DriverHuman',
                           '--count', '30'],
    'record.launch': ['--subscribed', '/leapmotion/data_right', '--subscribed', '/tf_static'],
    'replay.launch': ['--topic', '/leapmotion/data_right:leap_teleop/leapcobotright',
                      '--count', '30'],
    'ur10_arm.launch': ['--advertised', '/ur10_1/arm_controller/command',
                        '--subscribed', '/ur10_1/joint_states'],
}


# Started from the install space: together they start every node type any launch file
# names with its defaults (checked below). The others start from the source tree in
# test_launch_smoke.py (stopped with Ctrl-C there too) and differ from these only in how
# many of the same nodes run, in which namespaces: here they are resolved, not started.
INSTALLED_RUNS = tuple(SIGNS_OF_LIFE)

# Run in the install space's environment: each launch file loaded as roslaunch loads it
# (includes, args, rosparam files, param commands run); per file, its node types with the
# executables roslaunch would start and the parameter values that are paths.
RESOLVE_LAUNCHES = textwrap.dedent("""
    import json, os, sys
    import roslaunch.config, roslaunch.xmlloader, roslib.packages
    out = {}
    for path, argv in json.loads(sys.argv[1]):
        cfg = roslaunch.config.ROSLaunchConfig()
        loader = roslaunch.xmlloader.XmlLoader(resolve_anon=False)
        loader.ignore_unset_args = False     # as roslaunch sets it: a missing arg is named
        loader.load(path, cfg, argv=['roslaunch'] + argv, verbose=False)
        nodes = sorted({(n.package, n.type) for n in cfg.nodes})
        out[os.path.basename(path)] = {
            'nodes': [[pkg, kind, roslib.packages.find_node(pkg, kind)] for pkg, kind in nodes],
            'paths': sorted(v for v in (p.value for p in cfg.params.values())
                            if isinstance(v, str) and v.startswith('/') and '\\n' not in v)}
    print(json.dumps(out))""")


def launch_args(launch, tmp_path):
    """The args to start `launch` with its defaults: replay.launch needs its bag."""
    return ['bag:=' + gesture_bag(tmp_path / 'gestures.bag')] if launch == 'replay.launch' else []


@pytest.mark.rostest
def test_builds_tests_installs_and_runs_in_a_users_workspace(tmp_path):
    for tool in ('catkin_make', 'catkin', 'catkin_lint'):
        assert shutil.which(tool), '%s missing: make setup installs it (tools/debian-packages.txt)' % tool
    env = clean_env(tmp_path)
    ws = tmp_path / 'ws'
    copy_package(str(ws / 'src' / 'leap_teleop'))
    write_leap_motion(str(ws / 'src' / 'leap_motion'))

    lint = sh('catkin_lint -W2 --strict src/leap_teleop', env, ws)
    assert 'found 0 problems' in lint, lint

    args = '-DPYTHON_EXECUTABLE=%s -DCATKIN_ENABLE_TESTING=ON' % PYTHON
    sh('catkin_make %s' % args, env, ws)
    devel = ws / 'devel' / 'setup.bash'
    # `catkin_make run_tests` runs every test/*.test rostest and the pytest suite: each has
    # its run_tests target (rostests with args are named after them too).
    targets = set(re.findall(r'^\.\.\. (run_tests_leap_teleop\S*)$',
                             sh('make help', env, ws / 'build'), re.M))
    assert 'run_tests_leap_teleop_pytest_suite' in targets, sorted(targets)
    rostests = sorted(f[:-len('.test')] for f in os.listdir(HERE) if f.endswith('.test'))
    for name in rostests:
        pattern = r'run_tests_leap_teleop_rostest_(test_)?%s(__.*)?\.test$' % re.escape(name)
        assert any(re.match(pattern, t) for t in targets), (name, sorted(targets))
    assert len([t for t in targets if t.endswith('.test')]) == len(rostests), sorted(targets)
    # run_tests: one rostest target (the lightest graph, the sender alone) and the pytest
    # target, narrowed to the message tests.
    out = sh('catkin_make %s run_tests_leap_teleop_rostest_test_leapros.test '
             'run_tests_leap_teleop_pytest_suite && catkin_test_results build/test_results'
             % args, dict(env, PYTEST_ADDOPTS='-k test_messages -p no:cacheprovider'), ws,
             setup=devel)
    assert '0 errors, 0 failures' in out, out[-3000:]
    results = os.listdir(ws / 'build' / 'test_results' / 'leap_teleop')
    assert 'pytest-suite.xml' in results and any('leapros' in r for r in results), results

    sh('catkin_make %s install' % args, env, ws)
    install = ws / 'install'
    share = install / 'share' / 'leap_teleop'
    for folder in ('launch', 'config', 'msg', 'srv', 'rviz'):
        assert (share / folder).is_dir(), folder
    # From the install space alone (no devel, no source): the package, the library, the
    # nodes and every launch file.
    setup = install / 'setup.bash'
    found = sh('rospack find leap_teleop && %s -c "import leap_teleop.msg, leap_teleop.ur10.model;'
               'print(leap_teleop.__file__)" && rosrun leap_teleop sender.py --help | head -1'
               % PYTHON, env, ws, setup=setup)
    assert str(share) in found and str(install / 'lib') in found, found
    installed = installed_env(env, setup)
    assert sorted(os.listdir(share / 'launch')) == sorted(
        f for f in os.listdir(os.path.join(ROOT, 'launch')) if f.endswith('.launch'))
    launches = sorted(os.listdir(share / 'launch'))
    resolved = json.loads(sh('%s -c %s %s' % (PYTHON, shlex.quote(RESOLVE_LAUNCHES), shlex.quote(
        json.dumps([[str(share / 'launch' / f), launch_args(f, tmp_path)]
                    for f in launches]))), env, ws, setup=setup).splitlines()[-1])
    for launch in launches:
        for pkg, kind, paths in resolved[launch]['nodes']:
            assert paths, '%s: node %s/%s is not installed' % (launch, pkg, kind)
            if pkg == 'leap_teleop':
                assert all(p.startswith(str(install)) for p in paths), (launch, kind, paths)
        for path in resolved[launch]['paths']:
            assert not path.startswith(str(install)) or os.path.exists(path), (launch, path)
    kinds = {launch: {tuple(n[:2]) for n in resolved[launch]['nodes']} for launch in launches}
    uncovered = set().union(*kinds.values()) - set().union(*(kinds[f] for f in INSTALLED_RUNS))
    assert not uncovered, 'node types no installed run starts: %s' % sorted(uncovered)
    for launch in INSTALLED_RUNS:
        (tmp_path / launch).mkdir()
        run_launches(tmp_path / launch, [[launch] + launch_args(launch, tmp_path)],
                     SIGNS_OF_LIFE[launch], 90, env=installed, clean_exit=True)
    # The installed sender feeds the classic consumer (leap_motion/leapros, same MD5).
    port = free_port()
    env_run = dict(env, ROS_MASTER_URI='http://127.0.0.1:%d' % port)
    sender = subprocess.Popen(
        ['bash', '-c', 'source %s && exec roslaunch -p %d leap_teleop sender.launch '
                       'leapros_topic:=leapmotion/data loop:=true' % (setup, port)],
        env=env_run, stdout=open(tmp_path / 'sender.log', 'wb'), stderr=subprocess.STDOUT,
        start_new_session=True)
    try:
        out = sh('rosrun leap_motion listener.py', env_run, ws, setup=setup, timeout=120)
    finally:
        os.killpg(sender.pid, signal.SIGINT)
        sender.wait(30)
    line = [ln for ln in out.splitlines() if ln.startswith('leapros ')][-1].split()
    assert line[1] == LEAPROS_MD5
    assert int(line[3]) >= 50 and 100.0 < float(line[4]) < 400.0, line   # palm height, mm

    # catkin build (catkin-tools) of the same sources in a second workspace.
    ws2 = tmp_path / 'ws2'
    (ws2 / 'src').mkdir(parents=True)
    for pkg in ('leap_teleop', 'leap_motion'):
        os.symlink(ws / 'src' / pkg, ws2 / 'src' / pkg)
    sh('catkin init && catkin config --cmake-args -DPYTHON_EXECUTABLE=%s && '
       'catkin build --no-status --no-notify' % PYTHON, env, ws2)
    built = sh('%s -c "from leap_teleop.msg import leapros; from leap_motion.msg import '
               'leapros as classic; print(leapros._md5sum, classic._md5sum)"' % PYTHON, env, ws2,
               setup=ws2 / 'devel' / 'setup.bash')
    assert built.split()[-2:] == [LEAPROS_MD5, LEAPROS_MD5], built


def test_every_rostest_starts_without_args():
    # `catkin_make run_tests` passes only leapjs_data / hands_data (CMakeLists.txt): any
    # other arg of a test/*.test needs a default, or its run_tests target errors.
    import xml.etree.ElementTree as ET
    passed = {'leapjs_data', 'hands_data'}
    names = sorted(f for f in os.listdir(HERE) if f.endswith('.test'))
    assert names
    for name in names:
        for arg in ET.parse(os.path.join(HERE, name)).getroot().iter('arg'):
            assert ('default' in arg.attrib or 'value' in arg.attrib
                    or arg.get('name') in passed), '%s: arg %s has no default' % (name, arg.get('name'))
