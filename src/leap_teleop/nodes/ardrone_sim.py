"""ardrone_sim: a simulated AR.Drone 2.0 behind the ardrone_autonomy driver's interface.

Subscribes cmd_vel (Twist), ardrone/takeoff, ardrone/land, ardrone/reset (Empty);
publishes ardrone/navdata (leap_teleop/Navdata, the driver's MD5), ardrone/imu,
ardrone/odometry and TF odom -> ardrone_base_link (+ static front / bottom camera
frames) at ~looprate, the flown path (nav_msgs/Path, ardrone/path, bounded) at ~path_rate
and, latched, a drone body of primitive markers (ardrone/markers) for RViz; serves
ardrone/setflightanimation (FlightAnim) and ardrone/snapshot (std_srvs/Trigger: writes a PNG, returns its path). With
/use_sim_time true it publishes /clock and can run faster than real time.
"""
import math
import os
import threading
import time

import rospy
import tf2_ros
from geometry_msgs.msg import TransformStamped
from nav_msgs.msg import Odometry, Path
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import Imu
from std_msgs.msg import Empty
from std_srvs.srv import Trigger, TriggerResponse
from geometry_msgs.msg import Twist
from visualization_msgs.msg import MarkerArray

from leap_teleop.drone.sim import ArDroneSim, DroneParams, STATE_NAMES
from leap_teleop.msg import Navdata
from leap_teleop.nodes.common import Param, start_node
from leap_teleop.srv import FlightAnim, FlightAnimResponse
from leap_teleop.visualization import PathTrail, drone_markers

_D = DroneParams()
PARAMS = {
    'euler_angle_max': Param(_D.euler_angle_max, 'max tilt for linear.x/y = 1 (driver)',
                             unit='rad', gt=0.0, le=0.52),
    'control_vz_max': Param(_D.control_vz_max, 'climb rate for linear.z = 1 (driver)',
                            unit='mm/s', gt=0.0, le=2000.0),
    'control_yaw': Param(_D.control_yaw, 'yaw rate for angular.z = 1 (driver)',
                         unit='rad/s', gt=0.0, le=6.11),
    'altitude_max': Param(_D.altitude_max, 'altitude ceiling (driver)', unit='mm',
                          gt=0.0, le=100000.0),
    'altitude_min': Param(_D.altitude_min, 'altitude floor while flying (driver)',
                          unit='mm', ge=0.0, le=100000.0),
    'looprate': Param(50.0, 'navdata / imu / odometry / TF rate (driver)', unit='Hz',
                      ge=5.0, le=1000.0),
    'takeoff_altitude': Param(_D.takeoff_altitude, 'where a takeoff levels off', unit='m',
                              gt=0.0, le=10.0),
    'physics_rate': Param(_D.physics_rate, 'physics and onboard controller rate', unit='Hz',
                          ge=50.0, le=2000.0),
    'battery_flight_time': Param(_D.battery_flight_time, 'hover time on a full battery',
                                 unit='s', gt=0.0, le=100000.0),
    'link_timeout': Param(_D.link_timeout, 'no command this long -> land (firmware link '
                                           'loss); 0 = off, as with a live driver', unit='s',
                          ge=0.0, le=60.0),
    'gui': Param(False, 'open the PyBullet GUI window'),
    'realtime_factor': Param(1.0, 'sim speed vs wall time; 0 = as fast as possible '
                                  '(only sensible with /use_sim_time)', ge=0.0, le=100.0),
    'snapshot_dir': Param('', 'where ardrone/snapshot writes PNGs (default ROS_HOME or /tmp)'),
    'snapshot_size': Param([640, 480], 'snapshot width, height', unit='px', length=2,
                           ge=16, le=4096),
    'base_frame': Param('ardrone_base_link', 'drone body frame', empty_ok=False),
    'odom_frame': Param('odom', 'odometry frame', empty_ok=False),
    'start_xy': Param([0.0, 0.0], 'start position in odom', unit='m', length=2,
                      ge=-1000.0, le=1000.0),
    'path_length': Param(2000, 'poses kept in ardrone/path (oldest dropped)', ge=1,
                         le=100000),
    'path_min_step': Param(0.02, 'moved this far before the path gets a new pose', unit='m',
                           ge=0.0, le=100.0),
    'path_rate': Param(5.0, 'ardrone/path publish rate (only when it changed); 0 = off',
                       unit='Hz', ge=0.0, le=100.0),
    'markers': Param(True, 'publish the drone body markers on ardrone/markers (latched)'),
    'world_frame': Param('', 'if set, publish a static TF world_frame -> odom_frame '
                             '(so RViz can show the hands next to the drone)'),
    'odom_in_world': Param([1.0, 0.0, 0.0], 'odom_frame origin in world_frame', unit='m',
                           length=3, ge=-1000.0, le=1000.0),
}


