"""Gesture recognition and recording decoding speed.

gesture.us_per_hand_frame: GestureRecognizer.update per hand frame (stream mode, circles
on), over the real recorded hands of the shared recordings ($LEAPJS_DATA or
../shared/data/leapjs; without them this benchmark fails rather than measure something
else under the same name).
recording.frames_per_s: read + decode + convert to Frames (leapjs.load_frames, what
RecordingSource runs), all shared .json.gz takes.
recording.lz_frames_per_s: the same from the original .json.lz files.

Times are this process's CPU time (time.process_time), best of PASSES passes: the machine
is shared, and wall time would also count the turns other processes get on the cores.
"""
import glob
import os
import time

from leap_teleop.hands.gestures import GestureRecognizer
from leap_teleop.hands.gestures.datasets import data_dir
from leap_teleop.hands.sources import leapjs

PASSES = 5
_clock = time.process_time


def _files(pattern):
    files = sorted(glob.glob(os.path.join(data_dir(), pattern)))
    if not files:
        raise FileNotFoundError('no %s in %s (set $LEAPJS_DATA)' % (pattern, data_dir()))
    return files


def _hands(files):
    hands = []
    for path in files:
        for f in leapjs.load_frames(path)[1]:
            hands.extend((h, f.timestamp) for h in f.hands)
    return hands


def _decode_rate(files):
    """Frames per second through leapjs.load_frames (what RecordingSource runs): read,
    decompress, parse, convert every frame to a Frame. Best of 3 passes."""
    if not files:
        return None
    best = 0.0
    for _ in range(PASSES):
        t0 = _clock()
        n = 0
        for path in files:
            n += len(leapjs.load_frames(path)[1])
        best = max(best, n / (_clock() - t0))
    return best


def run():
    out = {}
    gz = _files(os.path.join('decoded', '*.json.gz'))
    lz = _files('*.json.lz')
    hands = _hands(gz)
    best = None
    for _ in range(PASSES):
        rec = {'right': GestureRecognizer(), 'left': GestureRecognizer()}
        t0 = _clock()
        for hand, ts in hands:
            rec[hand.side].update(hand, ts)
        us = (_clock() - t0) * 1e6 / len(hands)
        best = us if best is None else min(best, us)
    out['gesture.us_per_hand_frame'] = best
    n_hands = len(hands)
    # Let go of the hands first: thousands of live Hands would only slow the garbage
    # collector during the decoding measured next.
    del hands, rec
    out['recording.frames_per_s'] = _decode_rate(gz)
    out['recording.lz_frames_per_s'] = _decode_rate(lz)
    out['_sources'] = {
        'gesture.us_per_hand_frame': '%d hand frames of %d takes in %s/decoded, best of %d'
                                     % (n_hands, len(gz), data_dir(), PASSES),
        'recording.frames_per_s': '%d .json.gz takes in %s/decoded, best of %d'
                                  % (len(gz), data_dir(), PASSES),
        'recording.lz_frames_per_s': '%d .json.lz takes in %s, best of %d'
                                     % (len(lz), data_dir(), PASSES)}
    return out
