"""Two hosts on one machine: the paper's ground station / robot split over a real network.

Two network namespaces joined by a veth pair (10.231.0.1/24 ground station, 10.231.0.2/24
robot). The ground station runs the master and the sender (scripted single-arm pick and
place); the robot runs the UR10 arm node and the simulator, each host with its own
ROS_IP. The cube must end within 3 cm of its tray's centre. Skips where namespaces
cannot be created (not root, no CAP_NET_ADMIN); fails without iproute2 (a setup package).
The namespaces are always deleted.

Run as a script with --check inside the ground station namespace, this file is the
checker: it waits for the robot, starts the sender, waits for it to end and prints the
cube's distance to the tray as JSON.
"""
import json
import os
import shutil
import signal
import subprocess
import sys
import time

import pytest

# env.sh and tools/setup.sh of a checkout set up by make setup: not part of a package
# built in a user's workspace (catkin_make run_tests leaves these out).
pytestmark = [pytest.mark.checkout, pytest.mark.integration]

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
GROUND, ROBOT = '10.231.0.1', '10.231.0.2'
PORT = 11311
SCRIPT = os.path.join(ROOT, 'config', 'gestures', 'ur10_pick_place_single.yaml')


def _ip(*args, check=True):
    return subprocess.run(['ip'] + list(args), stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                          text=True, check=check)


def _netns_env(ip, log_dir):
    env = {k: v for k, v in os.environ.items() if k not in ('LD_PRELOAD',)}
    env.update(ROS_IP=ip, ROS_HOSTNAME=ip, ROS_MASTER_URI='http://%s:%d' % (GROUND, PORT),
               ROS_LOG_DIR=log_dir)
    return env


class Namespaces:
    def __init__(self):
        tag = '%d' % (os.getpid() % 100000)
        self.ground, self.robot = 'lt_ground_' + tag, 'lt_robot_' + tag
        self.veth = ('ltg' + tag, 'ltr' + tag)
        self.made = []

    def create(self):
        for ns in (self.ground, self.robot):
            _ip('netns', 'add', ns)
            self.made.append(ns)
        _ip('link', 'add', self.veth[0], 'type', 'veth', 'peer', 'name', self.veth[1])
        for ns, dev, addr in ((self.ground, self.veth[0], GROUND),
                              (self.robot, self.veth[1], ROBOT)):
            _ip('link', 'set', dev, 'netns', ns)
            _ip('-n', ns, 'addr', 'add', addr + '/24', 'dev', dev)
            _ip('-n', ns, 'link', 'set', dev, 'up')
            _ip('-n', ns, 'link', 'set', 'lo', 'up')

    def exec(self, ns, cmd, env, **kw):
        return subprocess.Popen(['ip', 'netns', 'exec', ns] + cmd, env=env,
                                start_new_session=True, **kw)

    def destroy(self):
        for ns in self.made:
            pids = _ip('netns', 'pids', ns, check=False).stdout.split()
            for pid in pids:
                try:
                    os.kill(int(pid), signal.SIGKILL)
                except OSError:
                    pass
            _ip('netns', 'del', ns, check=False)
        # The veth pair goes with its namespaces; a half-made one may be left in ours.
        _ip('link', 'del', self.veth[0], check=False)


def _stop(proc):
    if proc is None or proc.poll() is not None:
        return
    try:
        os.killpg(proc.pid, signal.SIGINT)
        proc.wait(15)
    except (OSError, subprocess.TimeoutExpired):
        try:
            os.killpg(proc.pid, signal.SIGKILL)
        except OSError:
            pass


