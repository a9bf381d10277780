"""Ctrl-C / SIGTERM shut a node down even when they arrive while its main thread holds a
lock that rospy's shutdown needs (a publisher's connection lock, mid-publish)."""
import os
import signal
import subprocess
import sys
import textwrap
import time

import pytest
import rosgraph

# needs a ROS master, a simulator, a subprocess or a build: not in make check
pytestmark = pytest.mark.integration

# A shutdown hook stands in for rospy's cleanup: it needs a lock that the main thread
# holds at the moment the signal arrives, and the main thread then waits for shutdown.
PROGRAM = textwrap.dedent('''
    import os, signal, sys, threading, time
    import rospy
    from leap_teleop.ros.signals import install_shutdown_handlers
    handlers = sys.argv[1]
    lock, ran_in = threading.Lock(), []
    def hook(*_reason):
        with lock:
            ran_in.append(threading.current_thread().name)
    rospy.core.add_shutdown_hook(hook)
    if handlers == 'ours':
        install_shutdown_handlers()
    else:
        rospy.core.register_signals()
    with lock:
        os.kill(os.getpid(), signal.%s)
        time.sleep(0.3)       # the Python-level handler has run on this thread by now
    deadline = time.monotonic() + 5.0
    while not (rospy.is_shutdown() and ran_in) and time.monotonic() < deadline:
        time.sleep(0.01)
    print('shutdown', rospy.is_shutdown(), 'hook ran in', ran_in, flush=True)
    if len(sys.argv) > 2:
        os.kill(os.getpid(), signal.SIGINT)   # a second signal: the default action
        time.sleep(5.0)
        print('still alive', flush=True)
''')


def run(handlers, sig, *more, timeout=15):
    return subprocess.run([sys.executable, '-c', PROGRAM % sig, handlers] + list(more),
                          capture_output=True, text=True, timeout=timeout)


@pytest.mark.parametrize('sig', ['SIGINT', 'SIGTERM'])
def test_a_signal_while_the_main_thread_holds_a_lock_shuts_down_from_another_thread(sig):
    out = run('ours', sig)
    assert out.returncode == 0, out.stderr
    assert "shutdown True hook ran in ['signal_shutdown']" in out.stdout, out.stdout + out.stderr


def test_rospys_own_handler_deadlocks_there():
    """The case the handlers exist for: rospy runs the hook inside the handler, on the main
    thread that holds the lock."""
    with pytest.raises(subprocess.TimeoutExpired):
        run('rospy', 'SIGINT', timeout=4)


def test_a_second_signal_ends_the_process_at_once():
    out = run('ours', 'SIGTERM', 'again')
    assert 'shutdown True' in out.stdout, out.stdout + out.stderr
    assert 'still alive' not in out.stdout
    assert out.returncode == -signal.SIGINT, (out.returncode, out.stderr)


ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), '..')


def interrupt_runs(env, args, ready, runs, rng):
    """Start `args(i)` for i in range(runs); once `ready` is in its output (or, when `ready` is a
    function, once ready(i) returns true), after a random 0.1..0.8 s, SIGINT it. [(exit status
    or None if still up 10 s later, output)]."""
    out = []
    for i in range(runs):
        proc = subprocess.Popen(args(i), env=env, stdout=subprocess.PIPE,
                                stderr=subprocess.STDOUT, text=True)
        lines = []
        try:
            if callable(ready):
                deadline = time.monotonic() + 20.0
                while not ready(i) and time.monotonic() < deadline:
                    time.sleep(0.05)
            else:
                for line in proc.stdout:
                    lines.append(line)
                    if ready in line:
                        break
            time.sleep(rng.uniform(0.1, 0.8))
            proc.send_signal(signal.SIGINT)
            try:
                proc.wait(10.0)
                status = proc.returncode
            except subprocess.TimeoutExpired:
                status = None
        finally:
            if proc.poll() is None:
                proc.kill()
                proc.wait()
        out.append((status, ''.join(lines) + proc.stdout.read()))
    return out


def test_publishing_nodes_end_cleanly_on_ctrl_c():
    """A node publishing from its main thread at 1 kHz, and the UR10 simulator (joint states
    from its main thread), each stopped mid-run: status 0 within 10 s, no traceback (rospy
    refuses publishes once it has closed the topics, before is_shutdown() turns true)."""
    import random

    from tools.bench.ros_processes import ros_master
    rng = random.Random(7)
    with ros_master() as env:
        master = rosgraph.Master('/signals_test', master_uri=env['ROS_MASTER_URI'])

        # A subscriber makes closing the topic take a while (its connection ends).
        echo = subprocess.Popen([sys.executable, '-m', 'tools.bench.echo'], env=env,
                                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)

        def publishing(i):
            return any(t == '/bench/echo_in' and '/bare_publisher' in nodes
                       for t, nodes in master.getSystemState()[0])
        try:
            runs = interrupt_runs(env, lambda i: [sys.executable, '-m',
                                                  'tools.bench.bare_publisher', '--rate',
                                                  '1000', '--topic', 'bench/echo_in'],
                                  publishing, 8, rng)
        finally:
            echo.send_signal(signal.SIGINT)
            echo.wait(10)
        sim = [sys.executable, os.path.join(ROOT, 'scripts', 'ur10_sim.py')]
        runs += interrupt_runs(env, lambda i: sim, 'ur10_sim: ready', 4, rng)
    for status, text in runs:
        assert status == 0 and 'Traceback' not in text, (status, text[-2000:])


