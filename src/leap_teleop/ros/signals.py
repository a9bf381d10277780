"""Ctrl-C and SIGTERM end a node by rospy.signal_shutdown on a thread of its own.

rospy's own handler calls signal_shutdown inside the signal handler, that is on the main
thread between two of its bytecodes. When the main thread was publishing at that moment
it holds the connection's lock that signal_shutdown's cleanup waits for (via rospy's
topic-manager lock, held meanwhile by its registration thread): the node deadlocks, and
a second signal deadlocks the same way, so only SIGKILL ends it. Here the handler only
writes a byte to a pipe; a daemon thread reads it and shuts rospy down, so the main thread
runs on, releases its locks and ends its loop on rospy.is_shutdown(). A second signal,
while that clean shutdown runs, ends the process at once (the default action).

rospy closes every topic before is_shutdown() turns true, so a loop that publishes while
another thread shuts rospy down runs into a refused publish: closed_at_shutdown() ends
such a loop quietly.
"""
import contextlib
import os
import signal
import threading

import rospy

SIGNALS = (signal.SIGINT, signal.SIGTERM)


def init_node(name, **kwargs):
    """rospy.init_node with the handlers above instead of rospy's."""
    rospy.init_node(name, disable_signals=True, **kwargs)
    install_shutdown_handlers()


def install_shutdown_handlers(signals=SIGNALS):
    """From the main thread: the first of `signals` shuts rospy down from a daemon thread,
    a second one takes the default action. Returns that thread."""
    read_fd, write_fd = os.pipe()

    def handler(signum, _frame):
        # Nothing here may take a lock the interrupted main thread could hold.
        for s in signals:
            signal.signal(s, signal.SIG_DFL)
        os.write(write_fd, bytes([signum]))

    def shut_down():
        signum = os.read(read_fd, 1)[0]
        rospy.signal_shutdown('signal-%d' % signum)

    thread = threading.Thread(target=shut_down, name='signal_shutdown', daemon=True)
    thread.start()
    for s in signals:
        signal.signal(s, handler)
    return thread


@contextlib.contextmanager
def closed_at_shutdown():
    """Around a loop that publishes: a publish rospy refuses because the node is shutting
    down ends the block quietly; any other error passes on."""
    try:
        yield
    except rospy.ROSException:
        if not rospy.core.is_shutdown_requested():
            raise


def quiet_at_shutdown(callback):
    """`callback` (one that publishes, called by a thread rospy does not own: a hand
    source's) as closed_at_shutdown treats a loop: its publish refused because the node is
    shutting down returns None; any other error passes on."""
    def call(*args):
        # closed_at_shutdown's test without its context manager: 1 us less per hand
        try:
            return callback(*args)
        except rospy.ROSException:
            if not rospy.core.is_shutdown_requested():
                raise
    return call
