"""Stress test of the pose model's invariances on scripted hands.

usage: python -m tools.evaluation.invariance [--draws N] [--seed S]

The scripted hand (rendered_hand: each pose as people's median hand) is changed in ways that
must not change what the model reads: hand size (0.7x .. 1.35x), side (a left hand is
the mirrored right one), orientation (roll, pitch, yaw within +-40 deg), tracker noise
on every joint (1, 3, 5 mm), and a missing joint (the model then judges nothing: no
gesture rather than a wrong one). Reported: the share of draws whose winning class
equals the unchanged hand's, per pose and per change. Real people are judged in
tools.evaluation.people; this only checks that nothing but the pose moves the decision.
"""
import argparse
import dataclasses
import sys

import numpy as np

from leap_teleop.hands.gestures import hand_geometry, load_model
from leap_teleop.hands.gestures.pose import classify_pose
from leap_teleop.hands.rendered_hand import POSES, render_hand, rpy_to_basis

CHANGES = ('size', 'side', 'orientation', 'noise_1mm', 'noise_3mm', 'noise_5mm')
PALM = (20.0, 200.0, -10.0)


def _scaled(hand, s):
    palm = hand.palm_position
    fingers = tuple(dataclasses.replace(f, tip=palm + s * (f.tip - palm),
                                        mcp=palm + s * (f.mcp - palm),
                                        pip=palm + s * (f.pip - palm),
                                        dip=palm + s * (f.dip - palm)) for f in hand.fingers)
    return dataclasses.replace(hand, fingers=fingers)


def _noisy(hand, sigma, rng):
    def j(p):
        return p + rng.normal(0.0, sigma, 3)
    fingers = tuple(dataclasses.replace(f, tip=j(f.tip), mcp=j(f.mcp), pip=j(f.pip), dip=j(f.dip))
                    for f in hand.fingers)
    return dataclasses.replace(hand, fingers=fingers)


def _label(hand, model):
    return classify_pose(hand, hand_geometry(hand), model)['label']


def changed(pose, change, rng):
    """A hand of `pose` under one random draw of `change`."""
    if change == 'side':
        return render_hand('left', pose, PALM)
    if change == 'orientation':
        roll, pitch, yaw = rng.uniform(-1, 1, 3) * np.radians(40.0)
        n, d = rpy_to_basis(roll, pitch, yaw, 'right')
        return render_hand('right', pose, PALM, n, d)
    hand = render_hand('right', pose, PALM)
    if change == 'size':
        return _scaled(hand, rng.uniform(0.7, 1.35))
    return _noisy(hand, float(change.split('_')[1][:-2]), rng)


def run(draws=40, seed=0, model=None):
    model = load_model(model, 'leap')
    rng = np.random.default_rng(seed)
    out = {'per_pose': {}, 'per_change': {}, 'dropout_wrong': 0, 'dropout_draws': 0}
    totals = {c: [0, 0] for c in CHANGES}
    for pose in sorted(POSES):
        base = _label(render_hand('right', pose, PALM), model)
        row = {'label': base}
        for change in CHANGES:
            n = 1 if change == 'side' else draws
            same = sum(_label(changed(pose, change, rng), model) == base for _ in range(n))
            row[change] = same / n
            totals[change][0] += same
            totals[change][1] += n
        out['per_pose'][pose] = row
        for i in range(5):          # a missing joint: nothing is judged
            hand = render_hand('right', pose, PALM)
            fingers = list(hand.fingers)
            fingers[i] = dataclasses.replace(fingers[i], pip=None)
            broken = dataclasses.replace(hand, fingers=tuple(fingers))
            s = classify_pose(broken, hand_geometry(broken), model)
            out['dropout_draws'] += 1
            out['dropout_wrong'] += bool(s['label'])
    out['per_change'] = {c: a / n for c, (a, n) in totals.items()}
    return out


def print_table(r):
    print('pose model invariances (share of draws reading as the unchanged hand):')
    print('  %-10s %-8s %s' % ('pose', 'reads', '  '.join('%-11s' % c for c in CHANGES)))
    for pose, row in r['per_pose'].items():
        print('  %-10s %-8s %s' % (pose, row['label'],
                                   '  '.join('%-11.3f' % row[c] for c in CHANGES)))
    print('  all poses           %s' % '  '.join('%-11.3f' % r['per_change'][c] for c in CHANGES))
    print('  a missing joint judged anyway: %d of %d' % (r['dropout_wrong'], r['dropout_draws']))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument('--draws', type=int, default=40)
    ap.add_argument('--seed', type=int, default=0)
    args = ap.parse_args(argv)
    print_table(run(args.draws, args.seed))
    return 0


if __name__ == '__main__':
    sys.exit(main())
