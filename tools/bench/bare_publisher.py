"""The baseline for latency figures: a bare rospy publisher of leapcobotright at a
fixed rate, stamped at publish time, with nothing else in the process.

usage: python -m tools.bench.bare_publisher --rate HZ [--topic T]
"""
import argparse
import time

import rospy

from leap_teleop.msg import leapcobotright
from leap_teleop.ros.signals import closed_at_shutdown, init_node


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument('--rate', type=float, required=True)
    ap.add_argument('--topic', default='leapmotion/data_right')
    args = ap.parse_args(rospy.myargv()[1:])
    init_node('bare_publisher')
    pub = rospy.Publisher(args.topic, leapcobotright, queue_size=200)
    period = 1.0 / args.rate
    msg = leapcobotright(is_right_hand=True)
    t0, k = time.monotonic(), 0
    with closed_at_shutdown():
        while not rospy.is_shutdown():
            delay = t0 + k * period - time.monotonic()
            if delay > 0:
                time.sleep(delay)
            msg.header.stamp = rospy.Time.from_sec(time.time())
            pub.publish(msg)
            k += 1


if __name__ == '__main__':
    main()
