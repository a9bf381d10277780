"""The camera hand source on the shared clips (shared/data/hands): throughput and latency.

webcam.fps: frames per second through the whole video source (decode, letterbox to
640x480, MediaPipe Hands full model looking for up to two hands, landmark conversion),
as fast as possible, both clips (searching for hands in the call: offline processing does
not use the search thread); next to it, alternating rounds, the plain legacy graph
(max_num_hands=2, palm detector on every frame with fewer than two hands).
webcam.recognition_us_per_hand: what recognizing a camera hand adds to MediaPipe: the
gesture recognizer's update (keypoint model as seen and mirrored, thumb guard, temporal
filter, circles) per hand the source found in both clips, one recognizer per side, in
stream order; this process's CPU time, best of RECOGNITION_PASSES passes.
webcam.latency_p99_ms: frame captured -> leapcobot message received, the sender running
as a node on the clips paced at 30 frames/s and behaving like a webcam (a frame that
arrives while the previous one is processed replaces it: ~video_drop_late), probed on
leapmotion/data_right; webcam.processed_fraction: the share of the clip's frames it
processed meanwhile. Every published message counts (none is left out of the tail).
Latency is measured with the hand searches on their worker thread (the default) and,
alternating rounds, in the frame's own processing (~search_thread false:
webcam.latency_*_search_inline), to show what the thread buys.
"""
import os
import sys
import time

import numpy as np

from leap_teleop.hands.gestures.datasets import HANDS_DATA
from leap_teleop.package_files import package_path
from tools.bench import ros_processes

CLIPS = ('clip_fist_then_thumbs_up__mps__gr_test_video.mp4',
         'clip_palm_motion__mps__hl_test_video.mp4')
ROUNDS = 3
RECOGNITION_PASSES = 5
PACE_HZ = 30
WINDOW_S = 10.0


def _clip(name):
    path = os.path.join(HANDS_DATA, name)
    if not os.path.isfile(path):
        raise RuntimeError('shared clip %s absent (set HANDS_DATA)' % path)
    return path


def _throughput(strategy, found=None):
    """(frames/s, CPU ms per frame, hands found) over both clips, as fast as possible;
    `found`, a list, gets each (hand, timestamp) found."""
    from leap_teleop.hands.sources import make_source
    frames = hands = 0
    wall = cpu = 0.0
    for name in CLIPS:
        source = make_source('video', path=_clip(name), realtime=False, width=640, height=480,
                             max_hands=2, model='full', strategy=strategy)
        t0, c0 = time.perf_counter(), time.process_time()
        for frame in source.frames():
            frames += 1
            hands += len(frame.hands)
            if found is not None:
                found.extend((h, frame.timestamp) for h in frame.hands)
        wall += time.perf_counter() - t0
        cpu += time.process_time() - c0
    return frames / wall, cpu / frames * 1e3, hands


def _recognition_us(hands):
    """Best per-hand CPU time of GestureRecognizer.update over `hands`, microseconds."""
    from leap_teleop.hands.gestures import GestureRecognizer
    best = None
    for _ in range(RECOGNITION_PASSES):
        rec = {'right': GestureRecognizer(), 'left': GestureRecognizer()}
        t0 = time.process_time()
        for hand, ts in hands:
            rec[hand.side].update(hand, ts)
        us = (time.process_time() - t0) * 1e6 / len(hands)
        best = us if best is None else min(best, us)
    return best


def _sender_cmd(video, search_thread):
    return [sys.executable, package_path('scripts', 'sender.py'), '__name:=leap_sender',
            '_source:=video', '_video:=%s' % video, '_loop:=true', '_rate:=%d' % PACE_HZ,
            '_video_drop_late:=true', '_search_thread:=%s' % str(search_thread).lower()]


def run():
    results = {}
    strategies = ('paired', 'single')
    fps = {k: [] for k in strategies}
    cpu = {k: [] for k in strategies}
    found = []
    for _ in range(ROUNDS):
        for name in strategies:
            f, c, hands = _throughput(name, found if not found and name == 'paired' else None)
            fps[name].append(f)
            cpu[name].append(c)
            print('  %s: %.1f frames/s, %.1f ms CPU per frame, %d hands'
                  % (name, f, c, hands))
    results['webcam.fps'] = float(np.median(fps['paired']))
    results['webcam.fps_single_graph'] = float(np.median(fps['single']))
    results['webcam.cpu_ms_per_frame'] = float(np.median(cpu['paired']))
    if not found:
        raise RuntimeError('MediaPipe found no hand in the shared clips')
    results['webcam.recognition_us_per_hand'] = _recognition_us(found)
    print('  recognition: %.1f us per camera hand (%d hands, best of %d)'
          % (results['webcam.recognition_us_per_hand'], len(found), RECOGNITION_PASSES))
    del found

    variants = {'thread': True, 'inline': False}
    latencies = {v: [] for v in variants}
    p99s = {v: [] for v in variants}
    received = 0
    with ros_processes.ros_master() as env:
        for _ in range(ROUNDS):
            for variant, search_thread in variants.items():
                lats = []
                for name in CLIPS:
                    node = ros_processes.spawn_node(env, _sender_cmd(_clip(name), search_thread))
                    try:
                        cobot = ros_processes.probe(env, 'leapmotion/data_right',
                                              'leap_teleop/leapcobotright', WINDOW_S,
                                              warmup=2.0)
                    finally:
                        ros_processes.stop_spawned(node)
                    lat = np.subtract(cobot['receipt'], cobot['stamp'])
                    print('  sender (search %s) on %s at %d Hz: %d messages (%.1f/s), latency '
                          'p50 %.1f ms, p99 %.1f ms'
                          % (variant, name, PACE_HZ, len(lat), len(lat) / WINDOW_S,
                             *ros_processes.percentiles_ms(lat)))
                    lats.extend(lat)
                    if search_thread:
                        received += len(lat)
                latencies[variant].extend(lats)
                p99s[variant].append(ros_processes.percentiles_ms(lats)[1])
    for variant in variants:
        print('  search %s: p99 per round %s ms' % (
            variant, ', '.join('%.1f' % v for v in p99s[variant])))
    results['webcam.processed_fraction'] = received / (PACE_HZ * WINDOW_S * len(CLIPS) * ROUNDS)
    results['webcam.latency_p50_ms'], results['webcam.latency_p99_ms'] = \
        ros_processes.percentiles_ms(latencies['thread'])
    results['webcam.latency_p50_ms_search_inline'], \
        results['webcam.latency_p99_ms_search_inline'] = \
        ros_processes.percentiles_ms(latencies['inline'])
    return results