def test_pick_and_place_across_two_hosts(tmp_path):
    assert shutil.which('ip'), 'ip not on PATH (Debian package iproute2)'
    nets = Namespaces()
    try:
        nets.create()
    except (subprocess.CalledProcessError, OSError) as e:
        nets.destroy()
        pytest.skip('cannot create network namespaces here (needs root / CAP_NET_ADMIN): %s'
                    % (getattr(e, 'stderr', '') or e))
    env_sh = os.path.join(ROOT, 'env.sh')
    procs = []
    try:
        genv, renv = _netns_env(GROUND, str(tmp_path / 'ground')), _netns_env(ROBOT, str(
            tmp_path / 'robot'))
        # The two hosts reach each other over the veth, and only through it.
        ping = subprocess.run(['ip', 'netns', 'exec', nets.robot, 'ping', '-c', '1', '-W', '2',
                               GROUND], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        if shutil.which('ping'):
            assert ping.returncode == 0, 'robot cannot reach the ground station'
        procs.append(nets.exec(nets.ground, [env_sh, 'roscore', '-p', str(PORT)], genv,
                               stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
        procs.append(nets.exec(nets.robot, [env_sh, 'roslaunch', '--wait', 'leap_teleop',
                                            'ur10_single.launch', 'sender:=false'], renv,
                               stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
        check = nets.exec(nets.ground, [env_sh, 'python', os.path.abspath(__file__), '--check'],
                          genv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        procs.append(check)
        out, err = check.communicate(timeout=150)
        assert check.returncode == 0, 'checker failed:\n%s\n%s' % (out, err[-3000:])
        result = json.loads(out.strip().splitlines()[-1])
        print('two hosts:', result)
        # The arm node and the simulator ran on the robot host, the sender on the ground.
        assert result['hosts']['/ur10_1/ur10_arm'] == ROBOT
        assert result['hosts']['/ur10_sim'] == ROBOT
        assert result['hosts']['/leap_sender'] == GROUND
        assert result['error_m'] < 0.03, result
    finally:
        for p in reversed(procs):
            _stop(p)
        nets.destroy()


# -- checker (runs inside the ground station namespace) -------------------------------------
def check():
    from urllib.parse import urlparse

    import numpy as np
    import rosgraph
    import rospy
    from sensor_msgs.msg import JointState

    from leap_teleop.ros.ur10_conversions import OBJECT_POSES_TOPIC, OBJECT_POSES_TYPE, object_positions
    from leap_teleop.ur10.config import load_config
    rospy.init_node('two_hosts_check')
    rospy.wait_for_message('/ur10_1/joint_states', JointState, timeout=90)
    master = rosgraph.Master('/two_hosts_check')
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline:
        try:
            master.lookupNode('/ur10_1/ur10_arm')
            break
        except rosgraph.MasterError:
            time.sleep(0.2)
    # The session starts once the arm node listens: it subscribes only after its robot's
    # joints, which may come after this node has had them on a loaded machine.
    sender = subprocess.Popen(['roslaunch', 'leap_teleop', 'sender.launch',
                               'script:=%s' % SCRIPT, 'right_topic:=leapmotion/data',
                               'shutdown_on_end:=true', 'required:=true',
                               'wait_for_subscribers:=true', 'wait_topics:=[leapmotion/data]'],
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                              start_new_session=True)
    hosts = {}
    while sender.poll() is None and not rospy.is_shutdown():
        for name in ('/ur10_1/ur10_arm', '/ur10_sim', '/leap_sender'):
            try:
                hosts[name] = urlparse(master.lookupNode(name)).hostname
            except rosgraph.MasterError:
                pass
        time.sleep(0.5)
    time.sleep(3.0)
    msg = rospy.wait_for_message(OBJECT_POSES_TOPIC, OBJECT_POSES_TYPE, timeout=10)
    cube = object_positions(msg)['cube_red']
    tray = load_config('ur10_cell.yaml').arm('ur10_1').tray
    err = float(np.linalg.norm(np.asarray(cube[:2]) - np.asarray(tray.xyz[:2])))
    print(json.dumps({'error_m': err, 'cube': list(cube), 'hosts': hosts}))


if __name__ == '__main__' and '--check' in sys.argv:
    check()
