"""Arm teleop: latency of the real node against a bare rospy echo (the closed loop's
tracking, jitter, orientation and onset figures: bench_arm_motion)."""
import json
import os
import subprocess
import sys
import tempfile

import numpy as np

from leap_teleop.bench import harness
from leap_teleop.nodes.common import package_path


def _round_trips(env, extra_args):
    with tempfile.NamedTemporaryFile(suffix='.json', delete=False) as f:
        out = f.name
    try:
        subprocess.run([sys.executable, '-m', 'leap_teleop.bench.arm_driver', '--out', out]
                       + extra_args, env=env, check=True, timeout=180)
        with open(out) as f:
            data = json.load(f)
    finally:
        os.unlink(out)
    if len(data['round_trip_s']) < 0.9 * data['sent']:
        raise RuntimeError('only %d of %d messages answered' % (len(data['round_trip_s']),
                                                                data['sent']))
    return np.asarray(data['round_trip_s'])


def _latency():
    with harness.ros_master() as env:
        arm = harness.start_node(env, [
            sys.executable, package_path('scripts', 'ur10_arm.py'), '__name:=ur10_arm',
            '__ns:=ur10_1', '_hand:=right', '_hand_topic:=/leapmotion/data_right',
            '_filter_min_cutoff_hz:=0.0', '_max_joint_speed:=1.0', '_input_timeout:=1.0',
            # The servo's command changes every period while it moves: with the periodic
            # loop at its slowest (10 Hz), a command answers a hand message, not the timer.
            '_rate:=10.0', '_joint_prefix:=ur10_1_'])
        try:
            arm_rt = _round_trips(env, [])
        finally:
            harness.stop_node(arm)
        echo = harness.start_node(env, [sys.executable, '-m', 'leap_teleop.bench.echo'])
        try:
            bare_rt = _round_trips(env, ['--echo'])
        finally:
            harness.stop_node(echo)
    arm_p99 = float(np.percentile(arm_rt, 99) * 1000)
    bare_p99 = float(np.percentile(bare_rt, 99) * 1000)
    print('  arm round trip p50 %.3f p99 %.3f ms; bare echo p50 %.3f p99 %.3f ms'
          % (np.percentile(arm_rt, 50) * 1000, arm_p99, np.percentile(bare_rt, 50) * 1000,
             bare_p99))
    return {'arm.latency_p99_ms': arm_p99, 'arm.latency_p99_over_bare_ms': arm_p99 - bare_p99}


def run():
    # arm.tracking_rms_m and the other motion figures: bench_arm_motion.
    return _latency()
