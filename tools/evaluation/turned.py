"""How reliable the gesture recognizer is while the hand is turned (the orientation
modes ask the user to turn the hand while gesturing).

Real data: every labelled frame of the LeapJS recordings (hands.gestures.datasets.LEAPJS_LABELS),
binned by how far the palm is turned from flat and pointing away (the angle of the
rotation hand_rotation() rebuilds from the frame's roll, yaw and pitch); per bin, the
fraction of labelled gesture values the recognizer gets right, with a pose model fitted
on every person but the LeapJS takes' (the shipped one is fitted on them too). Synthetic:
each pose of the scripted hand model at turns up to 70 deg, both hands; fraction of frames
recognised (shipped model).

usage: python -m tools.evaluation.turned [--data DIR]
"""
import argparse
import math
import os
import sys

import numpy as np

from leap_teleop.hands.gestures import GestureRecognizer
from leap_teleop.hands.gestures import train as tg
from leap_teleop.hands.gestures.datasets import DEFAULT_LEAPJS_DATA, LEAPJS_LABELS, find_take
from leap_teleop.hands.gestures.datasets import expected as label_value
from leap_teleop.hands.gestures.training_set import LEAPJS_PERSON
from leap_teleop.hands.rendered_hand import render_hand, rpy_to_basis
from leap_teleop.hands.sources import leapjs
from leap_teleop.hands.tracker import hand_angles
from leap_teleop.ur10 import kinematics as kin
from leap_teleop.ur10.orientation import hand_rotation
from tools.evaluation.evaluate import GESTURES
from tools.evaluation.take_stream import recognize_take

BINS_DEG = (0, 20, 40, 60, 90, 180)


def model_without_the_takes(data_dir):
    """The Leap pose model fitted as the shipped one, without the LeapJS takes' person."""
    x, y, persons, labels = tg.training_dataset('leap', os.path.dirname(os.path.abspath(data_dir)),
                                                []).arrays()
    if LEAPJS_PERSON not in set(persons.tolist()):
        raise FileNotFoundError('no LeapJS take in the training data beside %s' % data_dir)
    model = tg.models_without(x, y, persons, labels, [LEAPJS_PERSON], log=lambda *a: None)[LEAPJS_PERSON]
    model.family = 'leap'
    return model


def real(data_dir, model=None):
    """{bin label: (right, total)} over every labelled gesture value; `model`: the Leap pose
    model (default the shipped one)."""
    out = {}
    for take, labels in LEAPJS_LABELS.items():
        path = find_take(data_dir, take)
        if path is None:
            raise FileNotFoundError('recording %s not found in %s' % (take, data_dir))
        _, dicts = leapjs.load(path)
        for k, _, judged in recognize_take(dicts, lambda: GestureRecognizer(model=model)):
            for hand, state in judged:
                want = {}
                for side, frames, expected in labels:
                    if side == hand.side and k in frames:
                        want.update(expected)
                if not want:
                    continue
                turn = math.degrees(np.linalg.norm(kin.rotation_vector(hand_rotation(
                    *hand_angles(hand.palm_normal, hand.direction)))))
                b = next(i for i in range(len(BINS_DEG) - 1) if turn < BINS_DEG[i + 1])
                key = '%d-%d deg' % (BINS_DEG[b], BINS_DEG[b + 1])
                right, total = out.get(key, (0, 0))
                for g, value in want.items():
                    value = label_value(value, hand)    # a thumbs-up label: by thumb direction
                    if g in GESTURES and value is not None:
                        right += bool(getattr(state, g)) == value
                        total += 1
                out[key] = (right, total)
    return out


def _turned_thumbs_up(rpy, side):
    """Palm normal and direction of the hand model's thumbs-up turned by rpy (deg, as
    rpy_to_basis turns the palm-down pose), or (None, None) when the turn leaves the
    thumb more than 45 deg from up."""
    n0, d0 = rpy_to_basis(0.0, 0.0, 0.0, side)
    n1, d1 = rpy_to_basis(*np.radians(rpy), side)
    r = np.column_stack([n1, d1, np.cross(n1, d1)]) @ np.column_stack([n0, d0, np.cross(n0, d0)]).T
    up = render_hand(side, 'thumbs_up', (0.0, 0.0, 0.0))
    normal, direction = r @ up.palm_normal, r @ up.direction
    thumb = r @ (up.fingers[0].tip - up.fingers[0].pip)
    if thumb[1] / np.linalg.norm(thumb) < math.cos(math.radians(45.0)):
        return None, None
    return normal, direction


def synthetic(turns=((0, 0, 0), (0, 0, 40), (0, 0, -70), (30, 0, 0), (-30, 0, 0),
                     (0, 25, 0), (0, -25, 0), (20, 20, 50)), frames=120):
    """{pose: fraction of frames recognised as that pose} over turns and both hands."""
    out = {}
    for pose in ('open', 'pinch', 'fist', 'rock', 'thumb_up'):
        hits = total = 0
        for side in ('right', 'left'):
            for rpy in turns:
                rec = GestureRecognizer()
                normal, direction = rpy_to_basis(*np.radians(rpy), side)
                render_pose = 'thumbs_up' if pose == 'thumb_up' else pose
                if pose == 'thumb_up':
                    # the thumbs-up's own pose (thumb up) turned: a thumbs-up is a thumb
                    # pointing up, so only turns that keep it within 45 deg of up count
                    normal, direction = _turned_thumbs_up(rpy, side)
                    if normal is None:
                        continue
                for k in range(frames):
                    hand = render_hand(side, render_pose, (0.0, 250.0, 0.0), normal, direction,
                                       pinch_value=0.6)
                    state = rec.update(hand, k / 120.0)
                    if k >= 30:
                        hits += bool(getattr(state, pose))
                        total += 1
        out[pose] = hits / total
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument('--data', default=DEFAULT_LEAPJS_DATA)
    args = ap.parse_args(argv)
    print('real recordings, labelled gesture values right / total by palm turn (a model '
          'fitted without them):')
    results = real(args.data, model_without_the_takes(args.data))
    for lo, hi in zip(BINS_DEG, BINS_DEG[1:]):
        key = '%d-%d deg' % (lo, hi)
        right, total = results.get(key, (0, 0))
        # An empty bin has no fraction: a 0 there would read as every value wrong.
        share = '%.4f' % (right / total) if total else '-'
        print('  %-12s %6d / %-6d %s' % (key, right, total, share))
    print('synthetic hands turned up to 70 deg, both sides, fraction recognised:')
    for pose, frac in synthetic().items():
        print('  %-10s %.3f' % (pose, frac))
    return 0


if __name__ == '__main__':
    sys.exit(main())
