"""AR.Drone messages <-> the library's data, without a ROS master: the driver's navdata,
imu, mag and odometry that ardrone_sim publishes (DroneMessages), the pilot's input from a
Hand (pilot_input) and its cmd_vel (twist_msg)."""
from geometry_msgs.msg import Point, Twist, Vector3, Vector3Stamped
from nav_msgs.msg import Odometry
from sensor_msgs.msg import Imu

from leap_teleop.drone.pilot import PilotInput
from leap_teleop.msg import Navdata, navdata_altitude
from leap_teleop.ros.ardrone_interface import NAVDATA_ALTITUDE_SIZE, NAVDATA_ALTITUDE_TAG
from leap_teleop.ros.sensor_conversions import transform_msg

G_NAVDATA = 9.8                 # m/s^2 per g of navdata's ax / ay / az on ardrone/imu


class DroneMessages:
    """What ardrone_sim publishes each tick, from one drone.sim_runner.DroneReading:
    navdata (with the sensors), mag, imu, odometry, the TF odom -> body and the
    navdata_altitude option (built only when asked for)."""

    def __init__(self, reading, stamp, base_frame, odom_frame, with_altitude=False):
        r, nav = reading, reading.nav
        self.navdata = Navdata()
        self.navdata.header.stamp, self.navdata.header.frame_id = stamp, base_frame
        for key, value in nav.items():
            setattr(self.navdata, key, value)
        self.mag = Vector3Stamped(header=self.navdata.header,
                                  vector=Vector3(nav['magX'], nav['magY'], nav['magZ']))
        self.imu = Imu()
        self.imu.header.stamp, self.imu.header.frame_id = stamp, base_frame
        o = self.imu.orientation
        o.x, o.y, o.z, o.w = r.quat
        self.imu.angular_velocity = Vector3(*r.omega)
        self.imu.linear_acceleration = Vector3(nav['ax'] * G_NAVDATA, nav['ay'] * G_NAVDATA,
                                               nav['az'] * G_NAVDATA)
        self.odometry = Odometry()
        self.odometry.header.stamp, self.odometry.header.frame_id = stamp, odom_frame
        self.odometry.child_frame_id = base_frame
        pp = self.odometry.pose.pose
        pp.position = Point(r.pos[0], r.pos[1], r.altitude)
        pp.orientation = o
        self.odometry.twist.twist.linear = Vector3(nav['vx'] / 1000, nav['vy'] / 1000,
                                                   nav['vz'] / 1000)
        self.odometry.twist.twist.angular = Vector3(*r.omega)
        self.transform = transform_msg(odom_frame, base_frame,
                                       (r.pos[0], r.pos[1], r.altitude), r.quat, stamp)
        self.navdata_altitude = (navdata_altitude_msg(self.navdata.header, nav, r.altitude)
                                 if with_altitude else None)


def navdata_altitude_msg(header, nav, altitude):
    """The driver's altitude option: vision / raw / reference altitude (mm) are the sim's
    true one, the observer's state its altitude (m) and climb rate (m/s)."""
    out = navdata_altitude()
    out.header = header
    out.drone_time = nav['tm'] / 1e6
    out.tag, out.size = NAVDATA_ALTITUDE_TAG, NAVDATA_ALTITUDE_SIZE
    out.altitude_vision = out.altitude_raw = out.altitude_ref = nav['altd']
    out.altitude_vz = nav['vz']
    out.obs_accZ = nav['az'] * 9.81
    out.obs_alt = max(altitude, 0.0)
    out.obs_x.x, out.obs_x.y = max(altitude, 0.0), nav['vz'] / 1000.0
    out.est_vb.x = nav['vz'] / 1000.0
    return out


def pilot_input(msg):
    """The drone pilot's PilotInput from a leap_teleop/Hand (metres, unit vectors, the
    capture stamp in s)."""
    p, n, d = msg.palm_position, msg.palm_normal, msg.direction
    return PilotInput(msg.present, (p.x, p.y, p.z), (n.x, n.y, n.z), (d.x, d.y, d.z),
                      msg.header.stamp.to_sec())


def twist_msg(twist):
    """A geometry_msgs/Twist from (linear x, y, z, angular x, y, z)."""
    t = Twist()
    t.linear.x, t.linear.y, t.linear.z, t.angular.x, t.angular.y, t.angular.z = twist
    return t
