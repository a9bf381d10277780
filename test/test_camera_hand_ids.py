"""Camera hands keep their ids and sides from image to image (camera.HandTracks through
CameraSource.hands_of), on synthetic landmark frames: no MediaPipe, no shared data."""
import numpy as np
import pytest

from leap_teleop.hands.sources.camera import SIDE_SWITCH_FRAMES, CameraSource, HandTracks
from leap_teleop.hands.sources.landmarks import (
    DEFAULT_CAMERA_POSITION_MM,
    CameraModel,
    HandLandmarks,
    chirality,
    project,
)
from leap_teleop.hands.tracker import HandTracker

CAM = CameraModel.from_hfov(640, 480, 60.0)
# A flat open hand, fingers up, in the camera's axes (x right, y down), metres: its
# chirality is 0, so the detector's label decides its side, as on a hand seen edge-on.
FLAT_HAND = np.array([
    (0.0, 0.04, 0.0),
    (-0.025, 0.02, 0.0), (-0.04, 0.0, 0.0), (-0.05, -0.02, 0.0), (-0.06, -0.035, 0.0),
    (-0.025, -0.045, 0.0), (-0.027, -0.07, 0.0), (-0.028, -0.09, 0.0), (-0.029, -0.105, 0.0),
    (-0.008, -0.05, 0.0), (-0.008, -0.078, 0.0), (-0.008, -0.1, 0.0), (-0.008, -0.117, 0.0),
    (0.01, -0.047, 0.0), (0.011, -0.072, 0.0), (0.012, -0.091, 0.0), (0.013, -0.106, 0.0),
    (0.026, -0.04, 0.0), (0.029, -0.059, 0.0), (0.031, -0.073, 0.0), (0.033, -0.085, 0.0)])


def landmarks(side, x_mm, score=0.95, misread=False):
    """HandLandmarks of a person's `side` hand, its centre x_mm right of the camera's axis
    in the image (500 mm away), as a plain camera sees it; misread: labelled the other."""
    assert abs(chirality(FLAT_HAND)) < 1e-9
    shape = FLAT_HAND * (95.0 / np.linalg.norm(FLAT_HAND[9] - FLAT_HAND[0]))
    px = project(shape + np.array([x_mm, 0.0, 500.0]), CAM)
    image = np.column_stack((px[:, 0] / CAM.width, px[:, 1] / CAM.height, np.zeros(21)))
    # MediaPipe labels as if the image were mirrored: a plain image's right hand is 'Left'
    label = {'right': 'Left', 'left': 'Right'}[side]
    if misread:
        label = 'Right' if label == 'Left' else 'Left'
    return HandLandmarks(image, FLAT_HAND, label, score)


def camera_source():
    """A CameraSource's hand conversion alone: no capture, no detector."""
    src = CameraSource.__new__(CameraSource)
    src.mirrored, src.palm_length_mm = False, 95.0
    src.camera_position_mm = DEFAULT_CAMERA_POSITION_MM
    src._tracks = HandTracks()
    return src


def run(src, frames, dt=1 / 30):
    """Each image's published hands as {side: hand}."""
    return [{h.side: h for h in src.hands_of(lms, CAM, k * dt)} for k, lms in enumerate(frames)]


def test_two_hands_whose_sides_are_misread_together_keep_their_sides_ids_and_palms():
    # Keyed by side, a right hand read as the left one took the left hand's id: the left
    # tracker followed the right hand 0.9 m away with its origin kept, then jumped back.
    frames = []
    for k in range(30):
        misread = 10 <= k < 10 + SIDE_SWITCH_FRAMES - 2      # both at once, for 6 images
        # the person's right hand is on the image's left; both move 3 mm an image
        frames.append([landmarks('right', -200 + 3 * k, misread=misread),
                       landmarks('left', 200 - 3 * k, misread=misread)])
    out = run(camera_source(), frames)
    assert all(set(hands) == {'right', 'left'} for hands in out)
    for side, sign in (('right', 1), ('left', -1)):
        ids = {hands[side].id for hands in out}
        palms = np.array([hands[side].palm_position for hands in out])
        assert len(ids) == 1, (side, ids)
        assert np.all(sign * palms[:, 0] > 100), side                 # on the person's side
        assert np.max(np.linalg.norm(np.diff(palms, axis=0), axis=1)) < 20, side
        # read as the side it keeps: its thumb and palm normal are a `side` hand's
        assert all(hands[side].side == side for hands in out)
    assert out[0]['right'].id != out[0]['left'].id


