"""The fast per-hand path (hand_geometry, leap_features, PoseClassifier.proba) against the
same quantities computed the slow, obvious way (per finger, np.cross, np.linalg.norm, the
model's stored arrays), on real Leap frames of ../shared: people's static poses, their
dynamic takes and the LeapJS recordings. Fails without the data."""
import glob
import math
import os

import numpy as np
import pytest

from leap_teleop.hands.frame import Finger, TrackedHand
from leap_teleop.hands.gestures import datasets as gd
from leap_teleop.hands.gestures import geometry
from leap_teleop.hands.gestures.classifier import DEFAULT_MODELS, load_model
from leap_teleop.hands.gestures.features import leap_features
from leap_teleop.hands.gestures.geometry import hand_geometry
from leap_teleop.hands.sources import leapjs

RTOL = 1e-9
ATOL = 1e-12        # palm widths and cosines: far below anything a pose could show


def close(a, b):
    return np.allclose(a, b, rtol=RTOL, atol=ATOL)


def unit(v):
    return v / np.linalg.norm(v)


def reference(hand):
    """(features, extended flags, thumb_dir, pinch_gap) of a hand with finite joints."""
    n = unit(np.asarray(hand.palm_normal, dtype=float))
    d = np.asarray(hand.direction, dtype=float)
    d = unit(d - n * np.dot(d, n))
    t = np.cross(d, n) * (-1.0 if hand.side == 'left' else 1.0)
    joints = [[np.asarray(j, dtype=float) for j in (f.mcp, f.pip, f.dip, f.tip)]
              for f in hand.fingers]
    width = np.linalg.norm(joints[1][0] - joints[4][0])
    if not 25.0 <= width <= 120.0:
        width = 55.0
    local = [[np.array([np.dot(j, t), np.dot(j, n), np.dot(j, d)]) / width for j in finger]
             for finger in joints]
    reach, bones, lengths = [], [], []
    for finger in local:
        for k in (1, 2, 3):
            reach.append(finger[k] - finger[0])
            bone = finger[k] - finger[k - 1]
            lengths.append(np.linalg.norm(bone))
            bones.append(bone / max(lengths[-1], 1e-9))
    tips = [finger[3] for finger in local]
    gaps = [np.linalg.norm(tips[a] - tips[b])
            for a, b in ((0, 1), (0, 2), (0, 3), (0, 4), (1, 2), (2, 3), (3, 4))]
    cos = [np.dot(bones[3 * f + k + 1], bones[3 * f + k]) for f in range(5) for k in (0, 1)]
    features = np.concatenate([np.ravel(reach), np.ravel(bones), gaps, cos])
    extended = [local[0][3][0] - local[1][0][0] > 0.35]
    for f in (1, 2, 3, 4):
        chord = np.linalg.norm(local[f][3] - local[f][0]) / max(sum(lengths[3 * f:3 * f + 3]),
                                                                1e-9)
        extended.append(chord > 0.85 and bones[3 * f + 2][2] > math.cos(math.radians(85.0)))
    thumb_dir = unit(joints[0][3] - joints[0][1])
    pinch_gap = np.linalg.norm(joints[0][3] - joints[1][3]) / width
    return features, tuple(extended), thumb_dir, pinch_gap


def reference_proba(x):
    """Softmax of the shipped Leap model, read from its file, step by step."""
    with np.load(DEFAULT_MODELS['leap'], allow_pickle=False) as z:
        mean, scale, w0, b0, w1, b1 = (z[k] for k in ('mean', 'scale', 'w0', 'b0', 'w1', 'b1'))
    hidden = np.maximum((x - mean) / scale @ w0 + b0, 0.0)
    s = hidden @ w1 + b1
    e = np.exp(s - s.max())
    return e / e.sum()


def joints_finite(hand):
    try:
        return all(np.isfinite(np.asarray(j, dtype=float)).all() and np.shape(j) == (3,)
                   for f in hand.fingers for j in (f.mcp, f.pip, f.dip, f.tip))
    except TypeError:
        return False


@pytest.fixture(scope='module')
def real_hands(leapjs_data):
    """A few hundred real hands: every 100th static pose of the people's file, every 40th
    frame of 12 of their dynamic takes, every 30th hand of the LeapJS recordings."""
    if not os.path.isdir(gd.LEAP_PEOPLE):
        pytest.fail('the shared data is not at %s' % gd.SHARED_DATA)
    hands = []
    rows = gd.read_pose_lines(os.path.join(gd.LEAP_PEOPLE, 'gti_dev.jsonl.gz'))
    hands += [gd.first_hand(frame) for _, _, frame in rows[::100]]
    for _, _, path in gd.guinevere_takes()[::8]:
        hands += [gd.first_hand(f) for f in gd.read_take(path)[::40]]
    for path in sorted(glob.glob(os.path.join(leapjs_data, 'decoded', '*.json.gz'))):
        hands += [h for f in leapjs.load_frames(path)[1] for h in f.hands][::30]
    return [h for h in hands if h is not None and len(h.fingers) == 5 and joints_finite(h)]


