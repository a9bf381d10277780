"""Benchmark driver for the arm node's latency (run as its own process).

Publishes joint_states and leapcobotright messages and times each message until its
reply comes back, in alternating rounds: the arm node (arm, set the origin, then a palm
that moves on every message; the reply is the first arm command with a new target), then
a bare rospy echo node (same two hops, no teleop logic). Each message waits for its own
reply (up to --reply-timeout s: slow replies stay in the tails; none later counts as
lost). Writes the per-round round-trip times (s) as JSON.
"""
import argparse
import json
import threading
import time

import rospy
from geometry_msgs.msg import Point
from sensor_msgs.msg import JointState
from trajectory_msgs.msg import JointTrajectory

from leap_teleop.msg import leapcobotright
from leap_teleop.ros.signals import init_node
from leap_teleop.ur10.kinematics import HOME_Q, JOINT_NAMES


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument('--rounds', type=int, default=10)
    ap.add_argument('--count', type=int, default=150, help='messages per round and node')
    ap.add_argument('--rate', type=float, default=50.0)
    ap.add_argument('--reply-timeout', type=float, default=5.0)
    ap.add_argument('--out', required=True)
    args = ap.parse_args(rospy.myargv()[1:])
    init_node('arm_bench_driver')
    pubs = {'arm': rospy.Publisher('leapmotion/data_right', leapcobotright, queue_size=10,
                                   tcp_nodelay=True),
            'bare': rospy.Publisher('bench/echo_in', leapcobotright, queue_size=10,
                                    tcp_nodelay=True)}
    joints_pub = rospy.Publisher('ur10_1/joint_states', JointState, queue_size=10)
    got = {'arm': threading.Event(), 'bare': threading.Event()}
    last_q = [None]
    js = JointState(name=['ur10_1_' + n for n in JOINT_NAMES], position=list(HOME_Q))

    def on_command(msg):
        q = tuple(msg.points[0].positions) if msg.points else None
        if q != last_q[0]:
            last_q[0] = q
            got['arm'].set()
        if q is not None:       # the robot follows (a robot that does not is disarmed)
            js.position = list(q)

    rospy.Subscriber('bench/echo', leapcobotright, lambda _m: got['bare'].set(),
                     tcp_nodelay=True)
    rospy.Subscriber('ur10_1/arm_controller/command', JointTrajectory, on_command,
                     tcp_nodelay=True)

    def publish_joints():
        while not rospy.is_shutdown():
            js.header.stamp = rospy.Time.now()
            joints_pub.publish(js)
            time.sleep(0.008)
    threading.Thread(target=publish_joints, daemon=True).start()

    def hand(i, **flags):
        msg = leapcobotright(is_right_hand=True)
        msg.right_hand_palmpos = Point(0.1 * (i % 200), 250.0, 0.0)
        for k, v in flags.items():
            setattr(msg, 'right_hand_' + k, v)
        msg.header.stamp = rospy.Time.now()
        return msg

    deadline = time.time() + 20
    while any(p.get_num_connections() == 0 for p in pubs.values()) and time.time() < deadline:
        time.sleep(0.05)
    time.sleep(1.0)
    rounds = {'arm': [], 'bare': []}
    lost = {'arm': 0, 'bare': 0}
    i = 0
    for _ in range(args.rounds):
        for node in ('arm', 'bare'):
            if node == 'arm':       # (re-)arm: the watchdog disarmed it during the bare round
                # 0.5 s each: arming needs the thumbs-up held arm_hold_s (0.3 s by default)
                for flags in ({'thumb_up': True}, {'set_origin_frame_detected': True}):
                    for _ in range(50):
                        pubs['arm'].publish(hand(i, **flags))
                        time.sleep(0.01)
                time.sleep(0.2)
            times = []
            for _ in range(args.count):
                i += 1
                got[node].clear()
                msg = hand(i)
                t0 = time.perf_counter()
                pubs[node].publish(msg)
                if got[node].wait(args.reply_timeout):
                    times.append(time.perf_counter() - t0)
                else:
                    lost[node] += 1
                time.sleep(1.0 / args.rate)
            rounds[node].append(times)
    with open(args.out, 'w') as f:
        json.dump({'rounds': rounds, 'lost': lost, 'count': args.count}, f)


if __name__ == '__main__':
    main()
