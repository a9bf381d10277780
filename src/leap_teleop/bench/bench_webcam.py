"""The camera hand source on the shared clips (shared/data/hands): throughput and latency.

webcam.fps: frames per second through the whole video source (decode, letterbox to
640x480, MediaPipe Hands full model looking for up to two hands, landmark conversion),
as fast as possible, both clips; next to it the plain legacy graph (max_num_hands=2, palm
detector on every frame with fewer than two hands), alternating rounds.
webcam.latency_p99_ms: frame captured -> leapcobot message received, the sender running
as a node on the clips paced at 30 frames/s and behaving like a webcam (a frame that
arrives while the previous one is processed replaces it: ~video_drop_late), probed on
leapmotion/data_right; webcam.processed_fraction: the share of the clip's frames it
processed meanwhile.
"""
import os
import sys
import time

import numpy as np

from leap_teleop.bench import harness
from leap_teleop.nodes.common import package_path
from leap_teleop.tools.evaluate import HANDS_DATA

CLIPS = ('clip_fist_then_thumbs_up__mps__gr_test_video.mp4',
         'clip_palm_motion__mps__hl_test_video.mp4')
ROUNDS = 3
PACE_HZ = 30
WINDOW_S = 10.0


def _clip(name):
    path = os.path.join(HANDS_DATA, name)
    if not os.path.isfile(path):
        raise RuntimeError('shared clip %s absent (set HANDS_DATA)' % path)
    return path


def _throughput(strategy):
    """(frames/s, CPU ms per frame, hands found) over both clips, as fast as possible."""
    from leap_teleop.sources import make_source
    frames = hands = 0
    wall = cpu = 0.0
    for name in CLIPS:
        source = make_source('video', path=_clip(name), realtime=False, width=640, height=480,
                             max_hands=2, model='full', strategy=strategy)
        t0, c0 = time.perf_counter(), time.process_time()
        for frame in source.frames():
            frames += 1
            hands += len(frame.hands)
        wall += time.perf_counter() - t0
        cpu += time.process_time() - c0
    return frames / wall, cpu / frames * 1e3, hands


def _sender_cmd(video):
    return [sys.executable, package_path('scripts', 'sender.py'), '__name:=leap_sender',
            '_source:=video', '_video:=%s' % video, '_loop:=true', '_rate:=%d' % PACE_HZ,
            '_video_drop_late:=true']


def run():
    results = {}
    fps = {'paired': [], 'single': []}
    cpu = {'paired': [], 'single': []}
    for _ in range(ROUNDS):
        for strategy in ('paired', 'single'):
            f, c, hands = _throughput(strategy)
            fps[strategy].append(f)
            cpu[strategy].append(c)
            print('  %s: %.1f frames/s, %.1f ms CPU per frame, %d hands'
                  % (strategy, f, c, hands))
    results['webcam.fps'] = float(np.median(fps['paired']))
    results['webcam.fps_single_graph'] = float(np.median(fps['single']))
    results['webcam.cpu_ms_per_frame'] = float(np.median(cpu['paired']))

    latencies, received = [], 0
    with harness.ros_master() as env:
        for name in CLIPS:
            node = harness.start_node(env, _sender_cmd(_clip(name)))
            try:
                cobot = harness.probe(env, 'leapmotion/data_right', 'leap_teleop/leapcobotright',
                                      WINDOW_S, warmup=2.0)
            finally:
                harness.stop_node(node)
            lat = np.subtract(cobot['receipt'], cobot['stamp'])
            print('  sender on %s at %d Hz: %d messages (%.1f/s), latency p50 %.1f ms, '
                  'p99 %.1f ms' % (name, PACE_HZ, len(lat), len(lat) / WINDOW_S,
                                   *harness.percentiles_ms(lat)))
            latencies.extend(lat)
            received += len(lat)
    results['webcam.processed_fraction'] = received / (PACE_HZ * WINDOW_S * len(CLIPS))
    results['webcam.latency_p50_ms'], results['webcam.latency_p99_ms'] = \
        harness.percentiles_ms(latencies)
    return results
