"""Camera hands keep their ids and sides from image to image (hand_tracks.HandTracks through
CameraSource.hands_of), on synthetic landmark frames: no MediaPipe, no shared data."""
import dataclasses

import numpy as np
import pytest

from leap_teleop.hands.sources.camera import CameraSource
from leap_teleop.hands.sources.hand_tracks import (
    LONE_MATCH_MAX_SIZES,
    MATCH_MAX_SIZES,
    SIDE_SWITCH_FRAMES,
    HandTracks,
    image_place,
)
from leap_teleop.hands.sources.landmarks import (
    DEFAULT_CAMERA_POSITION_MM,
    CameraModel,
    HandLandmarks,
    chirality,
    project,
)
from leap_teleop.hands.tracker import HandTracker, hand_angles

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


def landmarks(side, x_mm, score=0.95, misread=False, y_mm=0.0, z_mm=500.0, mirrored=False):
    """HandLandmarks of a person's `side` hand, its centre x_mm right of the camera's axis
    in the image (and y_mm down, z_mm away), as a plain camera sees it; misread: labelled
    the other; mirrored: a left hand is the right one's mirror image, as a real one is."""
    assert abs(chirality(FLAT_HAND)) < 1e-9
    world = FLAT_HAND * (np.array([-1.0, 1.0, 1.0]) if mirrored and side == 'left' else 1.0)
    shape = world * (95.0 / np.linalg.norm(FLAT_HAND[9] - FLAT_HAND[0]))
    px = project(shape + np.array([x_mm, y_mm, z_mm]), CAM)
    image = np.column_stack((px[:, 0] / CAM.width, px[:, 1] / CAM.height, np.zeros(21)))
    # MediaPipe labels as if the image were mirrored: a plain image's right hand is 'Left'
    label = {'right': 'Left', 'left': 'Right'}[side]
    if misread:
        label = 'Right' if label == 'Left' else 'Left'
    return HandLandmarks(image, world, label, score)


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


def sessions(out, side):
    """A HandTracker of `side` through the published hands, its origin set in the first
    image (as a rock gesture would): [(state, session events)] per image."""
    tracker, states = HandTracker(side), []
    for k, hands in enumerate(out):
        state = tracker.update(hands.get(side), k / 30, k + 1)
        if k == 0:
            tracker._origin_angles = hand_angles(state.palm_normal, state.direction)
            tracker.state = state = dataclasses.replace(state, origin_set=True,
                                                        origin_palm=state.palm_position)
        states.append((state, [e.gesture for e in state.events
                               if e.gesture in ('hand_lost', 'hand_found')]))
    return states


@pytest.mark.parametrize('step, gap', [(10, 0), (20, 0), (40, 0), (40, 20), (60, 0), (60, 20), (90, 0)])
def test_crossing_hands_each_stay_on_their_side_with_their_id(step, gap):
    # Both read right in every image; they cross (at gap 0 in the same place): matched by
    # place alone, each side's track took the other hand there, with its id and origin,
    # read as the wrong side (palm 20-270 mm off, normal flipped) for 7 images.
    frames, true_x = [], []
    for k in range(int(600 / step)):
        xr, xl = -300 + step * k, 300 - step * k        # image x: the right hand moves right
        frames.append([landmarks('right', xr, y_mm=-gap / 2, mirrored=True),
                       landmarks('left', xl, y_mm=gap / 2, mirrored=True)])
        true_x.append({'right': -xr, 'left': -xl})      # Leap x is the image's -x here
    out = run(camera_source(), frames)
    for side in ('right', 'left'):
        assert len({hands[side].id for hands in out}) == 1, side
        palm_x = np.array([hands[side].palm_position[0] for hands in out])
        assert np.allclose(palm_x, [x[side] for x in true_x], atol=5), side
        assert all(hands[side].palm_normal[2] > 0.9 for hands in out), side    # facing the camera
        assert all(not events and state.origin_set for state, events in sessions(out, side)[1:]), side


