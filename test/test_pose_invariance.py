"""The shipped pose model under changes that must not move its decision (size, side,
orientation, tracker noise, a missing joint), and the thumbs-up guard beside it: a
thumbs-down or a sideways thumb never arms an arm, a held thumbs-up does."""
import math
import os

import numpy as np
import pytest

from leap_teleop.hands.gestures import GestureRecognizer, hand_geometry, load_model
from leap_teleop.hands.gestures.pose import classify_pose, thumb_points
from leap_teleop.hands.rendered_hand import render_hand
from leap_teleop.ur10 import kinematics as kin
from leap_teleop.ur10.teleop import ARMED, DISARMED, ArmInput, ArmTeleop
from tools.evaluation import invariance as evaluate_invariance


@pytest.fixture(scope='module')
def figures():
    return evaluate_invariance.run(draws=25, seed=3)


@pytest.mark.parametrize('change', ['size', 'side', 'orientation', 'noise_1mm', 'noise_3mm'])
def test_the_decision_ignores_size_side_orientation_and_noise(figures, change):
    assert figures['per_change'][change] >= 0.95, figures['per_pose']
    for pose, row in figures['per_pose'].items():
        assert row[change] >= 0.8, (pose, row)


def test_a_missing_joint_judges_nothing(figures):
    assert figures['dropout_draws'] == 40 and figures['dropout_wrong'] == 0


@pytest.mark.parametrize('where', ['a fingertip', 'every joint', 'the palm'])
def test_a_hand_at_absurd_coordinates_judges_nothing(where):
    # 1e308 is finite, but no tracker reports it: once read as a fist
    hand = render_hand('right', 'fist', (0.0, 200.0, 0.0))
    assert classify_pose(hand, hand_geometry(hand), load_model())['fist']
    if where == 'the palm':
        hand.palm_position = np.array([1e308, 0.0, 0.0])
    for f in hand.fingers if where != 'the palm' else ():
        for joint in ('tip',) if where == 'a fingertip' else ('mcp', 'pip', 'dip', 'tip'):
            setattr(f, joint, np.array([1e308, 1e308, 1e308]))
    g = hand_geometry(hand)
    decision = classify_pose(hand, g, load_model())
    assert not any(decision[k] for k in ('fist', 'open', 'pinch', 'rock', 'thumb_up',
                                         'thumb_down'))


def _turned(pose, normal, direction, side='right'):
    return render_hand(side, pose, (0.0, 200.0, 0.0), np.array(normal, float),
                       np.array(direction, float))


@pytest.mark.parametrize('side', ['right', 'left'])
def test_thumb_direction_decides_up_down_or_nothing(side):
    s = 1.0 if side == 'right' else -1.0
    # palm facing inward, fingers ahead: the thumb side is up, down or sideways
    up = _turned('thumbs_up', (-s, 0, 0), (0, 0, -1), side)
    down = _turned('thumbs_up', (s, 0, 0), (0, 0, -1), side)
    flat = _turned('thumbs_up', (0, -1, 0), (0, 0, -1), side)     # palm down: thumb sideways
    model = load_model(None, 'leap')
    got = {}
    for name, hand in (('up', up), ('down', down), ('flat', flat)):
        g = hand_geometry(hand)
        d = classify_pose(hand, g, model)
        got[name] = (thumb_points(g, hand), d['thumb_up'], d['thumb_down'])
    assert got == {'up': ('up', True, False), 'down': ('down', False, True),
                   'flat': (None, False, False)}


def _arm_with(hands, dt=1 / 60.0):
    rec, arm = GestureRecognizer(), ArmTeleop()
    arm.on_joints(kin.HOME_Q.copy())
    states = []
    for i, hand in enumerate(hands):
        t = i * dt
        st = rec.update(hand, t)
        states.append(st)
        arm.on_hand(ArmInput(present=True, palm_mm=(0.0, 200.0, 0.0), fist=st.fist,
                              thumb_up=st.thumb_up, stamp=100.0 + t), 100.0 + t)
        arm.step(100.0 + t)
    return arm.status.state, states


def test_a_held_thumbs_down_or_sideways_thumb_never_arms():
    rng = np.random.default_rng(5)
    for normal in ((1, 0, 0), (0, -1, 0), (0.7, -0.7, 0)):
        hands = [evaluate_invariance._noisy(_turned('thumbs_up', normal, (0, 0, -1)), 2.0, rng)
                 for _ in range(90)]                                    # 1.5 s held
        state, states = _arm_with(hands)
        assert state == DISARMED and not any(s.thumb_up for s in states), normal


