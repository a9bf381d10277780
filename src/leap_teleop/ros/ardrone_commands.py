"""The pilot's side of the ardrone_autonomy driver: the cmd_vel, ardrone/takeoff and
ardrone/land publishers and the ardrone/setflightanimation client."""
import time

import rospy
from geometry_msgs.msg import Twist
from std_msgs.msg import Empty

from leap_teleop.control.input_age import InputAgeWindow
from leap_teleop.drone.one_shot import HeldOneShot
from leap_teleop.drone.pilot import FLIP_NOT_CALLED
from leap_teleop.ros import drone_conversions
from leap_teleop.srv import FlightAnim


class ArdroneCommands:
    """send(cmd) publishes a pilot Command and never blocks; a takeoff or land with no
    subscriber yet is held (see HeldOneShot) and send_held() sends it later; flip() calls
    the service and may block (run it on a thread of its own). `twists` counts the Twists
    sent; input_age keeps the age of the hand input behind each command sent. Every method
    but flip runs on the sending thread only."""

    def __init__(self, service_timeout, takeoff_hold, takeoff_wanted, warn):
        self.cmd_vel = rospy.Publisher('cmd_vel', Twist, queue_size=10)
        self.one_shot_pubs = {'takeoff': rospy.Publisher('ardrone/takeoff', Empty, queue_size=2),
                              'land': rospy.Publisher('ardrone/land', Empty, queue_size=2)}
        self.one_shot = HeldOneShot(
            self._publish_one_shot, lambda kind: self.one_shot_pubs[kind].get_num_connections() > 0,
            takeoff_hold, takeoff_wanted, warn=warn)
        self.flight_animation = rospy.ServiceProxy('ardrone/setflightanimation', FlightAnim)
        self.service_timeout = service_timeout
        self.twists = 0
        self.input_age = InputAgeWindow()

    def send(self, cmd):
        """Publish one Command: a twist, takeoff or land."""
        if cmd.kind == 'twist':
            self.cmd_vel.publish(drone_conversions.twist_msg(cmd.twist))
            self.twists += 1
            self.input_age.add(rospy.get_time(), cmd.input_stamp)
        elif cmd.kind in self.one_shot_pubs:
            self.one_shot.send(cmd)

    def flush(self, timeout):
        """Wait (up to `timeout` s) until rospy's sender threads have written every queued
        cmd_vel: an ending pilot's last hover must not be dropped with its connections."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline and any(
                getattr(c, '_queue', None) for c in self.cmd_vel.impl.connections):
            time.sleep(0.005)
        time.sleep(0.02)            # taken off the queue, then written

    def send_held(self):
        """A held takeoff or land, once its driver listens (call this often)."""
        self.one_shot.send_held()

    def diagnostic_values(self):
        return [('twists published', self.twists),
                ('takeoff / land held for the driver', self.one_shot.held),
                ('held takeoffs dropped (too late or withdrawn)', self.one_shot.dropped)]

    def _publish_one_shot(self, cmd, waited):
        rospy.loginfo('%s: %s%s', rospy.get_name().lstrip('/'), cmd.kind, '' if waited is None else
                      ' (sent after waiting %.2f s for the driver)' % waited)
        self.one_shot_pubs[cmd.kind].publish(Empty())
        self.input_age.add(rospy.get_time(), cmd.input_stamp)

    def flip(self, anim_type, duration, still_wanted=None):
        """The flight animation service's result: waits up to service_timeout for the
        service, then for its answer. `still_wanted()` is asked once the service is there:
        a land or a lost hand meanwhile must not be followed by a flip."""
        self.flight_animation.wait_for_service(self.service_timeout)
        if still_wanted is not None and not still_wanted():
            return FLIP_NOT_CALLED
        return self.flight_animation(anim_type, duration).result
