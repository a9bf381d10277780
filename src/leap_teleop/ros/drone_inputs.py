"""The drone nodes' subscriptions, each with its type watched: rospy drops a connection of
another type with a word only in the node's own log file."""
import rospy
from geometry_msgs.msg import Twist
from std_msgs.msg import Empty

from leap_teleop.msg import GestureEvent, Hand, Navdata
from leap_teleop.ros.graph import TopicTypeWatch


def subscribe_pilot_inputs(hand_topic, gesture_topic, side, on_gesture, on_navdata, log):
    """drone_pilot's GestureEvent topic and ardrone/navdata; its Hand topic (subscribed by its
    HandSubscription) is watched too. Returns the TopicTypeWatch."""
    watch = TopicTypeWatch(rospy.get_name().lstrip('/'), log)
    watch.add(hand_topic, Hand, 'the pilot (hand %s)' % side,
              'no hand steers the drone; publish the sender\'s Hand there or set ~hand_topic')
    watch.subscribe(gesture_topic, GestureEvent, on_gesture, 'the pilot',
                    'no takeoff, land or flip; publish the sender\'s GestureEvent there or set '
                    '~gesture_topic', queue_size=50)
    watch.subscribe('ardrone/navdata', Navdata, on_navdata, 'the pilot',
                    'the drone state is unknown (no takeoff, hover, then land); publish the '
                    'driver\'s (or ardrone_sim\'s) navdata there', queue_size=5)
    return watch


def subscribe_ardrone_sim_inputs(sim, call, log):
    """ardrone_sim's cmd_vel and its takeoff, land and reset topics: each message becomes
    call(sim's method, its arguments). Returns the TopicTypeWatch."""
    watch = TopicTypeWatch('ardrone_sim', log)

    def on_cmd_vel(m):
        call(sim.set_cmd_vel, m.linear.x, m.linear.y, m.linear.z,
             m.angular.x, m.angular.y, m.angular.z)
    watch.subscribe('cmd_vel', Twist, on_cmd_vel, 'the simulated drone',
                    'the drone holds its last command; publish geometry_msgs/Twist there',
                    queue_size=10)
    for topic, command in (('takeoff', sim.takeoff), ('land', sim.land), ('reset', sim.reset)):
        watch.subscribe('ardrone/' + topic, Empty, lambda _, c=command: call(c),
                        'the simulated drone',
                        'no %s reaches the drone; publish std_msgs/Empty there' % topic)
    return watch
