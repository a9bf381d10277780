"""Drone benchmarks.

sim.drone_rtf         headless ArDroneSim real-time factor over a mixed flight (takeoff,
                      hover, tilts, yaw, a flip, landing) at the default 200 Hz physics.
pilot.latency_p99_ms  Hand message -> cmd_vel: a client process publishes Hand at 120 Hz
                      (each with a distinct palm offset, hence a distinct linear.x) to the
                      pilot node in another process and times the matching cmd_vel back.
                      Includes both hops (Hand to the pilot, cmd_vel back), so it is an
                      upper bound of the pilot's own delay. Also pilot.latency_p50_ms.
"""
import argparse
import json
import os
import sys
import tempfile
import time

import numpy as np

from leap_teleop.bench import harness

LATENCY_SECONDS = 10.0
HAND_RATE = 120.0


def sim_rtf():
    from leap_teleop.drone.sim import ArDroneSim, FLIP_AHEAD
    drone = ArDroneSim()
    try:
        t0 = time.perf_counter()
        drone.takeoff()
        drone.advance(4.0)
        for cmd in ((0.5, 0, 0, 0, 0, 0), (0, 0, 0, 0, 0, 0), (0, -0.5, 0.3, 0, 0, 0.5),
                    (0, 0, 0, 0, 0, 0)):
            drone.set_cmd_vel(*cmd)
            drone.advance(3.0)
        drone.flight_animation(FLIP_AHEAD, 0)
        drone.advance(4.0)
        drone.land()
        drone.advance(4.0)
        wall = time.perf_counter() - t0
        return drone.time / wall
    finally:
        drone.close()


def latency_client(out, seconds):
    """Runs in its own process: publish Hand, time the cmd_vel that answers each."""
    import rospy
    from geometry_msgs.msg import Twist
    from leap_teleop.msg import GestureEvent, Hand

    rospy.init_node('bench_drone_client', disable_signals=True)
    hand_pub = rospy.Publisher('leapmotion/hand_right', Hand, queue_size=10, tcp_nodelay=True)
    gesture_pub = rospy.Publisher('leapmotion/gestures', GestureEvent, queue_size=10)
    sent, answered, latencies = {}, set(), []

    def on_twist(msg):
        now = time.perf_counter()
        k = int(round(msg.linear.x * 1000))
        if k in sent and k not in answered:
            answered.add(k)
            latencies.append(now - sent[k])

    rospy.Subscriber('cmd_vel', Twist, on_twist, queue_size=1000, tcp_nodelay=True)
    deadline = time.monotonic() + 30
    while time.monotonic() < deadline and (hand_pub.get_num_connections() == 0
                                           or gesture_pub.get_num_connections() == 0):
        time.sleep(0.05)

    def hand(z):
        h = Hand()
        h.header.stamp = rospy.Time.now()
        h.side, h.present = Hand.SIDE_RIGHT, True
        h.palm_position.y, h.palm_position.z = 0.2, z
        h.palm_normal.y, h.direction.z = -1.0, -1.0
        return h

    for i in range(120):                   # the reference hand, engaged by an unfold
        hand_pub.publish(hand(0.0))
        if i == 40:
            gesture_pub.publish(GestureEvent(side=GestureEvent.SIDE_RIGHT, gesture='unfold',
                                             active=True))
        time.sleep(1.0 / HAND_RATE)
    n = int(seconds * HAND_RATE)
    t_next = time.perf_counter()
    for i in range(n):
        # Default tilt mapping: linear.x = (|z| - 0.03) / 0.10 = k / 1000, k = 100..899.
        k = 100 + i % 800
        msg = hand(-(0.03 + k / 1000.0 * 0.10))
        answered.discard(k)
        sent[k] = time.perf_counter()
        hand_pub.publish(msg)
        t_next += 1.0 / HAND_RATE
        delay = t_next - time.perf_counter()
        if delay > 0:
            time.sleep(delay)
    time.sleep(0.3)
    rospy.signal_shutdown('done')
    with open(out, 'w') as f:
        json.dump({'sent': n, 'latency_s': latencies}, f)


def pilot_latency():
    with harness.ros_master() as env:
        pilot = harness.start_node(env, [sys.executable, '-c',
                                         'from leap_teleop.nodes.drone_pilot import main; main()'])
        with tempfile.NamedTemporaryFile(suffix='.json', delete=False) as f:
            out = f.name
        try:
            subprocess_run([sys.executable, '-m', 'leap_teleop.bench.bench_drone',
                            '--latency-client', out, '--seconds', str(LATENCY_SECONDS)], env)
            with open(out) as f:
                data = json.load(f)
        finally:
            harness.stop_node(pilot)
            os.unlink(out)
    lat = data['latency_s']
    if len(lat) < 0.5 * data['sent']:
        raise RuntimeError('pilot answered only %d of %d hand messages' % (len(lat), data['sent']))
    p50, p99 = harness.percentiles_ms(lat)
    return p50, p99, len(lat) / float(data['sent'])


def subprocess_run(args, env):
    import subprocess
    subprocess.run(args, env=env, check=True, timeout=LATENCY_SECONDS + 90)


def run():
    rtf = sim_rtf()
    p50, p99, answered = pilot_latency()
    return {'sim.drone_rtf': rtf, 'pilot.latency_p50_ms': p50, 'pilot.latency_p99_ms': p99,
            'pilot.answered_fraction': answered}


if __name__ == '__main__':
    ap = argparse.ArgumentParser()
    ap.add_argument('--latency-client', metavar='OUT')
    ap.add_argument('--seconds', type=float, default=LATENCY_SECONDS)
    a = ap.parse_args()
    if a.latency_client:
        latency_client(a.latency_client, a.seconds)
    else:
        print(json.dumps(run(), indent=1))
