"""The arm's lag-jitter trade-off: palm filter and servo settings side by side in one run.

Each variant (overrides of the sim profile's arm parameters) runs the bench_arm_motion
measurements; the variants alternate within each repeat, and each repeat draws new
synthetic noise (seeds 0, 1, ...), so the spread shows what the noise alone moves. The
real-motion figures have no random input (the same for every repeat): run once each.

usage: python -m tools.lag_tradeoff [--repeats N] [--variant JSON ...]
"""
import argparse
import json

import numpy as np

from tools.bench import bench_arm_motion as bench
from tools.closed_loop import sim_params

# Variants measured for docs/robots.md (the first is the adopted default).
VARIANTS = (
    {},
    {'command_horizon': 0.032},
    {'command_horizon': 0.016},
    {'command_horizon': 0.032, 'servo_reach_fast': True},
)
SYNTHETIC = ('arm.tracking_lag_ms', 'arm.tracking_rms_m', 'arm.jitter_at_rest_mm',
             'arm.onset_latency_p99_ms', 'arm.step_overshoot_mm')
REAL = ('arm.tracking_lag_ms_real', 'arm.target_lag_ms_real', 'arm.tracking_rms_m_real',
        'arm.jitter_at_rest_mm_real')


def synthetic(overrides, seed):
    """The synthetic figures of one variant with noise seed `seed`."""
    r = {}
    bench.tracking(r, sim_params(**overrides), seed=100 + seed)
    bench.jitter(r, 5.0 / 6.0, 'arm.jitter_at_rest_mm', sim_params(**overrides),
                 seed=200 + seed)
    bench.onset(r, n=100, params=sim_params(**overrides), seed=300 + seed)   # as its table was run
    return r


def real(overrides):
    r = {}
    bench.tracking_real(r, sim_params(**overrides))
    bench.jitter_real(r, sim_params(**overrides))
    return r


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument('--repeats', type=int, default=3, help='synthetic repeats (noise seeds)')
    ap.add_argument('--variant', action='append', type=json.loads,
                    help='JSON overrides, e.g. \'{"command_horizon": 0.016}\' (repeatable); '
                         'default the documented set')
    args = ap.parse_args(argv)
    variants = args.variant or list(VARIANTS)
    runs = [[] for _ in variants]
    for seed in range(args.repeats):
        for i, overrides in enumerate(variants):        # alternate the variants
            runs[i].append(synthetic(overrides, seed))
            print('repeat %d, %s: %s' % (seed, json.dumps(overrides), {
                k: round(v, 4) for k, v in runs[i][-1].items() if k in SYNTHETIC}), flush=True)
    reals = []
    for overrides in variants:
        reals.append(real(overrides))
        print('real, %s: %s' % (json.dumps(overrides), {
            k: round(v, 4) for k, v in reals[-1].items() if k in REAL}), flush=True)
    print('\n| variant | ' + ' | '.join(k[4:] for k in SYNTHETIC + REAL) + ' |')
    print('|---' * (1 + len(SYNTHETIC) + len(REAL)) + '|')
    for overrides, rs, rl in zip(variants, runs, reals):
        cells = []
        for key in SYNTHETIC:
            v = np.array([r[key] for r in rs])
            cells.append('%.3g (%.3g..%.3g)' % (v.mean(), v.min(), v.max()))
        cells += ['%.3g' % rl[key] for key in REAL]
        print('| %s | %s |' % (json.dumps(overrides) if overrides else 'default',
                               ' | '.join(cells)))
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
