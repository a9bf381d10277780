"""The demo's pictures from a recorded flight: chase-view GIF, flight plot, hand insets."""
import math

import numpy as np
from PIL import Image

from leap_teleop.msg import Hand
from tools import demo_pictures as dp

# A short flight: landed, takeoff, hover, flip, landing (times in s).
STATES = [(0.0, 2), (0.5, 6), (1.5, 4), (2.0, 9), (2.5, 3), (3.0, 8), (3.8, 2)]
GESTURES = [(0.45, 'unfold'), (1.95, 'circle_cw'), (2.95, 'fold')]


def _track():
    rows = []
    for t in np.arange(0.0, 4.5, 0.02):
        z = min(1.0, max(0.0, t - 0.5)) if t < 3.0 else max(0.0, 1.0 - (t - 3.0) * 1.25)
        roll = 2 * math.pi * (t - 2.0) / 0.5 if 2.0 <= t < 2.5 else 0.0
        rows.append((t, 0.3 * t, 0.0, z, math.sin(roll / 2), 0.0, 0.0, math.cos(roll / 2)))
    return rows


def test_frame_times_slow_the_flip_down_and_stop_after_landing():
    times = dp.frame_times(_track(), STATES)
    slow = [t for t, ms in times if ms == 150]
    assert slow and min(slow) >= 1.7 - 1e-9 and max(slow) <= 3.0 + 1e-9
    assert times[-1][0] <= 3.8 + 2.0 + 1e-9
    assert dp.state_at(STATES, 2.2) == 9 and dp.state_at(STATES, 10.0) == 2


def test_chase_gif_and_flight_plot_are_written(tmp_path):
    track = _track()
    cams = [(t, np.full((90, 160, 3), 200, np.uint8)) for t in (0.0, 1.0, 2.0)]
    n = dp.chase_gif(track, STATES, GESTURES, str(tmp_path / 'drone.gif'), cams,
                     size=(160, 120))
    gif = Image.open(tmp_path / 'drone.gif')
    assert n == gif.n_frames == len(dp.frame_times(track, STATES))
    gif.seek(0)
    assert np.asarray(gif.convert('RGB')).std() > 10
    dp.flight_plot(track, STATES, GESTURES, str(tmp_path / 'flight.png'))
    plot = np.asarray(Image.open(tmp_path / 'flight.png').convert('RGB'))
    assert plot.shape[0] > 400 and plot.std() > 10


def test_hand_inset_names_the_pose():
    hand = Hand(present=True, pinch=True, pinch_value=0.5)
    hand.finger_extended = [True, True, False, False, False]
    assert dp.hand_label(hand) == 'pinch 0.50'
    assert dp.hand_label(None) == 'no hand'
    assert dp.hand_label(Hand(present=True, fist=True)) == 'fist'
    pic = dp.hand_inset(hand, 'ur10_1: right hand')
    assert pic.size == (128, 118) and np.asarray(pic).std() > 10