class ArDroneSimNode:
    def __init__(self, p):
        self.p = p
        names = ('euler_angle_max', 'control_vz_max', 'control_yaw', 'altitude_max',
                 'altitude_min', 'takeoff_altitude', 'physics_rate', 'battery_flight_time',
                 'link_timeout')
        self.sim = ArDroneSim({k: p[k] for k in names}, gui=bool(p['gui']),
                              warn=lambda key, text: rospy.logwarn('ardrone_sim: %s', text),
                              start_xyz=tuple(p['start_xy']))
        self.lock = threading.Lock()
        self.use_sim_time = bool(rospy.get_param('/use_sim_time', False))
        self.base, self.odom = p['base_frame'], p['odom_frame']
        self.nav_pub = rospy.Publisher('ardrone/navdata', Navdata, queue_size=25)
        self.imu_pub = rospy.Publisher('ardrone/imu', Imu, queue_size=25)
        self.odom_pub = rospy.Publisher('ardrone/odometry', Odometry, queue_size=25)
        self.clock_pub = (rospy.Publisher('/clock', Clock, queue_size=10)
                          if self.use_sim_time else None)
        self.tf = tf2_ros.TransformBroadcaster()
        self.static_tf = tf2_ros.StaticTransformBroadcaster()
        self._publish_camera_frames()
        self.trail = PathTrail(int(p['path_length']), float(p['path_min_step']))
        self.path_period = 1.0 / float(p['path_rate']) if float(p['path_rate']) > 0 else None
        self._path_sent = None
        self.path_pub = rospy.Publisher('ardrone/path', Path, queue_size=2, latch=True)
        if p['markers']:
            self.marker_pub = rospy.Publisher('ardrone/markers', MarkerArray, queue_size=1,
                                              latch=True)
            self.marker_pub.publish(drone_markers(self.base))
        rospy.Subscriber('cmd_vel', Twist, self.on_cmd_vel, queue_size=10)
        rospy.Subscriber('ardrone/takeoff', Empty, lambda _: self._call(self.sim.takeoff))
        rospy.Subscriber('ardrone/land', Empty, lambda _: self._call(self.sim.land))
        rospy.Subscriber('ardrone/reset', Empty, lambda _: self._call(self.sim.reset))
        rospy.Service('ardrone/setflightanimation', FlightAnim, self.on_flight_animation)
        rospy.Service('ardrone/snapshot', Trigger, self.on_snapshot)
        self._last_state = None

    # -- inputs ---------------------------------------------------------------------
    def _call(self, fn, *args):
        with self.lock:
            return fn(*args)

    def on_cmd_vel(self, msg):
        self._call(self.sim.set_cmd_vel, msg.linear.x, msg.linear.y, msg.linear.z,
                   msg.angular.x, msg.angular.y, msg.angular.z)

    def on_flight_animation(self, req):
        return FlightAnimResponse(result=bool(self._call(self.sim.flight_animation,
                                                         req.type, req.duration)))

    def on_snapshot(self, _req):
        folder = self.p['snapshot_dir'] or os.environ.get('ROS_HOME') or '/tmp'
        try:
            os.makedirs(folder, exist_ok=True)
            path = os.path.join(folder, 'ardrone_%08.3f.png' % self.sim.time)
            w, h = (int(v) for v in self.p['snapshot_size'])
            with self.lock:
                self.sim.snapshot(path, w, h)
        except (OSError, ValueError) as e:
            return TriggerResponse(success=False, message='snapshot failed: %s' % e)
        return TriggerResponse(success=True, message=path)

    # -- outputs --------------------------------------------------------------------
    def _publish_camera_frames(self):
        frames = []
        if self.p['world_frame']:
            t = TransformStamped()
            t.header.stamp = rospy.Time.now()
            t.header.frame_id, t.child_frame_id = self.p['world_frame'], self.odom
            xyz = [float(v) for v in self.p['odom_in_world']]
            if len(xyz) != 3:
                raise ValueError('~odom_in_world needs [x, y, z]')
            t.transform.translation.x, t.transform.translation.y, t.transform.translation.z = xyz
            t.transform.rotation.w = 1.0
            frames.append(t)
        for child, xyz, rpy in (('ardrone_base_frontcam', (0.21, 0.0, 0.0),
                                 (-math.pi / 2, 0.0, -math.pi / 2)),
                                ('ardrone_base_bottomcam', (0.0, -0.02, 0.0),
                                 (math.pi, 0.0, -math.pi / 2))):
            t = TransformStamped()
            t.header.stamp = rospy.Time.now()
            t.header.frame_id = self.base
            t.child_frame_id = child
            t.transform.translation.x, t.transform.translation.y, t.transform.translation.z = xyz
            q = _quat_from_rpy(*rpy)
            r = t.transform.rotation
            r.x, r.y, r.z, r.w = q
            frames.append(t)
        self.static_tf.sendTransform(frames)

    def stamp(self):
        return rospy.Time.from_sec(self.sim.time) if self.use_sim_time else rospy.Time.now()

    def publish(self):
        s = self.sim
        with self.lock:
            nav = s.navdata()
            pos, quat, omega, alt = s.pos, s.quat, s.omega, s.altitude
        stamp = self.stamp()
        if self.clock_pub is not None:
            self.clock_pub.publish(Clock(clock=stamp))
        msg = Navdata()
        msg.header.stamp, msg.header.frame_id = stamp, self.base
        for key, value in nav.items():
            setattr(msg, key, value)
        msg.magX = int(200 * math.cos(math.radians(nav['rotZ'])))     # earth field, heading
        msg.magY = int(-200 * math.sin(math.radians(nav['rotZ'])))
        msg.magZ = -400
        msg.pressure = int(101325 - 12.0 * alt)
        msg.temp = 25
        self.nav_pub.publish(msg)
        if nav['state'] != self._last_state:
            rospy.loginfo('ardrone_sim: state %d (%s)', nav['state'], STATE_NAMES[nav['state']])
            self._last_state = nav['state']

        imu = Imu()
        imu.header.stamp, imu.header.frame_id = stamp, self.base
        o = imu.orientation
        o.x, o.y, o.z, o.w = quat
        imu.angular_velocity.x, imu.angular_velocity.y, imu.angular_velocity.z = omega
        a = imu.linear_acceleration
        a.x, a.y, a.z = nav['ax'] * 9.8, nav['ay'] * 9.8, nav['az'] * 9.8
        self.imu_pub.publish(imu)

        odo = Odometry()
        odo.header.stamp, odo.header.frame_id = stamp, self.odom
        odo.child_frame_id = self.base
        pp = odo.pose.pose
        pp.position.x, pp.position.y, pp.position.z = pos[0], pos[1], alt
        pp.orientation = o
        tw = odo.twist.twist
        tw.linear.x, tw.linear.y, tw.linear.z = nav['vx'] / 1000, nav['vy'] / 1000, nav['vz'] / 1000
        tw.angular.x, tw.angular.y, tw.angular.z = omega
        self.odom_pub.publish(odo)

        t = TransformStamped()
        t.header.stamp, t.header.frame_id, t.child_frame_id = stamp, self.odom, self.base
        t.transform.translation.x, t.transform.translation.y = pos[0], pos[1]
        t.transform.translation.z = alt
        t.transform.rotation = o
        self.tf.sendTransform(t)
        self._publish_path(stamp, (pos[0], pos[1], alt), quat)

    def _publish_path(self, stamp, xyz, quat):
        if self.path_period is None:
            return
        self.trail.add(stamp, xyz, quat)
        now = stamp.to_sec()
        if self.trail.changed and (self._path_sent is None or now < self._path_sent
                                   or now - self._path_sent >= self.path_period):
            self.path_pub.publish(self.trail.to_msg(self.odom, stamp))
            self._path_sent = now

    def run(self):
        rate = float(self.p['looprate'])
        steps = max(1, int(round(self.sim.p.physics_rate / rate)))
        rtf = float(self.p['realtime_factor'])
        if rtf <= 0 and not self.use_sim_time:
            rospy.logwarn('ardrone_sim: realtime_factor %g without /use_sim_time: running in '
                          'real time instead', rtf)
            rtf = 1.0
        t0_wall, t0_sim = time.monotonic(), self.sim.time
        self.publish()
        while not rospy.is_shutdown():
            with self.lock:
                for _ in range(steps):
                    self.sim.step()
            self.publish()
            if rtf > 0:
                delay = t0_wall + (self.sim.time - t0_sim) / rtf - time.monotonic()
                if delay > 0:
                    time.sleep(delay)
                elif delay < -0.5:          # fell behind (loaded machine): do not sprint
                    t0_wall, t0_sim = time.monotonic(), self.sim.time
            else:
                time.sleep(0)               # let the callbacks in


def _quat_from_rpy(roll, pitch, yaw):
    cr, sr = math.cos(roll / 2), math.sin(roll / 2)
    cp, sp = math.cos(pitch / 2), math.sin(pitch / 2)
    cy, sy = math.cos(yaw / 2), math.sin(yaw / 2)
    return (sr * cp * cy - cr * sp * sy, cr * sp * cy + sr * cp * sy,
            cr * cp * sy - sr * sp * cy, cr * cp * cy + sr * sp * sy)


def main(argv=None):
    p, node = start_node('ardrone_sim.py', 'ardrone_sim', __doc__, PARAMS, ArDroneSimNode, argv)
    rospy.loginfo('ardrone_sim: ready (%s, %s)', 'GUI' if p['gui'] else 'headless',
                  'sim time x%g' % p['realtime_factor'] if node.use_sim_time else 'wall time')
    try:
        node.run()
    except rospy.ROSInterruptException:
        pass
    finally:
        node.sim.close()
