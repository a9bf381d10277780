"""The results files of `make bench` and `make soak`: written afresh per run (atomically),
this run's figures only, with `_run` (when, what), `_sources` (the data each figure came
from) and `_failed` (what gave no figure, and why)."""
import json
import math
import os
import time


def utc_now():
    return time.strftime('%Y-%m-%dT%H:%M:%SZ', time.gmtime())


def finite_figures(figures):
    """(figures that are finite numbers, {key: reason} for the others)."""
    good, bad = {}, {}
    for key, value in figures.items():
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            bad[key] = 'not measured (%r)' % (value,)
        else:
            good[key] = value
    return good, bad


def write_results(path, figures, sources, failed, run):
    """Replace `path` with this run's figures, `_run`, `_sources` and `_failed`."""
    results = dict(figures)
    results['_run'] = dict(run, finished=utc_now())
    results['_sources'] = dict(sources)
    results['_failed'] = dict(failed)
    tmp = path + '.tmp'
    with open(tmp, 'w') as f:
        json.dump(results, f, indent=1, sort_keys=True)
    os.replace(tmp, path)
