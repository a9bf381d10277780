"""Camera landmarks -> Frame conversion (sources.landmarks), without MediaPipe: on the
detections stored in shared/data/hands/hands.json and on synthetic projections of them."""
import json
import os
import subprocess
import sys

import numpy as np
import pytest

from leap_teleop.hands.gestures.datasets import HANDS_DATA
from leap_teleop.hands.sources.landmarks import (
    CameraModel,
    HandLandmarks,
    camera_to_leap,
    chirality,
    hand_from_landmarks,
    hand_side,
    join_touching_tips,
    person_side,
    project,
    reprojection_rms_px,
    solve_translation,
)

# needs a ROS master, a simulator, a subprocess or a build: not in make check
pytestmark = pytest.mark.integration


@pytest.fixture(scope='module')
def hands_json():
    path = os.path.join(HANDS_DATA, 'hands.json')
    assert os.path.isfile(path), 'shared hand photos absent: %s' % path
    with open(path) as f:
        return json.load(f)


def photo_hands(hands_json):
    for name, entry in hands_json['images'].items():
        cam = CameraModel.from_hfov(entry['width'], entry['height'])
        for d in entry['hands']:
            yield name, cam, HandLandmarks.from_dict(d)


def synthetic(lm, cam, t_mm, palm_mm=95.0):
    """HandLandmarks of lm's world shape (scaled to palm_mm) placed at t_mm, projected."""
    world = np.asarray(lm.world)
    shape = world * (palm_mm / np.linalg.norm(world[9] - world[0]))
    px = project(shape + t_mm, cam)
    image = np.column_stack((px[:, 0] / cam.width, px[:, 1] / cam.height,
                             (shape[:, 2] - shape[0, 2]) / cam.fx * cam.fx / cam.width))
    return HandLandmarks(image, world, lm.label, lm.score)


def test_a_hand_in_view_of_a_camera_anywhere_allowed_is_within_the_trackers_range(hands_json):
    # ~camera_position_mm took +-5000 mm, but the tracker drops every palm beyond 2000 mm:
    # a camera placed within the range could have its every hand refused.
    import itertools

    from leap_teleop.hands.sources.camera_params import CAMERA_PARAMS
    from leap_teleop.hands.tracker import HandTracker
    from leap_teleop.params import ParamError
    param = CAMERA_PARAMS['camera_position_mm']
    with pytest.raises(ParamError):
        param.check('camera_position_mm', [0.0, 200.0, -2500.0])
    name, cam, lm = next(photo_hands(hands_json))
    far = synthetic(lm, cam, np.array([0.0, 0.0, 950.0]))          # at the end of an arm
    for corner in itertools.product((param.ge, param.le), repeat=3):
        hand = hand_from_landmarks(far, cam, camera_position_mm=corner)
        state = HandTracker(hand.side).update(hand, 1.0, 1)
        assert state.present, (corner, hand.palm_position)


def test_side_follows_mirroring():
    assert person_side('Left', mirrored=False) == 'right'
    assert person_side('Right', mirrored=False) == 'left'
    assert person_side('Left', mirrored=True) == 'left'
    for mirrored in (False, True):
        assert np.isclose(np.linalg.det(camera_to_leap(mirrored)), 1.0 if not mirrored else -1.0)


def test_side_from_the_landmarks_chirality(hands_json):
    """The world landmarks' own chirality agrees with MediaPipe's label on 28 of the 30
    photographed hands; the other two are the same person's hand as fist__fp__fullcurl,
    labelled the other way at 0.69, and chirality gives all three the same side."""
    sides, agree = {}, 0
    for name, cam, lm in photo_hands(hands_json):
        assert abs(chirality(lm.world)) > 0.1, name
        side = hand_side(lm, mirrored=False)
        agree += side == person_side(lm.label, mirrored=False)
        sides[name] = side
        assert hand_from_landmarks(lm, cam).side == side
    assert agree == 28
    assert sides['fist__fp__fullcurl.jpg'] == sides['pointing__fp__nocurl.jpg'] \
        == sides['neg_half_curl__fp__halfcurl.jpg'] == 'left'


