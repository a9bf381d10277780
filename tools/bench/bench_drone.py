"""Drone benchmarks.

sim.drone_rtf         headless ArDroneSim real-time factor over a mixed flight (takeoff,
                      hover, tilts, yaw, a flip, landing) at the default 200 Hz physics.
sim.drone_rtf_cameras the same flight while both cameras render at the node's default
                      rates (front 640x360, bottom 320x240; the node's camera thread and
                      renderer process, poses copied under a lock as in the node).
                      sim.camera_front_hz / sim.camera_bottom_hz: the rates achieved while
                      the flight runs in real time as in the node (and
                      sim.drone_rtf_realtime_cameras, 1.0 when real time held); the
                      *_at_full_speed rates: while the flight runs as fast as possible.
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
import threading
import time

from tools.bench import ros_processes

LATENCY_SECONDS = 10.0
CAMERA_WALL_S = 10.0       # wall time of the camera run (flights repeated), for the rates
HAND_RATE = 120.0


def sim_rtf(rates=None, min_wall_s=0.0, paced=False):
    """Physics real-time factor of the mixed flight (repeated until `min_wall_s` of wall
    time has passed); with camera `rates` (Hz per camera) the cameras render meanwhile.
    `paced`: the flight runs in real time as in the node (sleeping between chunks).
    Returns (rtf, {camera: frames per wall second})."""
    import threading

    from leap_teleop.drone.cameras import CameraLoop
    from leap_teleop.drone.sim import ArDroneSim
    drone = ArDroneSim()
    lock = threading.Lock()

    def pose():
        with lock:
            return drone.pos, drone.quat, None

    loop = CameraLoop(rates or {}, pose, lambda name, rgb, ctx: None)
    loop.start()
    if loop.thread is not None:             # renderer up and warm before the clock starts
        loop.ready.wait(60.0)
    try:
        frames0 = dict(loop.frames)
        sim_s, t0 = 0.0, time.perf_counter()
        while True:
            drone.reset_state()
            _flight(drone, lock, (t0, sim_s) if paced else None)
            sim_s += drone.time
            wall = time.perf_counter() - t0
            if wall >= min_wall_s:
                break
        return sim_s / wall, {n: (loop.frames[n] - frames0[n]) / wall for n in loop.rates}
    finally:
        loop.stop()
        drone.close()


def _flight(drone, lock, pace=None):
    """Takeoff, tilts, yaw, climb, a flip, landing: 24 s of flight in 0.1 s chunks, each
    under the lock the camera thread takes to copy the pose (as in the node). With
    `pace` = (wall start, sim seconds flown before) each chunk waits for the wall clock."""
    from leap_teleop.drone.sim import FLIP_AHEAD

    def advance(seconds):
        for _ in range(int(round(seconds / 0.1))):
            with lock:
                drone.advance(0.1)
            if pace is not None:
                delay = pace[0] + pace[1] + drone.time - time.perf_counter()
                if delay > 0:
                    time.sleep(delay)

    drone.takeoff()
    advance(4.0)
    for cmd in ((0.5, 0, 0, 0, 0, 0), (0, 0, 0, 0, 0, 0), (0, -0.5, 0.3, 0, 0, 0.5),
                (0, 0, 0, 0, 0, 0)):
        drone.set_cmd_vel(*cmd)
        advance(3.0)
    drone.flight_animation(FLIP_AHEAD, 0)
    advance(4.0)
    drone.land()
    advance(4.0)


def latency_client(out, seconds):
    """Runs in its own process: publish Hand, time the cmd_vel that answers each."""
    import rospy
    from geometry_msgs.msg import Twist
    from std_msgs.msg import Header

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
    # A flying drone's navdata at the driver's 50 Hz: without fresh navdata the pilot
    # sends nothing beyond hover.
    from leap_teleop.msg import Navdata
    nav_pub = rospy.Publisher('ardrone/navdata', Navdata, queue_size=10)

    def navdata_loop():
        while not rospy.is_shutdown():
            try:
                nav_pub.publish(Navdata(header=Header(stamp=rospy.Time.now()), state=3,
                                        altd=1000, batteryPercent=90.0))
            except rospy.ROSException:          # closed at shutdown
                return
            time.sleep(0.02)
    threading.Thread(target=navdata_loop, daemon=True).start()
    deadline = time.monotonic() + 30
    while time.monotonic() < deadline and (hand_pub.get_num_connections() == 0
                                           or gesture_pub.get_num_connections() == 0
                                           or nav_pub.get_num_connections() == 0):
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
    with ros_processes.ros_master() as env:
        pilot = ros_processes.spawn_node(env, [sys.executable, '-c',
                                         'from leap_teleop.ros.nodes.drone_pilot import main; main()'])
        with tempfile.NamedTemporaryFile(suffix='.json', delete=False) as f:
            out = f.name
        try:
            subprocess_run([sys.executable, '-m', 'tools.bench.bench_drone',
                            '--latency-client', out, '--seconds', str(LATENCY_SECONDS)], env)
            with open(out) as f:
                data = json.load(f)
        finally:
            ros_processes.stop_spawned(pilot)
            os.unlink(out)
    lat = data['latency_s']
    if len(lat) < 0.5 * data['sent']:
        raise RuntimeError('pilot answered only %d of %d hand messages' % (len(lat), data['sent']))
    p50, p99 = ros_processes.percentiles_ms(lat)
    return p50, p99, len(lat) / float(data['sent'])


def subprocess_run(args, env):
    import subprocess
    subprocess.run(args, env=env, check=True, timeout=LATENCY_SECONDS + 90)


def camera_rates():
    from leap_teleop.drone.sim_runner import BOTTOM_RATE, FRONT_RATE
    return {'front': FRONT_RATE, 'bottom': BOTTOM_RATE}


def cameras_figures(rates=None):
    """Both cameras at `rates` (default: the node's): the RTF of the flight run as fast as
    possible, then the camera rates achieved while it flies in real time (as in the node)
    and the RTF it kept meanwhile (1.0 = real time held)."""
    rates = rates or camera_rates()
    rtf, achieved_fast = sim_rtf(rates, CAMERA_WALL_S)
    rtf_paced, achieved = sim_rtf(rates, CAMERA_WALL_S, paced=True)
    return {'sim.drone_rtf_cameras': rtf,
            'sim.camera_front_hz': achieved.get('front', 0.0),
            'sim.camera_bottom_hz': achieved.get('bottom', 0.0),
            'sim.drone_rtf_realtime_cameras': rtf_paced,
            'sim.camera_front_hz_at_full_speed': achieved_fast.get('front', 0.0),
            'sim.camera_bottom_hz_at_full_speed': achieved_fast.get('bottom', 0.0)}


def run():
    rtf, _ = sim_rtf()
    p50, p99, answered = pilot_latency()
    out = {'sim.drone_rtf': rtf}
    out.update(cameras_figures())
    out.update({'pilot.latency_p50_ms': p50, 'pilot.latency_p99_ms': p99,
                'pilot.answered_fraction': answered})
    return out


if __name__ == '__main__':
    ap = argparse.ArgumentParser()
    ap.add_argument('--latency-client', metavar='OUT')
    ap.add_argument('--seconds', type=float, default=LATENCY_SECONDS)
    ap.add_argument('--cameras', metavar='FRONT_HZ,BOTTOM_HZ',
                    help='only the camera figures, at these rates (default: the node\'s)')
    a = ap.parse_args()
    if a.cameras:
        front, bottom = (float(v) for v in a.cameras.split(','))
        print(json.dumps(cameras_figures({'front': front, 'bottom': bottom}), indent=1))
    elif a.latency_client:
        latency_client(a.latency_client, a.seconds)
    else:
        print(json.dumps(run(), indent=1))