def test_a_hand_passing_in_front_of_the_other_keeps_its_side_and_the_covered_one_comes_back_new():
    # The right hand passes 10 cm in front of the still left one, 2 cm higher; the left one
    # is not detected while it is covered by the other's middle.
    frames, covered = [], []
    for k in range(13):
        xr = -240 + 40 * k
        covered.append(abs(xr) < 100)
        right = landmarks('right', xr, y_mm=-20, z_mm=400, mirrored=True)
        frames.append([right] if covered[-1] else [right, landmarks('left', 0, mirrored=True)])
    out = run(camera_source(), frames)
    assert len({hands['right'].id for hands in out}) == 1
    assert all(abs(hands['right'].palm_position[0] - (240 - 40 * k)) < 5 for k, hands in enumerate(out))
    assert all(('left' in hands) != gone for hands, gone in zip(out, covered))
    assert all(abs(hands['left'].palm_position[0]) < 5 for hands in out if 'left' in hands)
    left = sessions(out, 'left')
    assert [events for _, events in left[1:] if events] == [['hand_lost'], ['hand_found']]
    # and passing in front while both are detected, the other one moving too: matched by
    # place alone, the sides swapped hands as they passed
    frames = [[landmarks('right', -240 + 40 * k, y_mm=-20, z_mm=400, mirrored=True),
               landmarks('left', 120 - 40 * k, mirrored=True)] for k in range(13)]
    out = run(camera_source(), frames)
    for side in ('right', 'left'):
        assert len({hands[side].id for hands in out}) == 1, side
    assert all(abs(hands['left'].palm_position[0] - (40 * k - 120)) < 5 for k, hands in enumerate(out))


@pytest.mark.parametrize('gap', [0, 20, 60, 220])
def test_a_hand_leaving_and_the_other_in_its_place_is_a_new_hand_on_its_side(gap):
    # The right hand leaves and in the next image the left one is in view gap mm beyond
    # where it was: matched by place, it was published as the right hand for 7 images,
    # with its id and origin (a palm jump up to 270 mm, flipped normal, no hand_lost).
    frames = [[landmarks('right', -100 + 5 * k, mirrored=True)] for k in range(6)]
    frames += [[landmarks('left', -75 + gap + 5 * k, mirrored=True)] for k in range(10)]
    out = run(camera_source(), frames)
    assert all(list(hands) == ['right'] for hands in out[:6])
    assert all(list(hands) == ['left'] for hands in out[6:])
    right, left = sessions(out, 'right'), sessions(out, 'left')
    assert right[6][1] == ['hand_lost'] and left[6][1] == ['hand_found']
    assert not np.any(out[6]['left'].palm_velocity)


@pytest.mark.parametrize('jump_sizes, same_hand', [(0.35, True), (0.65, True), (1.7, False)])
def test_a_lone_hand_further_than_the_lone_bound_from_its_last_place_is_a_new_hand(jump_sizes, same_hand):
    # A hand moving steadily 20 mm an image, then in one image `jump_sizes` hand sizes
    # beyond where it was heading: alone, it is that hand within LONE_MATCH_MAX_SIZES of
    # its last place (a fast hand got a new session every image); beyond, a new session.
    size_mm = image_place(camera_source().hands_of([landmarks('right', 0)], CAM, 0.0)[0])[1] \
        / CAM.fx * 500.0
    xs = [-200 + 20 * k for k in range(8)]
    xs.append(xs[-1] + 20 + jump_sizes * size_mm)
    xs += [xs[-1] + 20 * k for k in range(1, 4)]
    out = run(camera_source(), [[landmarks('right', x)] for x in xs])
    assert (out[8]['right'].id == out[7]['right'].id) == same_hand
    assert out[9]['right'].id == out[8]['right'].id
    events = [e for _, e in sessions(out, 'right')]
    assert events[8] == ([] if same_hand else ['hand_lost'])


@pytest.mark.parametrize('speed, rate', [(2.0, 15), (2.5, 15), (2.5, 30)])
def test_a_hand_setting_off_fast_keeps_its_id(speed, rate):
    # From rest at 2-2.5 m/s: a new track has no velocity to predict with, and the hand got
    # a new id (a new session) in every image.
    xs = [-300.0] * 5 + [-300.0 + 1000 * speed * k / rate for k in range(1, 10)]
    frames = [[landmarks('right', x)] for x in xs]
    out = run(camera_source(), frames, dt=1.0 / rate)
    assert len({hands['right'].id for hands in out}) == 1


def test_no_side_keeps_its_id_beyond_the_bound_from_its_prediction():
    # Two hands wandering about, each missed or misread now and then: whenever a side's
    # hand keeps its id, it is within half a hand size of where it was predicted to be, or
    # it is the lone hand of its side within LONE_MATCH_MAX_SIZES of its last place with
    # no other followed hand as near.
    rng = np.random.default_rng(7)
    checked = 0
    for _ in range(40):
        src, xs = camera_source(), rng.uniform(-250, 250, 2)
        for k in range(40):
            xs = xs + rng.normal(0, 40, 2)
            lms = [landmarks(side, x, misread=rng.random() < 0.3, y_mm=rng.normal(0, 20), mirrored=True)
                   for side, x in zip(('right', 'left'), xs) if rng.random() < 0.9]
            t = k / 30
            tracks = list(src._tracks._tracks)
            predicted = {tr.id: (tr.centre + getattr(tr, 'image_velocity', 0.0) * (t - tr.t)
                                 if tr.t is not None else tr.centre, tr.size, tr.centre) for tr in tracks}
            for hand in src.hands_of(lms, CAM, t):
                if hand.id in predicted:
                    centre, size = image_place(hand)
                    place, last_size, last = predicted[hand.id]
                    near = [tr.id for tr in tracks if np.linalg.norm(centre - tr.centre)
                            <= LONE_MATCH_MAX_SIZES * max(size, tr.size)]
                    assert np.linalg.norm(centre - place) <= MATCH_MAX_SIZES * max(size, last_size) + 1e-6 or (
                        near == [hand.id])
                    checked += 1
    assert checked > 1000