def test_every_photo_hand_converts_to_a_complete_leap_hand(hands_json):
    n = 0
    for name, cam, lm in photo_hands(hands_json):
        hand = hand_from_landmarks(lm, cam)
        assert hand is not None, name
        n += 1
        assert len(hand.fingers) == 5
        assert np.isclose(np.linalg.norm(hand.palm_normal), 1.0)
        assert np.isclose(np.linalg.norm(hand.direction), 1.0)
        assert abs(np.dot(hand.palm_normal, hand.direction)) < 1e-9
        # The SDK's 0..1 (the conversion clips them); by pose in test_grab_and_pinch_strengths.
        assert 0.0 <= hand.grab_strength <= 1.0 and 0.0 <= hand.pinch_strength <= 1.0
        for f in hand.fingers:
            for joint in (f.mcp, f.pip, f.dip, f.tip):
                assert np.all(np.isfinite(joint))
            assert np.isclose(np.linalg.norm(f.direction), 1.0)
        # The palm is where the camera sees it: in front of the virtual Leap, within reach.
        assert 0 < hand.palm_position[1] < 500 and abs(hand.palm_position[0]) < 400, name
        # World shape and image agree once placed: a check of the axes and the solver.
        assert reprojection_rms_px(lm, cam) < 0.12 * max(cam.width, cam.height), name
    assert n == 30


def test_thumb_points_up_in_thumbs_up_and_down_in_thumbs_down(hands_json):
    """Leap axes: +y is up; the thumb direction says which way the thumb points."""
    seen = set()
    for name, cam, lm in photo_hands(hands_json):
        thumb = hand_from_landmarks(lm, cam).fingers[0]
        if name.startswith('thumbs_up'):
            assert thumb.direction[1] > 0.6, name
            seen.add('up')
        elif name.startswith('thumbs_down'):
            assert thumb.direction[1] < -0.6, name
            seen.add('down')
    assert seen == {'up', 'down'}


def test_extended_flags_follow_the_labels(hands_json):
    """The SDK-style per-finger flags (thumb, index, middle, ring, pinky)."""
    expected = {'open_palm': '11111', 'fist': '00000', 'thumbs_up': '10000',
                'thumbs_down': '10000', 'pointing': '01000', 'neg_pinky': '00001',
                'neg_half_curl': '00000'}
    checked = 0
    for name, cam, lm in photo_hands(hands_json):
        want = expected.get(name.split('__')[0])
        if want is None:
            continue
        got = ''.join('1' if f.extended else '0' for f in hand_from_landmarks(lm, cam).fingers)
        assert got == want, name
        checked += 1
    assert checked == 23
    # Flat hands and OK signs: the four / three fingers that are out are extended.
    checked = 0
    for name, cam, lm in photo_hands(hands_json):
        flags = [f.extended for f in hand_from_landmarks(lm, cam).fingers]
        if name.startswith('flat_hand'):
            assert flags[1:] == [True] * 4, name
            checked += 1
        if name.startswith('ok'):
            assert flags[2:] == [True] * 3 and not flags[1], name
            checked += 1
    assert checked == 6                 # 2 flat hands, 4 OK signs


def test_grab_and_pinch_strengths(hands_json):
    closed = opened = 0
    for name, cam, lm in photo_hands(hands_json):
        hand = hand_from_landmarks(lm, cam)
        kind = name.split('__')[0]
        if kind in ('fist', 'thumbs_up', 'thumbs_down'):
            assert hand.grab_strength > 0.7, name
            closed += 1
        if kind in ('open_palm', 'flat_hand'):
            assert hand.grab_strength < 0.2, name
            assert hand.pinch_strength < 0.2, name
            opened += 1
    assert (closed, opened) == (10, 7)          # every such photographed hand was checked


def placed(lm, cam, palm_mm=95.0):
    """lm's world shape scaled to palm_mm and placed where the camera sees it, and the
    landmarks' pixels."""
    world = np.asarray(lm.world)
    shape = world * (palm_mm / np.linalg.norm(world[9] - world[0]))
    pixels = lm.image[:, :2] * (cam.width, cam.height)
    return shape + solve_translation(shape, pixels, cam), pixels


def tip_gap_mm(hand):
    return float(np.linalg.norm(hand.fingers[0].tip - hand.fingers[1].tip))


