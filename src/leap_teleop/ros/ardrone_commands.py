"""The pilot's side of the ardrone_autonomy driver: the cmd_vel, ardrone/takeoff and
ardrone/land publishers and the ardrone/setflightanimation client."""
import rospy
from geometry_msgs.msg import Twist
from std_msgs.msg import Empty

from leap_teleop.control.input_age import InputAgeWindow
from leap_teleop.ros import conversions
from leap_teleop.srv import FlightAnim


class ArdroneCommands:
    """send(cmd) publishes a pilot Command and never blocks; flip() calls the service and
    may block (run it on a thread of its own). `twists` counts the Twists sent; input_age
    keeps the age of the hand input behind each command sent (the sending thread only)."""

    def __init__(self, service_timeout):
        self.cmd_vel = rospy.Publisher('cmd_vel', Twist, queue_size=10)
        self.takeoff = rospy.Publisher('ardrone/takeoff', Empty, queue_size=2)
        self.land = rospy.Publisher('ardrone/land', Empty, queue_size=2)
        self.flight_animation = rospy.ServiceProxy('ardrone/setflightanimation', FlightAnim)
        self.service_timeout = service_timeout
        self.twists = 0
        self.input_age = InputAgeWindow()

    def send(self, cmd):
        """Publish one Command: a twist, takeoff or land."""
        if cmd.kind == 'twist':
            self.cmd_vel.publish(conversions.twist_msg(cmd.twist))
            self.twists += 1
        elif cmd.kind == 'takeoff':
            rospy.loginfo('pilot: takeoff')
            self.takeoff.publish(Empty())
        elif cmd.kind == 'land':
            rospy.loginfo('pilot: land')
            self.land.publish(Empty())
        self.input_age.add(rospy.get_time(), cmd.input_stamp)

    def flip(self, anim_type, duration):
        """The flight animation service's result: waits up to service_timeout for the
        service, then for its answer."""
        self.flight_animation.wait_for_service(self.service_timeout)
        return self.flight_animation(anim_type, duration).result
