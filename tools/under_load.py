"""Run a command beside CPU hogs: each hog is a process spinning on one core at full
speed for as long as the command runs, so the command shares the machine the way it does
beside another heavy job. Prints the load average before and after and exits with the
command's status.

usage: python -m tools.under_load [--hogs N] -- COMMAND [ARG...]
  e.g. python -m tools.under_load --hogs 2 -- make demo
"""
import argparse
import multiprocessing
import os
import subprocess
import sys


def spin():
    while True:
        pass


def start_hogs(n):
    hogs = [multiprocessing.Process(target=spin, daemon=True) for _ in range(n)]
    for hog in hogs:
        hog.start()
    return hogs


def stop_hogs(hogs):
    for hog in hogs:
        hog.terminate()
    for hog in hogs:
        hog.join(5)


def main(argv=None):
    ap = argparse.ArgumentParser(prog='python -m tools.under_load',
                                 description=__doc__.split('\n\n')[0])
    ap.add_argument('--hogs', type=int, default=2, help='busy processes beside it (default 2)')
    ap.add_argument('command', nargs=argparse.REMAINDER, help='-- COMMAND [ARG...]')
    args = ap.parse_args(sys.argv[1:] if argv is None else argv)
    command = args.command[1:] if args.command[:1] == ['--'] else args.command
    if not command:
        ap.error('no command to run (put it after --)')
    if not 0 <= args.hogs <= 64:
        ap.error('--hogs must be between 0 and 64, not %d' % args.hogs)
    print('[under_load] %d CPU hog(s) beside: %s (load average before: %.2f)'
          % (args.hogs, ' '.join(command), os.getloadavg()[0]), flush=True)
    hogs = start_hogs(args.hogs)
    try:
        rc = subprocess.call(command)
    except OSError as e:
        print('[under_load] cannot run %s: %s' % (command[0], e), file=sys.stderr)
        rc = 127
    finally:
        load = os.getloadavg()[0]
        stop_hogs(hogs)
    print('[under_load] %s exited %d (load average at its end: %.2f)'
          % (' '.join(command), rc, load), flush=True)
    return rc


if __name__ == '__main__':
    sys.exit(main())
