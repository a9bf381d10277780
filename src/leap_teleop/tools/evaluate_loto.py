"""Leave-one-take-out figures for the pose thresholds read off the shared takes.

Each threshold below got its value from looking at the recordings. To show what that
fitting is worth on a take it did not see: for every take, each threshold is chosen
again from a grid (its shipped value times FACTORS) by the fewest labelled-frame errors
on the other takes (one threshold at a time, the others as shipped; ties go to the
shipped value), and the recognizer with those choices is scored on the held-out take.
The held-out counts are pooled over the takes. Only the takes with labels
(evaluate.LABELS) count: a take without labels neither fits nor tests anything.
"""
import contextlib

from ..gestures import pose
from . import evaluate

# Thresholds read off the recordings (pose module constants: (to turn on, to stay on)
# pairs or single values).
FITTED = ('CURLED_BEND', 'EXTENDED_BEND', 'THUMB_UP_CURLED_BEND', 'THUMB_OUT', 'PINCH_GAP',
          'FIST_THUMB_NEAR', 'OPEN_MEAN_BEND', 'PINCH_REST_BEND', 'THUMB_UP_OUT', 'THUMB_OVER',
          'HOOK_OTHERS_KNUCKLE', 'O_TIP_SPREAD', 'THUMB_UP_MIN_THUMBWARD',
          'THUMB_BEYOND_HAND', 'THUMB_VERTICAL')
FACTORS = (0.7, 0.85, 1.0, 1.15, 1.3)


@contextlib.contextmanager
def scaled(name, factor):
    old = getattr(pose, name)
    setattr(pose, name, tuple(v * factor for v in old) if isinstance(old, tuple)
            else old * factor)
    try:
        yield
    finally:
        setattr(pose, name, old)


def _errors(counts):
    return sum(c[1] + c[2] for c in counts.values())


def run(data_dir=evaluate.DEFAULT_DATA):
    takes = [t for t in evaluate.LABELS if evaluate.find_file(data_dir, t)]
    # counts[name][factor][take] = {gesture: [tp, fp, fn, n]} (recognizer)
    counts = {}
    for name in FITTED:
        counts[name] = {}
        for f in FACTORS:
            with scaled(name, f):
                counts[name][f] = {t: evaluate.score_take(t, evaluate.run_take(
                    evaluate.find_file(data_dir, t))[0])['recognizer'] for t in takes}
    pooled = {g: [0, 0, 0, 0] for g in evaluate.GESTURES}
    chosen = {}
    for held in takes:
        choice = {}
        for name in FITTED:
            best = min(FACTORS, key=lambda f: (sum(_errors(counts[name][f][t]) for t in takes
                                                   if t != held), abs(f - 1.0)))
            choice[name] = best
        chosen[held] = choice
        with contextlib.ExitStack() as stack:
            for name, f in choice.items():
                stack.enter_context(scaled(name, f))
            rows = evaluate.run_take(evaluate.find_file(data_dir, held))[0]
            res = evaluate.score_take(held, rows)
        for g, c in res['recognizer'].items():
            for i in range(4):
                pooled[g][i] += c[i]
    return {'takes': takes, 'factors': list(FACTORS), 'fitted': list(FITTED),
            'held_out': {g: evaluate._score(*c) for g, c in pooled.items()},
            'chosen_factors': chosen}


def print_table(res):
    print('leave-one-take-out (%d labelled takes; thresholds %s refitted from x%s):'
          % (len(res['takes']), ', '.join(res['fitted']), '/'.join(str(f) for f in res['factors'])))
    for g, r in res['held_out'].items():
        print('  %-10s held-out P / R %5.3f / %5.3f (%d)'
              % (g, r['precision'], r['recall'], r['n']))
    moved = {t: {k: v for k, v in c.items() if v != 1.0} for t, c in res['chosen_factors'].items()}
    print('  refits that moved a threshold: %s' % ({t: c for t, c in moved.items() if c} or 'none'))
