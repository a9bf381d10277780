"""Real palm paths from the shared Leap recordings, for the closed-loop arm benches: the
LeapJS takes (../shared/data/leapjs, through the recording source) and the Guinevere
dynamic takes (../shared/data/leap_people/guinevere, through the dataset readers).

A path is (name, times s from its first frame, palm positions mm, Leap axes) of one hand.
Missing data raises DataError (a bench on real motion has nothing to measure without it).
"""
import os

import numpy as np

from leap_teleop.hands.gestures import datasets
from leap_teleop.hands.sources import leapjs
from leap_teleop.hands.sources.recording import RecordingSource

# Takes where the hand travels: the open hand moved and the palm swipes of both
# Guinevere people (0.4-1.3 s, 100-330 mm at 150-450 mm/s median), and the LeapJS takes
# with an open hand moving about (wave, paddling, brian's moves, claps, flapping).
GUINEVERE_MOVES = ('open_hand_', 'swipe_')
GUINEVERE_HOW = '#palm'
LEAPJS_MOVES = ('wave', 'test-paddle-rightwards', 'brian', 'three-claps', 'flapping')
# The stillest take: a right hand pinching in place (palm within 3-6 mm for 2.7 s).
LEAPJS_STILL = 'pinch'


def _path(name, frames, side='right'):
    """(name, t, palm) of `side`'s hand over Frames (the first hand when no `side` one)."""
    t, palm = [], []
    for frame in frames:
        hands = [h for h in frame.hands if h.side == side] or frame.hands[:1]
        if hands:
            t.append(frame.timestamp)
            palm.append(hands[0].palm_position)
    if len(t) < 10:
        raise datasets.DataError('%s: fewer than 10 frames with a hand' % name)
    t = np.asarray(t, dtype=float)
    return name, t - t[0], np.asarray(palm, dtype=float)


def leapjs_path(take, side='right'):
    """The palm path of a shared LeapJS take, read by the project's recording source."""
    path = datasets.find_take(datasets.data_dir(), take)
    if path is None:
        raise datasets.DataError('LeapJS take %r not found under %s' % (take, datasets.data_dir()))
    source = RecordingSource(path, realtime=False, clock=lambda: 0.0)
    return _path('leapjs/' + take, source.frames(), side)


def guinevere_paths(root=None):
    """The palm paths of the Guinevere takes where the open hand or the palm moves."""
    takes = [(person, gesture, path) for person, gesture, path in datasets.guinevere_takes(root)
             if gesture.startswith(GUINEVERE_MOVES)
             and (gesture.startswith('open_hand_') or GUINEVERE_HOW in gesture)]
    if not takes:
        raise datasets.DataError('no Guinevere open-hand or palm-swipe takes under %s'
                                 % (root or os.path.join(datasets.LEAP_PEOPLE, 'guinevere')))
    out = []
    for person, _, path in takes:
        frames = []
        for d in datasets.read_take(path):
            try:
                frames.append(leapjs.frame_from_dict(d))
            except leapjs.FrameError:
                continue
        name = 'guinevere/%s/%s' % (person, os.path.basename(path).split('.json')[0])
        out.append(_path(name, frames))
    return out


def moving_paths():
    """Every real path the tracking bench replays."""
    return guinevere_paths() + [leapjs_path(take) for take in LEAPJS_MOVES]