def test_features_and_flags_match_the_obvious_computation(real_hands):
    assert len(real_hands) >= 400
    sides = set()
    for hand in real_hands:
        g = hand_geometry(hand)
        x = leap_features(hand, g)
        ref_x, ref_ext, ref_thumb, ref_gap = reference(hand)
        assert x is not None and x.shape == ref_x.shape
        assert close(x, ref_x), np.abs(x - ref_x).max()
        assert g.extended == ref_ext
        assert close(g.thumb_dir, ref_thumb) and close(g.pinch_gap, ref_gap)
        sides.add(hand.side)
    assert sides == {'left', 'right'}


def test_probabilities_match_the_obvious_computation(real_hands):
    model = load_model(None, 'leap')
    rows = []
    for hand in real_hands:
        x = reference(hand)[0]
        p = model.proba(x)
        assert close(p, reference_proba(x)) and abs(p.sum() - 1.0) < 1e-12
        rows.append(x)
    # rows at once (the training and evaluation tools' path) give the same
    assert close(model.proba(np.array(rows)), [model.proba(x) for x in rows])
    # and the decisions differ between hands: the test is not comparing constants
    assert len({int(model.proba(x).argmax()) for x in rows}) >= 4


def _with_joints(hand, convert):
    fingers = tuple(Finger(convert(f.tip), f.direction,
                           f.extended, *(convert(j) for j in (f.mcp, f.pip, f.dip)))
                    for f in hand.fingers)
    return TrackedHand(hand.side, hand.palm_position, hand.palm_velocity, hand.palm_normal,
                hand.direction, fingers=fingers)


@pytest.mark.parametrize('convert', [
    lambda j: [float(c) for c in j],                               # plain lists
    lambda j: np.asarray(j, dtype=np.float32).astype(float),        # float64 (the fast path)
    lambda j: np.asarray(j, dtype=np.float32),                      # another dtype
    lambda j: np.repeat(np.asarray(j, dtype=float), 2)[::2],        # not contiguous
    lambda j: np.asarray(j, dtype=float).reshape(1, 3),             # rows
    lambda j: np.asarray(j, dtype=np.float32).reshape(1, 3),
], ids=['lists', 'float64', 'float32', 'strided', 'rows', 'float32 rows'])
def test_joints_of_any_array_kind_give_the_same_features(real_hands, convert):
    for hand in real_hands[::25]:
        # joints rounded to float32 first, so that every kind holds the same numbers
        base = _with_joints(hand, lambda j: np.asarray(j, dtype=np.float32).astype(float))
        other = _with_joints(base, convert)
        assert close(leap_features(other), leap_features(base))
        assert hand_geometry(other).extended == hand_geometry(base).extended


def test_a_joint_that_is_missing_or_not_finite_leaves_no_joints(real_hands):
    hand = real_hands[0]
    for bad in (None, np.array([0.0, math.nan, 1.0]), np.array([math.inf, 0.0, 0.0]),
                np.zeros(2), np.float64(1.0)):
        fingers = list(hand.fingers)
        fingers[2] = Finger(fingers[2].tip, fingers[2].direction, True, fingers[2].mcp, bad,
                            fingers[2].dip)
        broken = TrackedHand(hand.side, hand.palm_position, hand.palm_velocity, hand.palm_normal,
                      hand.direction, fingers=tuple(fingers))
        g = hand_geometry(broken)
        assert g is not None and g.joints is None and g.local is None, bad
        assert leap_features(broken) is None
        assert g.extended[2] is True                    # the tracker's flag, without joints


def test_joints_beyond_any_trackers_range_are_no_joints():
    # finite, but 1e200 mm from anything: no tracker reports that (once read as a fist)
    side = 1e200
    fingers = tuple(Finger(np.array([x, 0.0, -side]), np.array([0.0, 0.0, -1.0]), None,
                           np.array([x, 0.0, 0.0]), np.array([x, 0.0, -side / 3]),
                           np.array([x, 0.0, -side / 2]))
                    for x in np.linspace(-side / 4, side / 4, 5))
    hand = TrackedHand('right', fingers=fingers)
    with np.errstate(over='ignore'):
        g = hand_geometry(hand)
    assert g is None or g.joints is None
    assert leap_features(hand, g) is None
    assert geometry.MAX_COORD_MM == 1e5
