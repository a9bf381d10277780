"""Bare rospy echo: republish each leapcobotright from bench/echo_in on bench/echo at once
(the latency baseline; its own input topic, so the arm node next to it sees none of it)."""
import rospy

from leap_teleop.msg import leapcobotright
from leap_teleop.ros.signals import init_node


def main():
    init_node('bench_echo')
    pub = rospy.Publisher('bench/echo', leapcobotright, queue_size=10, tcp_nodelay=True)
    rospy.Subscriber('bench/echo_in', leapcobotright, pub.publish, tcp_nodelay=True)
    rospy.spin()


if __name__ == '__main__':
    main()