def test_a_hand_source_publishing_into_a_shutdown_is_quiet(monkeypatch):
    # The sender's source thread can outlive stop()'s join by a frame: its publish, refused
    # because the node shuts down, ended the take as 'hand source failed' (exit status 2).
    import rospy

    from leap_teleop.ros.signals import quiet_at_shutdown

    def publish(*_args):
        raise rospy.ROSException('publish() to a closed topic')
    call = quiet_at_shutdown(publish)
    with pytest.raises(rospy.ROSException):          # not shutting down: a real error
        call('frame', 'state')
    monkeypatch.setattr(rospy.core, 'is_shutdown_requested', lambda: True)
    assert call('frame', 'state') is None
    assert quiet_at_shutdown(lambda a, b: a + b)(1, 2) == 3


def test_ctrl_c_stops_the_sender_cleanly_not_as_a_source_end_or_a_bad_parameter(tmp_path):
    """Ctrl-C on a running sender once logged 'source ended after N frames' (the shutdown
    hook stops the source before rospy.is_shutdown() turns true); while it waited for
    ~camera_info_topic, a FATAL 'bad parameter' and status 1."""
    import random

    import cv2
    import numpy as np

    from tools.bench.ros_processes import ros_master
    image = str(tmp_path / 'still.png')
    cv2.imwrite(image, np.zeros((48, 64, 3), np.uint8))
    sender = [sys.executable, os.path.join(ROOT, 'scripts', 'sender.py')]
    rng = random.Random(5)
    with ros_master() as env:
        master = rosgraph.Master('/signals_test', master_uri=env['ROS_MASTER_URI'])

        def sender_up(_i):
            try:
                return bool(master.lookupNode('/leap_sender'))
            except rosgraph.MasterError:
                return False
        runs = interrupt_runs(env, lambda i: sender + ['_loop:=true', '_shutdown_on_end:=%s' % bool(i)],
                              'sender: publishing', 2, rng)
        waits = interrupt_runs(env, lambda i: sender + ['_source:=video', '_video:=' + image,
                                                        '_camera_info_topic:=/camera/camera_info'],
                               sender_up, 1, rng)
    for status, text in runs + waits:
        assert status == 0, (status, text[-2000:])
        for sign in ('source ended', 'bad parameter', 'Traceback'):
            assert sign not in text, text[-2000:]


# A source that delivers frames, then fails as an unplugged webcam does.
FAILING_SOURCE_SENDER = textwrap.dedent('''
    import sys, time
    import numpy as np
    from leap_teleop.hands.frame import Frame, TrackedHand
    from leap_teleop.hands.sources import SOURCES
    from leap_teleop.hands.sources.source import HandSource, SourceError

    class Unplugged(HandSource):
        rate_hz = 30.0

        def __init__(self, **_):
            pass

        def frames(self):
            for k in range(30):
                time.sleep(1 / 30.0)
                yield Frame(k + 1, time.time(), [TrackedHand('right', np.array([0., 200., 0.]), id=1)])
            raise SourceError('camera 0 stopped delivering frames (unplugged?)')

    sys.modules['unplugged'] = sys.modules[__name__]
    SOURCES['scripted'] = ('unplugged', 'Unplugged')
    from leap_teleop.ros.nodes import sender
    sender.main(['sender.py'] + sys.argv[1:])
''')


def test_a_sender_whose_source_fails_ends_with_status_2_so_it_can_be_respawned():
    # It logged 'source ended', reported OK on /diagnostics and spun for ever, publishing
    # nothing (sender.launch leaves ~shutdown_on_end false), so respawn never came.
    from tools.bench.ros_processes import ros_master
    with ros_master() as env:
        proc = subprocess.Popen([sys.executable, '-c', FAILING_SOURCE_SENDER,
                                 '_shutdown_on_end:=false'], env=env,
                                stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        try:
            out, _ = proc.communicate(timeout=30)
        except subprocess.TimeoutExpired:
            proc.kill()
            out = proc.communicate()[0]
            raise AssertionError('the sender did not end: ' + out[-2000:])
        finally:
            if proc.poll() is None:
                proc.kill()
                proc.wait()
    assert proc.returncode == 2, out[-2000:]
    assert 'the hand source failed: camera 0 stopped delivering frames' in out, out[-2000:]
    assert 'source ended' not in out and 'Traceback' not in out, out[-2000:]


def test_the_sender_reports_a_failed_source_as_an_error_on_diagnostics():
    import types

    from leap_teleop.ros.hand_topics import HandTopics
    topics = types.SimpleNamespace(interface=types.SimpleNamespace(
        frames_seen=30, rejected_frames=0, error=None), published=30)
    assert HandTopics.report(topics)[0] == 'ok'
    topics.interface.error = RuntimeError('camera 0 stopped delivering frames')
    level, summary, _ = HandTopics.report(topics)
    assert level == 'error' and 'camera 0 stopped delivering frames' in summary
