"""Arm teleop: latency of the real node against a bare rospy echo, and tracking error
of the closed loop on the simulated cell (sim profile: max_joint_speed 1 rad/s)."""
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
            '_joint_prefix:=ur10_1_'])
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


def _tracking():
    from leap_teleop.teleop.closed_loop import run_session
    sys.path.insert(0, package_path('test'))
    from test_arm_closed_loop import sim_params   # the same profile the tests use
    cell, runs = run_session(package_path('config', 'gestures', 'ur10_pick_place_single.yaml'),
                             'ur10_cell.yaml', {'ur10_1': 'right'}, sim_params())
    cell.close()
    errors = np.asarray(runs['ur10_1'].tracking_errors)
    return {'arm.tracking_rms_m': float(np.sqrt(np.mean(errors ** 2)))}


def run():
    results = _latency()
    results.update(_tracking())
    return results
