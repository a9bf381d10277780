"""latency_monitor: a live table of each consumer's input age (capture -> command, p50 /
p99 over its window) read from /diagnostics, as the arm nodes and pilots report it.

usage: rosrun leap_teleop latency_monitor [--once] [--timeout S]
  --once      print one table (1.5 s after the first report), then exit
  --timeout   give up (exit 1) when no node reports an input age within S seconds
"""
import argparse
import sys
import threading

import rospy
from diagnostic_msgs.msg import DiagnosticArray

from leap_teleop.control.input_age import age_row, age_table


class LatencyMonitor:
    def __init__(self):
        self.rows = {}
        self.heard = threading.Event()

    def on_diagnostics(self, msg):
        for status in msg.status:
            row = age_row(status.name, [(kv.key, kv.value) for kv in status.values])
            if row is not None:
                self.rows[status.name] = row
                self.heard.set()

    def table(self):
        return age_table(list(self.rows.values()))


def main(argv=None):
    ap = argparse.ArgumentParser(prog='latency_monitor', description=__doc__.split('\n\n')[0])
    ap.add_argument('--once', action='store_true', help='print one table, then exit')
    ap.add_argument('--timeout', type=float, default=30.0,
                    help='seconds to wait for a first report (default 30)')
    args = ap.parse_args(rospy.myargv(sys.argv)[1:] if argv is None else argv)
    rospy.init_node('latency_monitor', anonymous=True, disable_signals=True)
    monitor = LatencyMonitor()
    rospy.Subscriber('/diagnostics', DiagnosticArray, monitor.on_diagnostics, queue_size=20)
    try:
        if not monitor.heard.wait(args.timeout):
            print('latency_monitor: no node reported an input age on /diagnostics in %g s'
                  % args.timeout, file=sys.stderr)
            return 1
        rospy.sleep(1.5)     # the updaters publish about once a second: hear them all
        while not rospy.is_shutdown():
            print(monitor.table(), flush=True)
            if args.once:
                return 0
            print()
            rospy.sleep(1.0)
    except KeyboardInterrupt:
        pass
    return 0
