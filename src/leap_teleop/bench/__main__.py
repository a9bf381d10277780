"""Run every benchmark module, print a table, write bench_results.json.

usage: python -m leap_teleop.bench [--only AREA ...] [--out bench_results.json]
"""
import argparse
import importlib
import json
import math
import os
import pkgutil
import sys
import time
import traceback

import leap_teleop.bench as bench_pkg


def discover():
    return sorted(m.name for m in pkgutil.iter_modules(bench_pkg.__path__)
                  if m.name.startswith('bench_'))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument('--only', nargs='*', default=None,
                    help='areas to run (module names without bench_), default all')
    ap.add_argument('--out', default='bench_results.json')
    args = ap.parse_args(argv)
    modules = discover()
    if args.only:
        modules = [m for m in modules if m[len('bench_'):] in args.only]
    results = {}
    if os.path.exists(args.out):
        try:
            with open(args.out) as f:
                results = json.load(f)     # keep the other areas' figures on --only
        except (OSError, ValueError):
            results = {}
    failed = []
    for name in modules:
        print('[bench] %s ...' % name, flush=True)
        t0 = time.monotonic()
        try:
            figures = importlib.import_module('leap_teleop.bench.' + name).run()
        except Exception:
            traceback.print_exc()
            failed.append(name)
            continue
        for key, value in figures.items():
            if not isinstance(value, (int, float)) or not math.isfinite(value):
                raise SystemExit('benchmark %s returned a non-number for %s: %r' % (name, key, value))
        results.update(figures)
        print('[bench] %s done in %.1f s' % (name, time.monotonic() - t0), flush=True)
    width = max([len(k) for k in results] or [10])
    print('\n%-*s  %s' % (width, 'key', 'value'))
    for key in sorted(results):
        print('%-*s  %.6g' % (width, key, results[key]))
    with open(args.out, 'w') as f:
        json.dump(results, f, indent=1, sort_keys=True)
    print('\nwrote %s (%d keys)' % (args.out, len(results)))
    if failed:
        print('failed benchmarks: %s' % ', '.join(failed), file=sys.stderr)
        return 1
    return 0


if __name__ == '__main__':
    sys.exit(main())
