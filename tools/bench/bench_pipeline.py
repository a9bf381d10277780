"""Capture to arm command through the real graph, for a Leap recording and for video.

pipeline.capture_to_command_p50_ms_<source> / _p99_ms_<source>: per hand input that an arm
command acts on, the command's time minus the input's capture stamp (the frame's), with
the sample count in pipeline.capture_to_command_samples_<source>. The graph: one sender
(the recording source on the shared LeapJS take rollAndPitchCropped, an open hand rolled
and pitched at ~114 frames/s, looping in real time; or the video source on the shared
clip of a fist then a held thumbs-up, paced at 30 frames/s like a webcam, dropping late
frames, hand searches on their thread), one ur10_arm node and the UR10 simulator, under a
private master. The arm's ArmStatus stream gives (command time, input_stamp) per control
period: the status is stamped as the period's command goes out and carries the capture
stamp of the hand behind it. The first command carrying a new input stamp is that input's
command; periodic repeats of an older input are not counted (they measure the input
rate, not the latency). Only inputs from the measured sender count (its Hand stamps).

So that each command has its own status: ~status_rate 1000 Hz and the control loop's
periodic rate at its floor (10 Hz, as bench_arm) - the loop still runs on every new hand
message, so hand-driven commands are timed as in service; a status within 1 ms of the
previous one is skipped by the node (that input is then not counted).

Arming: the recording has no thumbs-up and neither source shows a rock, so the driver
(pipeline_driver) holds a made-up thumbs-up before the recording starts and sends a short
rock at the measured palm whenever the arm is armed; the clip's own thumbs-up arms the arm
on each pass (its start shows no hand, then a fist: the arm disarms there).
"""
import json
import os
import subprocess
import sys
import tempfile

import numpy as np

from leap_teleop.hands.gestures.datasets import HANDS_DATA, data_dir
from leap_teleop.package_files import package_path
from tools.bench import ros_processes

RECORDING = 'rollAndPitchCropped.json.lz'
CLIP = 'clip_fist_then_thumbs_up__mps__gr_test_video.mp4'
VIDEO_HZ = 30
SOURCES = ('leap_recording', 'video')
ROUNDS = 2                  # per source, alternating
DURATION_S = 30.0           # recorded per round, from 1 s after the arm first tracks
GATE = '/bench/pipeline_go'


def first_command_ages(commands, input_stamps=None, tol=1e-6):
    """Capture-to-command ages (s), one per input, from the arm's stream of (command time,
    input stamp) pairs in the order sent: a pair whose stamp is newer than every earlier
    one is the first command acting on that input; a repeated or older stamp (a periodic
    command on the same input) is no new sample, nor is a stamp <= 0 (no input yet). With
    input_stamps, only stamps within tol of one of them count (the measured source's)."""
    known = np.sort(np.asarray(input_stamps, dtype=float)) if input_stamps is not None else None
    ages = []
    newest = 0.0
    for when, stamp in commands:
        if not stamp > newest:
            continue
        newest = stamp
        if known is not None:
            i = np.searchsorted(known, stamp)
            near = [known[j] for j in (i - 1, i) if 0 <= j < len(known)]
            if not any(abs(k - stamp) <= tol for k in near):
                continue
        ages.append(when - stamp)
    return ages


def summary_ms(ages_s):
    """(p50 ms, p99 ms, samples); ValueError when there is no sample."""
    if len(ages_s) == 0:
        raise ValueError('no arm command acted on the measured hands')
    p50, p99 = ros_processes.percentiles_ms(ages_s)
    return p50, p99, len(ages_s)


def _data(folder, name, var):
    path = os.path.join(folder, name)
    if not os.path.isfile(path):
        raise RuntimeError('shared file %s absent (set %s)' % (path, var))
    return path


def _sender_cmd(source):
    cmd = [sys.executable, package_path('scripts', 'sender.py'), '__name:=leap_sender',
           '_sides:=[right]', '_loop:=true', '_wait_for_subscribers:=true',
           '_wait_topics:=[%s]' % GATE]
    if source == 'leap_recording':
        return cmd + ['_source:=recording',
                      '_recording:=%s' % _data(data_dir(), RECORDING, 'LEAPJS_DATA')]
    return cmd + ['_source:=video', '_video:=%s' % _data(HANDS_DATA, CLIP, 'HANDS_DATA'),
                  '_rate:=%d' % VIDEO_HZ, '_video_drop_late:=true']


