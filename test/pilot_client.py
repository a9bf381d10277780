"""Client code (for `python -c`) that plays the rest of the graph beside a drone_pilot
node: after rospy.init_node, PILOT_FEED streams a right hand at state['palm'] (m) and
navdata of state['nav'] at 50 Hz on a thread of its own, and offers gesture_pub.
PILOT_FLYING then (with a `twist_sub` on cmd_vel defined first) waits until the pilot is
connected both ways, unfolds and reports the drone flying; it offers wait_until."""

PILOT_FEED = r'''
import threading, time
from leap_teleop.msg import GestureEvent, Hand, Navdata
state = {'nav': 2, 'palm': (0.0, 0.2, 0.0)}
hand_pub = rospy.Publisher('leapmotion/hand_right', Hand, queue_size=10)
nav_pub = rospy.Publisher('ardrone/navdata', Navdata, queue_size=10)
gesture_pub = rospy.Publisher('leapmotion/gestures', GestureEvent, queue_size=10)

def feed():
    while not rospy.is_shutdown():
        h = Hand(side=0, present=True)
        h.header.stamp = rospy.Time.now()
        h.palm_position.x, h.palm_position.y, h.palm_position.z = state['palm']
        h.palm_normal.y, h.direction.z = -1.0, -1.0
        hand_pub.publish(h)
        nav_pub.publish(Navdata(state=state['nav'], altd=1000))
        time.sleep(0.02)

threading.Thread(target=feed, daemon=True).start()
'''

PILOT_FLYING = r'''
def wait_until(ok, what, timeout=30.0):
    # conditions, not fixed sleeps: on a loaded machine connections form late
    deadline = time.monotonic() + timeout
    while not ok():
        if time.monotonic() > deadline:
            raise SystemExit('timed out waiting for ' + what)
        time.sleep(0.02)

wait_until(lambda: min(c.get_num_connections() for c in (hand_pub, nav_pub, gesture_pub, twist_sub))
           > 0, 'the pilot connected both ways')
gesture_pub.publish(GestureEvent(side=0, gesture='unfold', active=True))
time.sleep(0.5)
state['nav'] = 3
'''
