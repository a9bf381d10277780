"""Run every benchmark module, print a table, write bench_results.json afresh: this run's
figures only, with the data each came from (`_sources`) and the modules that failed
(`_failed`). Each module runs in a fresh interpreter of its own: a figure must not depend
on which modules ran before it (their heap, threads and imports slowed the CPU-bound ones
that followed).

usage: python -m tools.bench [--only AREA ...] [--out bench_results.json]
"""
import argparse
import math
import pkgutil
import sys
import time
import traceback

import tools.bench as bench_pkg
from tools.bench.fresh_process import fresh_process_module
from tools.bench.results import utc_now, write_results


def discover():
    return sorted(m.name for m in pkgutil.iter_modules(bench_pkg.__path__)
                  if m.name.startswith('bench_'))


def collect(modules, load=fresh_process_module):
    """Run each module's run(); returns (figures, sources, failed). A module that raises or
    returns a non-finite figure is recorded as failed and contributes no figure; a figure
    without a stated source gets its module's first docstring line."""
    figures, sources, failed = {}, {}, {}
    for name in modules:
        print('[bench] %s ...' % name, flush=True)
        t0 = time.monotonic()
        try:
            module = load(name)
            got = dict(module.run())
        except Exception as e:
            traceback.print_exc()
            failed[name] = '%s: %s' % (type(e).__name__, e)
            continue
        stated = got.pop('_sources', {})
        bad = {k: v for k, v in got.items()
               if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v)}
        if bad:
            failed[name] = 'non-finite or non-number figures: %r' % (bad,)
            continue
        doc = (module.__doc__ or name).strip().splitlines()[0]
        for key, value in got.items():
            figures[key] = value
            sources[key] = '%s: %s' % (name, stated.get(key, doc))
        print('[bench] %s done in %.1f s' % (name, time.monotonic() - t0), flush=True)
    return figures, sources, failed


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument('--only', nargs='+', default=None, metavar='AREA',
                    help='areas to run (module names, with or without bench_), default all')
    ap.add_argument('--out', default='bench_results.json')
    args = ap.parse_args(argv)
    modules = discover()
    if args.only:
        wanted = {a if a.startswith('bench_') else 'bench_' + a for a in args.only}
        unknown = sorted(wanted.difference(modules))
        if unknown:     # before anything runs or the results file is replaced
            ap.error('--only: no benchmark %s (areas: %s)' % (
                ', '.join(u[len('bench_'):] for u in unknown),
                ', '.join(m[len('bench_'):] for m in modules)))
        modules = [m for m in modules if m in wanted]
    started = utc_now()
    figures, sources, failed = collect(modules)
    width = max([len(k) for k in figures] or [10])
    print('\n%-*s  %s' % (width, 'key', 'value'))
    for key in sorted(figures):
        print('%-*s  %.6g' % (width, key, figures[key]))
    # A fresh file per run: only this run's figures, what each came from, what failed.
    write_results(args.out, figures, sources, failed, {'started': started, 'modules': modules})
    print('\nwrote %s (%d figures from this run)' % (args.out, len(figures)))
    if failed:
        print('failed benchmarks: %s' % '; '.join('%s (%s)' % kv for kv in failed.items()),
              file=sys.stderr)
        return 1
    return 0


if __name__ == '__main__':
    sys.exit(main())
