"""Helpers for benchmarks that run real ROS processes: a private master, nodes as
subprocesses, a measuring probe in its own process, and percentile figures."""
import contextlib
import json
import os
import signal
import socket
import subprocess
import sys
import tempfile
import time

import numpy as np


def free_port():
    with socket.socket() as s:
        s.bind(('127.0.0.1', 0))
        return s.getsockname()[1]


@contextlib.contextmanager
def ros_master(base_env=None):
    """A private rosmaster on a free loopback port; yields the env to run nodes in
    (`base_env`, default this process's, pointed at that master)."""
    port = free_port()
    env = dict(os.environ if base_env is None else base_env, ROS_MASTER_URI='http://127.0.0.1:%d' % port,
               ROS_HOSTNAME='127.0.0.1', ROS_IP='127.0.0.1')
    master = subprocess.Popen(['rosmaster', '--core', '-p', str(port)], env=env,
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        _wait_for_master(env)
        yield env
    finally:
        master.terminate()
        master.wait(10)


def _wait_for_master(env, timeout=15.0):
    import xmlrpc.client
    proxy = xmlrpc.client.ServerProxy(env['ROS_MASTER_URI'])
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        try:
            proxy.getPid('/bench')
            return
        except OSError:
            time.sleep(0.1)
    raise RuntimeError('rosmaster did not come up')


def spawn_node(env, args):
    """Start `args` (a command list) as a ROS process; stop it with stop_spawned(). Its
    stderr goes to a temporary file, `proc.stderr`, to read once stop_spawned() has
    returned: a pipe nobody reads while it runs would block it once 64 KiB of warnings
    had filled it."""
    err = tempfile.TemporaryFile()
    proc = subprocess.Popen(args, env=env, stdout=subprocess.DEVNULL, stderr=err)
    proc.stderr = err
    return proc


def stop_spawned(proc, timeout=10.0):
    if proc.poll() is None:
        proc.send_signal(2)
        try:
            proc.wait(timeout)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()
    if proc.stderr is not None and proc.stderr.seekable():
        proc.stderr.seek(0)             # spawn_node's file: read from the start


def interrupt_group(proc, timeout=30.0):
    """Stop a process started with start_new_session=True as Ctrl-C does: SIGINT to its
    process group, SIGKILL to the group if it outlives `timeout`. False when it had to be
    killed; True when it ended on SIGINT or had ended before."""
    if proc.poll() is not None:
        return True
    os.killpg(proc.pid, signal.SIGINT)
    try:
        proc.wait(timeout)
        return True
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
        return False


def probe(env, topic, msg_type, duration, warmup=1.0, cpu_pid=0):
    """Run tools.bench.probe in its own process; returns its record dict:
    per message receipt time, header stamp, and leap_frame_id where the type has one;
    with cpu_pid, 'cpu_s': that process's CPU seconds over the same recording window."""
    with tempfile.NamedTemporaryFile(suffix='.json', delete=False) as f:
        out = f.name
    try:
        subprocess.run([sys.executable, '-m', 'tools.bench.probe', '--topic', topic,
                        '--type', msg_type, '--duration', str(duration), '--warmup', str(warmup),
                        '--cpu-pid', str(cpu_pid), '--out', out], env=env, check=True,
                       timeout=duration + warmup + 60)
        with open(out) as f:
            return json.load(f)
    finally:
        os.unlink(out)


def percentiles_ms(latencies_s):
    a = np.asarray(latencies_s) * 1000.0
    return float(np.percentile(a, 50)), float(np.percentile(a, 99))
