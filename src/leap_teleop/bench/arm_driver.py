"""Benchmark driver for the arm node's latency (run as its own process).

Publishes joint_states and leapcobotright messages (arm, set the origin, then a palm
that moves on every message) and times each message until the first arm command with a
new target comes back. With --echo it times a bare rospy echo node instead (same two
hops, no teleop logic). Writes the round-trip times (s) as JSON.
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
from leap_teleop.ur10.kinematics import HOME_Q, JOINT_NAMES


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument('--count', type=int, default=500)
    ap.add_argument('--rate', type=float, default=50.0)
    ap.add_argument('--echo', action='store_true')
    ap.add_argument('--out', required=True)
    args = ap.parse_args(rospy.myargv()[1:])
    rospy.init_node('arm_bench_driver')
    hand_pub = rospy.Publisher('leapmotion/data_right', leapcobotright, queue_size=10,
                               tcp_nodelay=True)
    joints_pub = rospy.Publisher('ur10_1/joint_states', JointState, queue_size=10)
    got = threading.Event()
    last_q = [None]

    def on_command(msg):
        q = tuple(msg.points[0].positions) if msg.points else None
        if q != last_q[0]:
            last_q[0] = q
            got.set()

    def on_echo(_msg):
        got.set()

    if args.echo:
        rospy.Subscriber('bench/echo', leapcobotright, on_echo, tcp_nodelay=True)
    else:
        rospy.Subscriber('ur10_1/arm_controller/command', JointTrajectory, on_command,
                         tcp_nodelay=True)
    js = JointState(name=['ur10_1_' + n for n in JOINT_NAMES], position=list(HOME_Q))

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

    # Wait for the graph, then arm and set the origin.
    deadline = time.time() + 20
    while hand_pub.get_num_connections() == 0 and time.time() < deadline:
        time.sleep(0.05)
    time.sleep(1.0)
    for _ in range(20):
        hand_pub.publish(hand(0, thumb_up=True))
        time.sleep(0.01)
    for _ in range(20):
        hand_pub.publish(hand(0, set_origin_frame_detected=True))
        time.sleep(0.01)
    times = []
    for i in range(1, args.count + 1):
        got.clear()
        msg = hand(i)
        t0 = time.perf_counter()
        hand_pub.publish(msg)
        if got.wait(0.5):
            times.append(time.perf_counter() - t0)
        time.sleep(1.0 / args.rate)
    with open(args.out, 'w') as f:
        json.dump({'round_trip_s': times, 'sent': args.count}, f)


if __name__ == '__main__':
    main()
