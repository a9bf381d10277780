"""TopicTypeWatch on the drone nodes' inputs: rospy drops a connection of another type
with a word only in the node's own log file. One RateLimitedLog serves them all (its
warnings are keyed by topic)."""
from geometry_msgs.msg import Twist
from std_msgs.msg import Empty

from leap_teleop.msg import GestureEvent, Hand, Navdata
from leap_teleop.ros.graph import TopicTypeWatch


def pilot_type_watches(hand_topic, gesture_topic, side, log):
    """drone_pilot's inputs: its Hand and GestureEvent topics and ardrone/navdata."""
    who = 'drone_pilot'
    return [
        TopicTypeWatch(hand_topic, Hand, who, 'the pilot (hand %s)' % side,
                       'no hand steers the drone; publish the sender\'s Hand there or set '
                       '~hand_topic', log),
        TopicTypeWatch(gesture_topic, GestureEvent, who, 'the pilot',
                       'no takeoff, land or flip; publish the sender\'s GestureEvent there or set '
                       '~gesture_topic', log),
        TopicTypeWatch('ardrone/navdata', Navdata, who, 'the pilot',
                       'the drone state is unknown (no takeoff, hover, then land); publish the '
                       'driver\'s (or ardrone_sim\'s) navdata there', log)]


def ardrone_sim_type_watches(log):
    """ardrone_sim's inputs: cmd_vel and the takeoff, land and reset topics."""
    who = 'ardrone_sim'
    watches = [TopicTypeWatch('cmd_vel', Twist, who, 'the simulated drone',
                              'the drone holds its last command; publish geometry_msgs/Twist '
                              'there', log)]
    for topic in ('takeoff', 'land', 'reset'):
        watches.append(TopicTypeWatch('ardrone/' + topic, Empty, who, 'the simulated drone',
                                      'no %s reaches the drone; publish std_msgs/Empty there'
                                      % topic, log))
    return watches
