"""By default every node of a running graph listens on loopback only.

rospy nodes and the master bind to ROS_IP; roscpp nodes (rosout, robot_state_publisher)
bind 0.0.0.0 whatever ROS_IP says, so env.sh preloads tools/loopback_bind.c (built by
tools/setup.sh) while ROS_IP / ROS_HOSTNAME is loopback. The graph is started through
env.sh exactly as a user gets it."""
import os
import re
import shutil
import signal
import subprocess
import time

import pytest

from tools.bench.ros_processes import free_port

# env.sh and tools/setup.sh of a checkout set up by make setup: not part of a package
# built in a user's workspace (catkin_make run_tests leaves these out).
pytestmark = [pytest.mark.checkout, pytest.mark.integration]

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
LAUNCHES = [('demo.launch', ['ur10:=true', 'drone:=true'])]


def _descendants(pid):
    out = subprocess.run(['ps', '-e', '-o', 'pid=,ppid='], stdout=subprocess.PIPE, text=True).stdout
    children = {}
    for line in out.splitlines():
        p, pp = (int(x) for x in line.split())
        children.setdefault(pp, []).append(p)
    found, todo = set(), [pid]
    while todo:
        p = todo.pop()
        found.add(p)
        todo.extend(children.get(p, []))
    return found


def _listening(pids):
    """(address, pid) of every listening TCP/UDP socket owned by pids."""
    out = subprocess.run(['ss', '-Hlntup'], stdout=subprocess.PIPE, text=True).stdout
    sockets = []
    for line in out.splitlines():
        fields = line.split()
        local = fields[4]
        for pid in re.findall(r'pid=(\d+)', line):
            if int(pid) in pids:
                sockets.append((local, int(pid)))
    return sockets


@pytest.mark.parametrize('launch, args', LAUNCHES)
def test_every_listening_socket_is_on_loopback(launch, args, tmp_path):
    assert shutil.which('ss'), 'ss not on PATH (Debian package iproute2)'
    port = free_port()
    env = dict(os.environ, ROS_MASTER_URI='http://127.0.0.1:%d' % port,
               ROS_LOG_DIR=str(tmp_path))
    # The user's defaults: env.sh picks ROS_IP / ROS_HOSTNAME and the shim itself.
    for key in ('ROS_IP', 'ROS_HOSTNAME', 'LD_PRELOAD'):
        env.pop(key, None)
    proc = subprocess.Popen([os.path.join(ROOT, 'env.sh'), 'roslaunch', '-p', str(port),
                             'leap_teleop', launch] + args,
                            env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                            start_new_session=True)
    try:
        deadline = time.monotonic() + 60
        sockets = []
        # Wait until the graph is up: the master plus at least one socket per node.
        while time.monotonic() < deadline:
            time.sleep(2.0)
            pids = _descendants(proc.pid)
            sockets = _listening(pids)
            if len({pid for _, pid in sockets}) >= 10:
                break
        # master, rosout, 2 senders, 2 arm nodes, 2 robot_state_publishers, 2 sims, pilot
        assert len({pid for _, pid in sockets}) >= 10, sockets
        exposed = [(addr, pid) for addr, pid in sockets
                   if not (addr.startswith('127.') or addr.startswith('[::1]'))]
        assert not exposed, 'listening beyond loopback: %s' % exposed
    finally:
        os.killpg(proc.pid, signal.SIGINT)
        try:
            proc.wait(20)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)


SHIM = os.path.join(ROOT, '.ws', 'loopback_bind.so')
BIND_ANY = ('import socket; s = socket.socket(); s.bind(("0.0.0.0", 0)); '
            'print(s.getsockname()[0])')


@pytest.mark.parametrize('ros_ip, bound', [('127.0.0.1', '127.0.0.1'),
                                           ('10.231.9.1', '0.0.0.0')])
def test_shim_binds_wildcards_to_loopback_only_while_ros_is_on_loopback(ros_ip, bound):
    assert os.path.exists(SHIM), 'tools/setup.sh did not build %s (no C compiler?)' % SHIM
    env = dict(os.environ, ROS_IP=ros_ip, ROS_HOSTNAME=ros_ip, LD_PRELOAD=SHIM)
    out = subprocess.run(['python3', '-c', BIND_ANY], env=env, stdout=subprocess.PIPE,
                         text=True, check=True).stdout.strip()
    assert out == bound


def test_env_sh_preloads_the_shim_only_for_loopback():
    env = {k: v for k, v in os.environ.items() if k not in ('ROS_IP', 'ROS_HOSTNAME',
                                                            'LD_PRELOAD')}
    show = [os.path.join(ROOT, 'env.sh'), 'bash', '-c', 'echo "$LD_PRELOAD"']
    assert SHIM in subprocess.run(show, env=env, stdout=subprocess.PIPE, text=True).stdout
    env.update(ROS_IP='10.231.9.1', ROS_HOSTNAME='10.231.9.1')
    assert SHIM not in subprocess.run(show, env=env, stdout=subprocess.PIPE, text=True).stdout
