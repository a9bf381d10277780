"""Bare rospy echo: republish each leapcobotright at once (the latency baseline)."""
import rospy

from leap_teleop.msg import leapcobotright


def main():
    rospy.init_node('bench_echo')
    pub = rospy.Publisher('bench/echo', leapcobotright, queue_size=10, tcp_nodelay=True)
    rospy.Subscriber('leapmotion/data_right', leapcobotright, pub.publish, tcp_nodelay=True)
    rospy.spin()


if __name__ == '__main__':
    main()