def test_a_held_thumbs_up_arms_but_not_before_the_hold():
    rng = np.random.default_rng(6)
    hands = [evaluate_invariance._noisy(_turned('thumbs_up', (-1, 0, 0), (0, 0, -1)), 2.0, rng)
             for _ in range(40)]
    state, states = _arm_with(hands)
    assert state == ARMED
    state, _ = _arm_with(hands[:15])            # 0.25 s: shown, not yet held arm_hold_s
    assert state == DISARMED


def test_a_model_file_of_the_wrong_family_or_malformed_is_refused(tmp_path):
    from leap_teleop.hands.gestures import ModelError, PoseClassifier
    bad = tmp_path / 'bad.npz'
    bad.write_bytes(b'not a zip')
    with pytest.raises(ModelError, match='cannot read'):
        PoseClassifier.load(str(bad))
    keypoints = load_model(None, 'keypoints')
    path = str(tmp_path / 'k.npz')
    keypoints.save(path)
    with pytest.raises(ModelError, match='keypoints model, not a leap'):
        PoseClassifier.load(path, 'leap')
    # arrays that do not fit together
    m = load_model(None, 'leap')
    with pytest.raises(ModelError, match='inconsistent'):
        PoseClassifier(m.classes, 'leap', m.mean, 1.0 / m.inv_scale, m.w0[:-1], m.b0, m.w1,
                       m.b1)
    with pytest.raises(ModelError, match='inconsistent'):
        PoseClassifier(m.classes, 'leap', m.mean * math.nan, 1.0 / m.inv_scale, m.w0, m.b0,
                       m.w1, m.b1)
    # finite, but the first product overflows to NaN: every frame read as the first class
    with pytest.raises(ModelError, match='weights beyond'):
        PoseClassifier(m.classes, 'leap', m.mean, 1.0 / m.inv_scale, m.w0, m.b0, m.w1 * 1e300,
                       m.b1)


def test_a_model_saved_in_npy_format_3_loads(tmp_path):
    # the size check reads format 3.0 headers too, and refuses none that is sound
    import io
    import zipfile

    from leap_teleop.hands.gestures import PoseClassifier
    from leap_teleop.hands.gestures.classifier import DEFAULT_MODELS
    path = tmp_path / 'v3.npz'
    with np.load(DEFAULT_MODELS['leap'], allow_pickle=False) as z, zipfile.ZipFile(path, 'w') as out:
        for k in z.files:
            b = io.BytesIO()
            np.lib.format.write_array(b, z[k], version=(3, 0))
            out.writestr(k + '.npy', b.getvalue())
    m = load_model(None, 'leap')
    np.testing.assert_array_equal(PoseClassifier.load(str(path), 'leap').w0, m.w0)


def test_a_model_that_says_nan_holds_no_gesture(monkeypatch):
    model = load_model(None, 'leap')
    hand = render_hand('right', 'fist', (0, 200, 0))
    g = hand_geometry(hand)
    assert classify_pose(hand, g, model)['fist']
    monkeypatch.setattr(model, 'proba', lambda x: np.full(len(model.classes), math.nan))
    out = classify_pose(hand, g, model)
    assert not any(out[k] for k in ('fist', 'open', 'pinch', 'rock', 'thumb_up', 'thumb_down'))
    assert out['label'] == '' and out['probability'] == 0.0


def test_the_shipped_models_are_arrays_with_a_card():
    from leap_teleop.hands.gestures.classifier import DEFAULT_MODELS
    for family in ('leap', 'keypoints'):
        m = load_model(None, family)
        with np.load(DEFAULT_MODELS[family], allow_pickle=False) as z:
            assert z['w0'].dtype == np.float64 and 'card' in z.files
        assert m.card['family'] == family and m.card['people']
        assert {'fist', 'open', 'pinch', 'rock', 'thumb', 'none'} <= set(m.classes)


def test_camera_thumb_guard_wants_the_thumb_up_in_the_picture():
    from leap_teleop.hands.gestures import datasets as gesture_data
    from leap_teleop.hands.gestures.features import rotate_keypoints
    from leap_teleop.hands.gestures.pose import camera_thumb_points
    thumbs = [xy for source, label, xy in gesture_data.photo_hands() if label == 'thumbs_up']
    assert len(thumbs) == 4
    for xy in thumbs:
        centre = xy.mean(axis=0)
        assert camera_thumb_points(xy) == 'up'
        # the picture upside down: a thumbs-down; turned on its side: neither
        upside_down = rotate_keypoints(xy - centre, math.pi) + centre
        assert camera_thumb_points(upside_down) == 'down'
        for turn in (math.radians(80), -math.radians(80)):
            assert camera_thumb_points(rotate_keypoints(xy - centre, turn) + centre) is None