def test_one_hand_misread_for_a_few_images_keeps_its_side_and_id():
    frames = [[landmarks('right', -100, misread=10 <= k < 16)] for k in range(25)]
    src = camera_source()
    out = run(src, frames)
    tracker, events = HandTracker('right'), []
    for k, hands in enumerate(out):
        assert list(hands) == ['right']
        state = tracker.update(hands['right'], k / 30, k + 1)
        events += [e.gesture for e in state.events]
    assert len({hands['right'].id for hands in out}) == 1
    assert events.count('hand_lost') == 0 and events.count('hand_found') == 1


def test_a_hand_read_as_the_other_side_for_long_changes_side_as_a_new_hand():
    n = SIDE_SWITCH_FRAMES
    frames = [[landmarks('right', -100, misread=k >= 5)] for k in range(5 + n + 3)]
    out = run(camera_source(), frames)
    assert all(list(hands) == ['right'] for hands in out[:5 + n - 1])
    assert all(list(hands) == ['left'] for hands in out[5 + n - 1:])
    assert out[-1]['left'].id != out[0]['right'].id
    assert not np.any(out[5 + n - 1]['left'].palm_velocity)          # a new hand: no velocity


def test_another_hand_taking_a_side_is_a_new_hand_and_a_fast_one_stays_itself():
    src = camera_source()
    # one hand moving 60 mm an image (1.8 m/s at 30 images/s) stays itself
    out = run(src, [[landmarks('right', -300 + 60 * k)] for k in range(8)])
    assert len({hands['right'].id for hands in out}) == 1
    # in the next image a right hand elsewhere (another person's): a new id, and the
    # tracker loses the first one (and its origin)
    tracker = HandTracker('right')
    state = tracker.update(out[-1]['right'], 1.0, 1)
    first_id = out[-1]['right'].id
    other = src.hands_of([landmarks('right', -380)], CAM, 8 / 30)[0]
    assert other.id != first_id and not np.any(other.palm_velocity)
    state = tracker.update(other, 1.0 + 1 / 30, 2)
    assert not state.present and [e.gesture for e in state.events] == ['hand_lost']


def test_a_side_taken_by_another_followed_hand_goes_to_the_other_side_at_once():
    # Both hands read as right when they appear: the one not published takes the left
    # side as soon as it is read so, rather than after SIDE_SWITCH_FRAMES images.
    frames = [[landmarks('right', -200), landmarks('left', 200, misread=True, score=0.9)],
              [landmarks('right', -200), landmarks('left', 200)],
              [landmarks('right', -200), landmarks('left', 200)]]
    out = run(camera_source(), frames)
    assert list(out[0]) == ['right'] and out[0]['right'].palm_position[0] > 0
    assert set(out[1]) == set(out[2]) == {'right', 'left'}
    assert out[1]['left'].palm_position[0] < 0 and out[1]['left'].id == out[2]['left'].id
    assert out[1]['right'].id == out[0]['right'].id


@pytest.mark.parametrize('forget, same_id', [('forget_motion', True), ('forget_hands', False)])
def test_separate_photos_keep_each_sides_id_and_a_cut_starts_afresh(forget, same_id):
    src = camera_source()
    first = src.hands_of([landmarks('right', -200)], CAM, 0.0)[0]
    getattr(src, forget)()
    photo = src.hands_of([landmarks('right', 250)], CAM, 0.1)[0]     # far from the last
    assert (photo.id == first.id) == same_id and not np.any(photo.palm_velocity)
