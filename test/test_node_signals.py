"""Ctrl-C / SIGTERM shut a node down even when they arrive while its main thread holds a
lock that rospy's shutdown needs (a publisher's connection lock, mid-publish)."""
import signal
import subprocess
import sys
import textwrap

import pytest

# A shutdown hook stands in for rospy's cleanup: it needs a lock that the main thread
# holds at the moment the signal arrives, and the main thread then waits for shutdown.
PROGRAM = textwrap.dedent('''
    import os, signal, sys, threading, time
    import rospy
    from leap_teleop.nodes.signals import install_shutdown_handlers
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