def _arm_cmd():
    return [sys.executable, package_path('scripts', 'ur10_arm.py'), '__name:=ur10_arm',
            '__ns:=ur10_1', '_hand:=right', '_hand_topic:=/leapmotion/data_right',
            '_joint_prefix:=ur10_1_', '_max_joint_speed:=1.0', '_max_joint_accel:=3.14159',
            '_rate:=10.0', '_status_rate:=1000.0']


def measure_round(env, source, duration):
    """One sender on `source` into the running arm: the driver's record (dict)."""
    with tempfile.NamedTemporaryFile(suffix='.json', delete=False) as f:
        out = f.name
    sender = ros_processes.spawn_node(env, _sender_cmd(source))
    try:
        cmd = [sys.executable, '-m', 'tools.bench.pipeline_driver', '--out', out,
               '--gate', GATE, '--duration', str(duration)]
        if source == 'leap_recording':
            cmd.append('--inject-thumbs-up')
        subprocess.run(cmd, env=env, check=True, timeout=duration + 150)
        with open(out) as f:
            return json.load(f)
    finally:
        ros_processes.stop_spawned(sender)
        os.unlink(out)


def round_ages(data):
    """(ages s, capture -> Hand receipt s) of one driver record."""
    stamps = [h[0] for h in data['hands']]
    ages = first_command_ages([(s[0], s[1]) for s in data['status']], stamps)
    transit = [h[1] - h[0] for h in data['hands']]
    return ages, transit


def measure(rounds=ROUNDS, duration=DURATION_S, sources=SOURCES):
    """{source: (ages s, capture -> Hand receipt s, rocks sent)} over alternating rounds
    under one master, simulator and arm node."""
    got = {s: ([], [], 0) for s in sources}
    with ros_processes.ros_master() as env:
        sim = ros_processes.spawn_node(env, [sys.executable, package_path('scripts', 'ur10_sim.py'),
                                             '__name:=ur10_sim'])
        arm = ros_processes.spawn_node(env, _arm_cmd())
        try:
            for _ in range(rounds):
                for source in sources:
                    data = measure_round(env, source, duration)
                    ages, transit = round_ages(data)
                    p50, p99, n = summary_ms(ages) if ages else (np.nan, np.nan, 0)
                    # The sender's share: its Hand message received by the driver.
                    t50, t99 = ros_processes.percentiles_ms(transit)
                    print('  %s: %d commands on new input in %.0f s (%d rocks sent), capture -> '
                          'command p50 %.1f ms, p99 %.1f ms; capture -> Hand received p50 '
                          '%.1f ms, p99 %.1f ms' % (source, n, duration, data['rocks'], p50, p99,
                                                    t50, t99), flush=True)
                    a, t, r = got[source]
                    got[source] = (a + ages, t + transit, r + data['rocks'])
        finally:
            ros_processes.stop_spawned(arm)
            ros_processes.stop_spawned(sim)
    return got


def run():
    results, sources = {}, {}
    for source, (ages, transit, rocks) in measure().items():
        # The capture stamps must be this run's wall clock (a replayed file's own times
        # would make every age years long, or negative).
        lag = float(np.median(transit))
        if not 0.0 <= lag < 1.0:
            raise RuntimeError('%s: capture stamps are not on the wall clock (median capture '
                               '-> receipt %.3f s)' % (source, lag))
        p50, p99, n = summary_ms(ages)
        keys = ['pipeline.capture_to_command_%s_%s' % (k, source)
                for k in ('p50_ms', 'p99_ms', 'samples')]
        results.update(zip(keys, (p50, p99, n)))
        what = (RECORDING + ' looping in real time' if source == 'leap_recording'
                else CLIP + ' paced at %d frames/s, late frames dropped' % VIDEO_HZ)
        for key in keys:
            sources[key] = ('%d rounds of %.0f s alternating the sources, one sender on %s -> '
                            'ur10_arm -> UR10 sim; %d commands on new input, %d rocks sent'
                            % (ROUNDS, DURATION_S, what, n, rocks))
    results['_sources'] = sources
    return results
