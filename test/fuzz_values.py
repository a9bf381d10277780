"""Cheap fuzz values for the property tests: hypothesis draws a seed (and a length), numpy
makes the rest. Drawing each float through hypothesis cost ~3/4 of a long sequence test's
time; these tests look for any input that breaks a limit, not for a minimal one."""
import sys

import numpy as np

# What no sensor sends but a broken one or a fuzzer might: non-finite, zero, signed zero,
# huge, tiny, the smallest normal and subnormal values, either sign.
SPECIAL = np.array([np.nan, -np.nan, np.inf, -np.inf, 0.0, -0.0, 1e9, -1e9, 1e-300, -1e-300,
                    1e308, -1e308, sys.float_info.max, -sys.float_info.max,
                    sys.float_info.min, -sys.float_info.min, 5e-324, -5e-324])


def wild(rng, n=None):
    """n wild floats (one when n is None): a third each plausible (+-600), special, or of any
    magnitude up to 1e300 (either sign)."""
    size = 1 if n is None else n
    kind = rng.integers(0, 3, size)
    plausible = rng.uniform(-600.0, 600.0, size)
    special = SPECIAL[rng.integers(0, len(SPECIAL), size)]
    any_size = rng.uniform(-1.0, 1.0, size) * 10.0 ** rng.uniform(-300.0, 300.0, size)
    v = np.where(kind == 0, plausible, np.where(kind == 1, special, any_size))
    return float(v[0]) if n is None else tuple(float(x) for x in v)


def within(rng, lo, hi):
    """A float in [lo, hi]: a quarter of the time exactly lo, hi, 0.0 or -0.0 (when inside),
    else uniform."""
    if rng.integers(0, 4) == 0:
        edges = [x for x in (lo, hi, 0.0, -0.0) if lo <= x <= hi]
        return float(edges[rng.integers(0, len(edges))])
    return float(rng.uniform(lo, hi))


def either(rng, usual, n=None):
    """Half the time `usual(rng)` (a value or a tuple of n), else wild values."""
    return usual(rng) if rng.integers(0, 2) else wild(rng, n)