def test_keypoint_features_ignore_the_cameras_roll_and_scale_but_not_the_mirror():
    from leap_teleop.hands.gestures import datasets as gesture_data
    from leap_teleop.hands.gestures.features import (
        KEYPOINT_FEATURES,
        keypoint_features,
        mirror_keypoints,
        rotate_keypoints,
    )
    _, _, xy = gesture_data.read_keypoints(os.path.join(gesture_data.KEYPOINTS, 'CharlesCai7.csv'))
    for q in xy[::60]:
        a = keypoint_features(q)
        assert a.shape == (KEYPOINT_FEATURES,)
        for turn in (0.3, 1.6, math.pi):
            np.testing.assert_allclose(keypoint_features(rotate_keypoints(q, turn) * 7.0), a,
                                       atol=1e-9)
        assert not np.allclose(keypoint_features(mirror_keypoints(q)), a)
    assert keypoint_features(np.zeros((21, 2))) is None


def test_keypoint_classes_that_show_another_pose_are_left_out_of_the_fit():
    from leap_teleop.hands.gestures import datasets as gesture_data
    from leap_teleop.hands.gestures import training_set
    ds = training_set.Dataset('keypoints')
    training_set.add_keypoints(ds, os.path.join(gesture_data.KEYPOINTS, 'ASHISH74888.csv'))
    labels = set(ds.label)
    # Close (four fingers up) and Ok (a side-view thumbs-up) are out; the rest are in
    assert 'fist' not in labels and 'ok' not in labels
    assert {'open', 'pointing', 'other'} <= labels
    assert ds.sources == ['ASHISH74888.csv (678 rows, 234 mislabelled left out)']
    # a user's file is never second-guessed
    ds = training_set.Dataset('keypoints')
    training_set.add_keypoints(ds, os.path.join(gesture_data.KEYPOINTS, 'ASHISH74888.csv'),
                        label='mine', person='user:me')
    assert set(ds.y) == {'mine'} and len(ds.y) == 2 * 2 * 912


def test_a_fitted_keypoint_row_is_fitted_with_all_its_copies():
    # The stride kept every second pair of rows over the whole data set, so every row's
    # first turned copy fell on a dropped pair: open, fist and none were never fitted
    # turned, and every row as recorded was.
    from leap_teleop.hands.gestures import datasets as gesture_data
    from leap_teleop.hands.gestures import training_set
    from leap_teleop.hands.gestures.train import strided
    ds = training_set.Dataset('keypoints')
    training_set.add_keypoints(ds, os.path.join(gesture_data.KEYPOINTS, 'kinivi.csv'))
    groups, augmented = ds.groups(), ~ds.clean()
    kept = strided(np.arange(len(groups)), groups)
    assert 0.45 < len(kept) / len(groups) < 0.55             # every second recorded row
    y = np.array(ds.y)
    for cls in set(ds.y):
        mine = kept[y[kept] == cls]
        copies = training_set.RARE_KEYPOINT_COPIES if cls in ('thumb', 'pinch') else 2
        # each recorded row as itself and mirrored, its copies too
        assert augmented[mine].sum() == (copies - 1) * (~augmented[mine]).sum() > 0, cls
    for g in set(groups[kept].tolist()):
        assert (groups[kept] == g).sum() == (groups == g).sum()   # a group is kept whole


def test_keypoint_feature_rows_of_sets_with_no_hand_are_none():
    # A batch in which no set has features (every landmark on one spot, or not finite)
    # raised a ValueError from an empty reshape, not the mask it documents.
    from leap_teleop.hands.gestures.features import KEYPOINT_FEATURES, keypoint_features_rows
    xy = np.full((3, 21, 2), 0.5)
    xy[2, 4] = np.nan
    feats, ok = keypoint_features_rows(xy)
    assert feats.shape == (3, KEYPOINT_FEATURES) and not feats.any() and not ok.any()
    feats, ok = keypoint_features_rows(np.zeros((0, 21, 2)))
    assert feats.shape == (0, KEYPOINT_FEATURES) and ok.shape == (0,)
