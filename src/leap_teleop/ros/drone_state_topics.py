"""The simulated drone's state on the ardrone_autonomy driver's topics, every loop tick:
ardrone/navdata, mag, navdata_altitude (with ~enable_navdata_altitude), imu and odometry,
TF odom -> base (and the static camera frames), /clock in sim time (watched for a second
publisher); and two extras: the flown path (ardrone/path, bounded) and the latched drone
body of markers."""
import rospy
import tf2_ros
from geometry_msgs.msg import Vector3Stamped
from nav_msgs.msg import Odometry, Path
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import Imu
from visualization_msgs.msg import MarkerArray

from leap_teleop.drone.sim_runner import static_frames
from leap_teleop.msg import Navdata, navdata_altitude
from leap_teleop.ros.drone_conversions import DroneMessages
from leap_teleop.ros.graph import ClockRivalWatch
from leap_teleop.ros.markers import PathTrail, drone_markers
from leap_teleop.ros.sensor_conversions import transform_msg

# Published in this order each tick (DroneMessages' names).
STATE_TOPICS = (('navdata', Navdata), ('mag', Vector3Stamped), ('navdata_altitude', navdata_altitude),
                ('imu', Imu), ('odometry', Odometry))


class DroneStateTopics:
    """The publishers of a DroneReading, from the node's checked ~params `p`; `frames` are
    the runner's DroneFrames, `path_gate` its SendGate for the path."""

    def __init__(self, p, frames, path_gate, use_sim_time):
        self.frames, self.path_gate, self.use_sim_time = frames, path_gate, use_sim_time
        pub = rospy.Publisher
        self.pubs = {name: pub('ardrone/' + name, kind, queue_size=25) for name, kind in
                     STATE_TOPICS if name != 'navdata_altitude' or p['enable_navdata_altitude']}
        self.clock = pub('/clock', Clock, queue_size=10) if use_sim_time else None
        self.clock_watch = ClockRivalWatch('ardrone_sim') if use_sim_time else None
        self.tf = tf2_ros.TransformBroadcaster()
        self.static_tf = tf2_ros.StaticTransformBroadcaster()
        self.static_tf.sendTransform([transform_msg(*f, stamp=rospy.Time.now()) for f in
                                      static_frames(frames, p['world_frame'], p['odom_in_world'])])
        self.trail = PathTrail(int(p['path_length']), float(p['path_min_step']), frames.odom)
        self.path = pub('ardrone/path', Path, queue_size=2, latch=True)
        if p['markers']:
            self.markers = pub('ardrone/markers', MarkerArray, queue_size=1, latch=True)
            self.markers.publish(drone_markers(frames.base))

    def stamp(self, sim_time):
        """The header stamp of what the sim shows at `sim_time`: that time with
        /use_sim_time, else now."""
        return rospy.Time.from_sec(sim_time) if self.use_sim_time else rospy.Time.now()

    def publish(self, reading):
        stamp = self.stamp(reading.time)
        if self.clock is not None:
            self.clock.publish(Clock(clock=stamp))
        m = DroneMessages(reading, stamp, self.frames.base, self.frames.odom,
                          with_altitude='navdata_altitude' in self.pubs)
        for name, pub in self.pubs.items():
            pub.publish(getattr(m, name))
        self.tf.sendTransform(m.transform)
        if self.path_gate.period is not None:
            self.trail.add(stamp, (reading.pos[0], reading.pos[1], reading.altitude), reading.quat)
            if self.trail.changed and self.path_gate.open(stamp.to_sec()):
                self.path.publish(self.trail.to_msg(self.frames.odom, stamp))
                self.path_gate.sent(stamp.to_sec())
