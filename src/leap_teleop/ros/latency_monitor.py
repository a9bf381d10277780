"""latency_monitor: a live table of the age of the hand input at each stage (capture ->
sender recognized, published, arm / pilot command; p50 / p99 over each node's window),
read from /diagnostics, one row per (node, stage) in data-path order; then, per arm, how
long the UR10 simulator's commands waited for the physics step that applied them.

usage: rosrun leap_teleop latency_monitor [--once] [--timeout S]
  --once      print one table (1.5 s after the first report), then exit
  --timeout   give up (exit 1) when no node reports an input age or a command wait within S seconds
              (or the ROS master does not answer within S seconds)
"""
import argparse
import math
import socket
import sys
import threading
import time
import xmlrpc.client

import rosgraph
import rospy
from diagnostic_msgs.msg import DiagnosticArray

from leap_teleop.control.input_age import LatencyBoard


class LatencyMonitor:
    """Subscribes /diagnostics and keeps a LatencyBoard of every node's input ages (also
    used by hand_markers' text marker and the sender's camera overlay)."""

    def __init__(self, subscribe=True, clock=None):
        self.board = LatencyBoard()
        self.heard = threading.Event()
        # Reports are timed on wall and ROS time (LatencyBoard._fresh): on ROS time alone a
        # /clock looped back (a bag played again) kept a node that stopped reporting on the
        # board as long as the bag; on wall time alone a slow simulation dropped live ones.
        self.clock = clock or (lambda: (time.monotonic(), rospy.get_time()))
        self.sub = (rospy.Subscriber('/diagnostics', DiagnosticArray, self.on_diagnostics,
                                     queue_size=20) if subscribe else None)

    def on_diagnostics(self, msg):
        now = self.clock()
        for status in msg.status:
            if self.board.on_status(status.name, [(kv.key, kv.value) for kv in status.values],
                                    now):
                self.heard.set()

    def table(self):
        # now: a node that stopped reporting drops out instead of showing its last numbers
        return self.board.table(self.clock())

    def notes(self):
        """The board's short lines for an overlay or a marker (silent nodes left out)."""
        return self.board.notes(self.clock())

    def rows(self):
        """The board's rows of the nodes still reporting."""
        return self.board.rows(self.clock())


MAX_TIMEOUT_S = 86400.0


def master_problem(timeout):
    """(master URI, why it does not answer or None, whether waiting can help).
    rospy.init_node would retry forever."""
    try:
        uri = rosgraph.get_master_uri()
    except ValueError as e:           # a malformed __master:= remapping
        return '?', str(e), False
    old = socket.getdefaulttimeout()
    socket.setdefaulttimeout(timeout)  # a host that drops packets would block the call for minutes
    try:
        rosgraph.Master('/latency_monitor', master_uri=uri).getPid()
        return uri, None, False
    except xmlrpc.client.ProtocolError as e:      # an HTTP server that is not a master
        return uri, 'HTTP %s %s' % (e.errcode, e.errmsg), False
    except OSError as e:                            # nothing there yet, or silent: wait
        return uri, e.strerror or str(e) or type(e).__name__, True
    except Exception as e:      # it answered, and not as a master does: waiting cannot help
        return uri, str(e) or type(e).__name__, False
    finally:
        socket.setdefaulttimeout(old)


def main(argv=None):
    ap = argparse.ArgumentParser(prog='latency_monitor', description=__doc__.split('\n\n')[0])
    ap.add_argument('--once', action='store_true', help='print one table, then exit')
    ap.add_argument('--timeout', type=float, default=30.0,
                    help='seconds to wait for the master and a first report (default 30)')
    args = ap.parse_args(rospy.myargv(sys.argv)[1:] if argv is None else argv)
    # nan: Event.wait returns at once; beyond a day the socket timeout overflows
    if not (math.isfinite(args.timeout) and 0 < args.timeout <= MAX_TIMEOUT_S):
        ap.error('--timeout must be a number of seconds > 0 and <= %g, got %s'
                 % (MAX_TIMEOUT_S, args.timeout))
    deadline = time.monotonic() + args.timeout
    try:
        while True:     # started beside a roslaunch, the master may come up a moment later
            uri, why, may_come_up = master_problem(max(0.1, min(2.0, deadline - time.monotonic())))
            if not why or not may_come_up or time.monotonic() + 0.5 > deadline:
                break
            time.sleep(0.5)
    except KeyboardInterrupt:           # Ctrl-C while waiting: no traceback
        return 1
    if why:
        print('latency_monitor: no ROS master at %s (%s)' % (uri, why), file=sys.stderr)
        return 1
    rospy.init_node('latency_monitor', anonymous=True, disable_signals=True)
    monitor = LatencyMonitor()
    try:
        if not monitor.heard.wait(max(0.0, deadline - time.monotonic())):
            print('latency_monitor: no node reported an input age on /diagnostics in %g s'
                  % args.timeout, file=sys.stderr)
            return 1
        # Wall-time pacing: rospy.sleep raised on a /clock looped back (a bag played again),
        # which ended the table silently with status 0.
        time.sleep(1.5)      # the updaters publish about once a second: hear them all
        while not rospy.is_shutdown():
            print(monitor.table(), flush=True)
            if args.once:
                return 0
            print()
            time.sleep(1.0)
    except KeyboardInterrupt:
        pass
    return 0