def test_touching_fingertips_meet_in_depth(hands_json):
    """Thumb and index tips touching in the image but parted in depth by the world
    landmarks (ok__htj__21: 64 mm, the "O": 49 mm) meet in the Frame; every landmark keeps
    its pixel and the palm (wrist, knuckles) does not move; hands whose thumb tip is clear
    of every fingertip in the image are left as they were."""
    gaps = {}
    for name, cam, lm in photo_hands(hands_json):
        p, pixels = placed(lm, cam)
        q = join_touching_tips(p, pixels, cam, 95.0)
        assert np.allclose(project(q, cam), project(p, cam), atol=1e-9), name
        assert np.array_equal(q[[0, 5, 9, 13, 17]], p[[0, 5, 9, 13, 17]]), name
        hand = hand_from_landmarks(lm, cam)
        if name.startswith(('ok', 'pinch_o')):
            gaps[name] = tip_gap_mm(hand)
            assert hand.pinch_strength > 0.8, (name, hand.pinch_strength)
        if name.split('__')[0] in ('open_palm', 'flat_hand', 'thumbs_up', 'thumbs_down'):
            assert np.array_equal(q, p), name
    assert gaps['ok__htj__21.jpg'] < 25.0 and gaps['pinch_o__sld__IMG_1138.JPG'] < 30.0, gaps
    assert max(gaps.values()) < 30.0, gaps


def test_a_thumb_misplaced_in_depth_is_brought_back_to_the_finger(hands_json):
    """A photographed OK sign (tips touching in both world and image) with its world thumb
    moved 30..60 mm along the camera ray, nearer or farther (the image cannot tell): the
    Frame's tips touch again, within a few mm of the unmoved hand's."""
    cam = CameraModel.from_hfov(640, 480, 60.0)
    lm = next(h for name, _, h in photo_hands(hands_json) if name == 'ok__sld__IMG_1137.JPG')
    t = np.array([20.0, -10.0, 450.0])
    clean = synthetic(lm, cam, t)
    want = tip_gap_mm(hand_from_landmarks(clean, cam))
    world = np.asarray(lm.world)
    scale = 95.0 / np.linalg.norm(world[9] - world[0])
    thumb = (4, 3)
    for dz in (-60.0, -30.0, 30.0, 60.0):
        moved = world.copy()
        for i in thumb:                  # the thumb's tip and IP joint, along their rays
            cam_pt = world[i] * scale + t
            moved[i] = (cam_pt * (cam_pt[2] + dz * (1.0 if i == 4 else 0.5)) / cam_pt[2] - t) \
                / scale
        hand = hand_from_landmarks(HandLandmarks(clean.image, moved, lm.label, lm.score), cam)
        assert abs(tip_gap_mm(hand) - want) < 6.0, (dz, tip_gap_mm(hand), want)
        assert hand.pinch_strength > 0.8, dz


def test_depth_from_hand_size_on_synthetic_projections(hands_json):
    """Known hands placed at known points, projected by a known camera: the palm comes
    back where it was (exactly without noise; within a few % of the depth with 1 px of
    landmark noise at 640x480), and a palm length 10 % off moves the depth by 10 %."""
    cam = CameraModel.from_hfov(640, 480, 60.0)
    rng = np.random.default_rng(1)
    rel_err = []
    for name, _, lm in photo_hands(hands_json):
        for t in ([0.0, 0.0, 400.0], [-120.0, 60.0, 600.0], [80.0, -40.0, 900.0]):
            t = np.array(t)
            clean = synthetic(lm, cam, t)
            exact = hand_from_landmarks(clean, cam, mirrored=False)
            ref = hand_from_landmarks(synthetic(lm, cam, np.array([0.0, 0.0, 500.0])), cam)
            # Moving the hand by t - (0, 0, 500) in camera axes moves it by R (t - ...) in Leap.
            want = ref.palm_position + camera_to_leap(False) @ (t - [0.0, 0.0, 500.0])
            assert np.allclose(exact.palm_position, want, atol=1e-6), name
            noisy = HandLandmarks(clean.image + np.column_stack(
                (rng.normal(0, 1.0 / cam.width, 21), rng.normal(0, 1.0 / cam.height, 21),
                 np.zeros(21))), clean.world, clean.label, clean.score)
            got = hand_from_landmarks(noisy, cam)
            rel_err.append(abs(got.palm_position[2] - want[2]) / t[2])
            small = hand_from_landmarks(clean, cam, palm_length_mm=95.0 * 0.9)
            # z_leap = z_cam - 500: the camera distance scales with the assumed size.
            assert np.isclose(small.palm_position[2] + 500.0,
                              0.9 * (exact.palm_position[2] + 500.0), rtol=1e-6), name
    assert np.percentile(rel_err, 95) < 0.05, np.percentile(rel_err, 95)