def test_one_misread_image_off_course_is_the_wrong_side_for_that_image_only():
    # A 70 mm jerk in one image, that image misread: a track started by it held the left
    # side against the 7 right readings after it.
    xs = [100.0] * 10 + [30.0] * 10
    out = run(camera_source(), [[landmarks('right', x, misread=k == 10)] for k, x in enumerate(xs)])
    assert [k for k, hands in enumerate(out) if 'left' in hands] == [10]
    assert all('right' in hands for hands in out[11:])


@pytest.mark.parametrize('order', ['other first', 'own first'])
def test_a_fast_hand_does_not_lose_its_session_to_another_hand_near_it(order):
    # The lone rule checked only the hands followed so far: another hand read as the same
    # side, new in the same image near the fast hand's last place, took the session
    # whenever the detector listed it first, with the origin kept.
    src, out = camera_source(), []
    for k in range(9):
        own = landmarks('right', -100 + 110 * max(0, k - 4))
        other = landmarks('right', -250)
        lms = [own] if k < 5 else ([other, own] if order == 'other first' else [own, other])
        out.append({h.side: h for h in src.hands_of(lms, CAM, k / 30)})
    kept = [k for k in range(5, 9) if out[k]['right'].id == out[4]['right'].id]
    # a session kept is the moving hand's (it moves right), never the other's (at the left)
    assert all(out[k]['right'].palm_position[0] > out[4]['right'].palm_position[0] for k in kept)


@pytest.mark.parametrize('x_mm, z_mm', [(330, 1300), (230, 900), (120, 250)])
def test_a_same_side_hand_at_another_depth_where_one_vanished_is_a_new_session(x_mm, z_mm):
    # Within 1.5 hand sizes in the image, a hand 0.4-0.8 m further or 0.25 m nearer kept
    # the vanished hand's session: palm jumps of 333-908 mm with the origin kept.
    frames = [[landmarks('right', -100)]] * 5 + [[landmarks('right', x_mm, z_mm=z_mm)]] * 3
    out = run(camera_source(), frames)
    assert out[5]['right'].id != out[4]['right'].id


@pytest.mark.parametrize('every', [2, 3])
def test_a_hand_misread_every_few_images_keeps_one_id_and_its_side(every):
    frames = [[landmarks('right', -150 + 5 * k, misread=k % every == 1)] for k in range(60)]
    out = run(camera_source(), frames)
    assert {hands['right'].id for hands in out} == {out[0]['right'].id}
    assert not any('left' in hands for hands in out)


@pytest.mark.parametrize('apart_mm', [80, 150])
def test_two_hands_misread_together_near_each_other_do_not_jump(apart_mm):
    # Both read as the other side for 6 images while close: each side keeps its own hand.
    frames = [[landmarks('right', -apart_mm / 2 - 2 * k, misread=8 <= k < 14, mirrored=True),
               landmarks('left', apart_mm / 2 + 2 * k, misread=8 <= k < 14, mirrored=True)]
              for k in range(20)]
    out = run(camera_source(), frames)
    for side, sign in (('right', 1), ('left', -1)):
        assert len({hands[side].id for hands in out}) == 1, side
        palms = np.array([hands[side].palm_position for hands in out])
        assert np.all(sign * palms[:, 0] > 0), side
        assert np.max(np.linalg.norm(np.diff(palms, axis=0), axis=1)) < 5, side


@pytest.mark.parametrize('step', [0, 20, 40])
def test_one_moving_hand_misread_for_seven_images_keeps_its_side_and_id(step):
    frames = [[landmarks('right', -150 + step * k, misread=5 <= k < 5 + SIDE_SWITCH_FRAMES - 1)]
              for k in range(20)]
    out = run(camera_source(), frames)
    assert all(list(hands) == ['right'] for hands in out)
    assert len({hands['right'].id for hands in out}) == 1
