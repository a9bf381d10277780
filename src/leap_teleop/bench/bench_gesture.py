"""Gesture recognition and recording decoding speed.

gesture.us_per_hand_frame: GestureRecognizer.update per hand frame (stream mode, circles
on), over real recorded hands when the shared recordings exist, else synthetic poses.
recording.frames_per_s: read + decode + convert to Frames (leapjs.load_frames, what
RecordingSource runs), all shared .json.gz takes.
recording.lz_frames_per_s: the same from the original .json.lz files.

Times are this process's CPU time (time.process_time), best of PASSES passes: the machine
is shared, and wall time would also count the turns other processes get on the cores.
"""
import glob
import os
import time

PASSES = 5
_clock = time.process_time

from ..gestures import GestureRecognizer
from ..hand_model import POSES, render_hand
from ..sources import leapjs
from ..tools.evaluate import DEFAULT_DATA


def _hands():
    files = sorted(glob.glob(os.path.join(DEFAULT_DATA, 'decoded', '*.json.gz')))
    hands = []
    for path in files:
        for f in leapjs.load_frames(path)[1]:
            hands.extend((h, f.timestamp) for h in f.hands)
    if not hands:
        hands = [(render_hand('right', pose, (0.0, 200.0 + i % 50, 0.0)), i / 120.0)
                 for i, pose in enumerate(list(POSES) * 200)]
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
    hands = _hands()
    best = None
    for _ in range(PASSES):
        rec = {'right': GestureRecognizer(), 'left': GestureRecognizer()}
        t0 = _clock()
        for hand, ts in hands:
            rec[hand.side].update(hand, ts)
        us = (_clock() - t0) * 1e6 / len(hands)
        best = us if best is None else min(best, us)
    out['gesture.us_per_hand_frame'] = best
    # Let go of the hands first: thousands of live Hands would only slow the garbage
    # collector during the decoding measured next.
    del hands, rec
    gz = sorted(glob.glob(os.path.join(DEFAULT_DATA, 'decoded', '*.json.gz')))
    rate = _decode_rate(gz)
    if rate is None:    # no shared data: a recording of synthetic frames written here
        import tempfile
        from ..frame import Frame
        with tempfile.TemporaryDirectory() as tmp:
            path = os.path.join(tmp, 'synthetic.json.gz')
            frames = [leapjs.frame_to_dict(Frame(i, i / 120.0, [render_hand('right', 'open', (0, 200, 0))]))
                      for i in range(2000)]
            leapjs.save(path, frames)
            rate = _decode_rate([path])
    out['recording.frames_per_s'] = rate
    lz = sorted(glob.glob(os.path.join(DEFAULT_DATA, '*.json.lz')))
    if lz:
        out['recording.lz_frames_per_s'] = _decode_rate(lz)
    return out