def test_mirrored_image_gives_the_same_hand(hands_json):
    """The same hand seen in a mirrored image (flipped landmarks, detector's label kept
    as the person's) converts to the same side, position and orientation."""
    cam = CameraModel.from_hfov(640, 480)
    for name, _, lm in photo_hands(hands_json):
        plain = synthetic(lm, cam, np.array([30.0, -20.0, 500.0]))
        flip = np.diag([-1.0, 1.0, 1.0])
        mirrored = HandLandmarks(np.column_stack((1.0 - plain.image[:, 0], plain.image[:, 1:])),
                                 plain.world @ flip,
                                 'Right' if plain.label == 'Left' else 'Left', plain.score)
        a = hand_from_landmarks(plain, cam, mirrored=False)
        b = hand_from_landmarks(mirrored, cam, mirrored=True)
        assert a.side == b.side, name
        assert np.allclose(a.palm_position, b.palm_position, atol=1e-6), name
        assert np.allclose(a.palm_normal, b.palm_normal, atol=1e-9), name
        assert np.allclose(a.direction, b.direction, atol=1e-9), name


def test_bad_landmarks_give_no_hand(hands_json):
    cam = CameraModel.from_hfov(640, 480)
    _, _, lm = next(photo_hands(hands_json))
    nan = HandLandmarks(np.full((21, 3), np.nan), lm.world, lm.label, lm.score)
    assert hand_from_landmarks(nan, cam) is None
    flat = HandLandmarks(lm.image, np.zeros((21, 3)), lm.label, lm.score)
    assert hand_from_landmarks(flat, cam) is None
    with pytest.raises(ValueError):
        CameraModel.from_hfov(640, 480, 0.0)
    with pytest.raises(ValueError):
        CameraModel.from_matrix(640, 480, [0, 0, 320, 0, 0, 240, 0, 0, 1])
    # a CameraInfo of size 0 (its K fine) gave a division by zero once frames came
    for width, height in ((0, 480), (640, 0), (100000, 480)):
        with pytest.raises(ValueError, match='image size needs 1..16384 pixels a side'):
            CameraModel.from_matrix(width, height, [500.0, 0, 320.0, 0, 500.0, 240.0, 0, 0, 1])


def test_camera_matrix_and_letterbox():
    k = [500.0, 0, 320.0, 0, 510.0, 240.0, 0, 0, 1]
    cam = CameraModel.from_matrix(640, 480, k)
    assert (cam.fx, cam.fy, cam.cx, cam.cy) == (500.0, 510.0, 320.0, 240.0)
    half = cam.scaled_to(320, 240)
    assert (half.fx, half.cx) == (250.0, 160.0)
    box = CameraModel.from_hfov(1280, 720).letterboxed(0.5, 0, 60, 640, 480)
    assert np.isclose(box.cx, 320.0) and np.isclose(box.cy, 240.0)


def test_camera_modules_load_without_mediapipe_or_opencv():
    """Nodes that do not use the camera must not pay for MediaPipe or OpenCV at start-up."""
    code = ('import sys; import leap_teleop.hands.sources.camera, leap_teleop.hands.sources.camera_params, '
            'leap_teleop.hands.camera_view, leap_teleop.ros.nodes.sender; '
            'bad = [m for m in ("mediapipe", "cv2") if m in sys.modules]; '
            'sys.exit("imported: %s" % bad if bad else 0)')
    proc = subprocess.run([sys.executable, '-c', code], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stdout + proc.stderr


def test_missing_mediapipe_names_what_to_install(tmp_path):
    code = ('import sys; sys.modules["mediapipe"] = None\n'
            'from leap_teleop.hands.sources import make_source, SourceError\n'
            'try:\n'
            '    make_source("video", path=%r)\n'
            'except SourceError as e:\n'
            '    print(e); sys.exit(0)\n'
            'sys.exit("no SourceError")\n'
            % os.path.join(HANDS_DATA, 'fist__htj__22.jpg'))
    proc = subprocess.run([sys.executable, '-c', code], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert 'requirements-camera.txt' in proc.stdout and 'MediaPipe' in proc.stdout
