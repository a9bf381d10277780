"""ardrone_sim: a simulated AR.Drone 2.0 behind the ardrone_autonomy driver's interface.

Offers every endpoint the driver offers by default, with the driver's names and types
(leap_teleop.ros.ardrone_interface.DRIVER_ENDPOINTS): subscribes cmd_vel (Twist),
ardrone/takeoff, ardrone/land, ardrone/reset (Empty); publishes ardrone/navdata
(Navdata), ardrone/imu, ardrone/mag, ardrone/odometry and TF odom -> ardrone_base_link
(+ static front / bottom camera frames) at ~looprate, the cameras (ardrone/front/*,
ardrone/bottom/*: image_raw + camera_info, rendered by PyBullet in a process of their
own at ~front_rate / ~bottom_rate) and the active camera again on ardrone/image_raw +
ardrone/camera_info; serves ardrone/setflightanimation, ardrone/flattrim,
ardrone/togglecam, ardrone/setcamchannel, ardrone/setledanimation, ardrone/setrecord and
ardrone/front|bottom/set_camera_info. Like the driver, the services answer true (the
firmware ignores what it cannot do; the reason is logged). With ~enable_navdata_altitude
it also publishes ardrone/navdata_altitude. Extras: the flown path (nav_msgs/Path,
ardrone/path, bounded) at ~path_rate, a latched drone body of markers (ardrone/markers)
and ardrone/snapshot (std_srvs/Trigger: writes a chase-view PNG, returns its path). With
/use_sim_time true it publishes /clock and can run faster than real time.
Everything is relative to the node's namespace, so drones run side by side in their own
namespaces (~tf_prefix keeps their TF frames apart, as with the driver).
"""
import math
import os
import threading
import time

import rospy
import tf2_ros
from geometry_msgs.msg import TransformStamped, Twist, Vector3Stamped
from nav_msgs.msg import Odometry, Path
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import CameraInfo, Image, Imu
from sensor_msgs.srv import SetCameraInfo, SetCameraInfoResponse
from std_msgs.msg import Empty
from std_srvs.srv import Empty as EmptySrv
from std_srvs.srv import EmptyResponse, Trigger, TriggerResponse
from visualization_msgs.msg import MarkerArray

from leap_teleop.drone import cameras
from leap_teleop.drone.sim import STATE_NAMES, ArDroneSim, DroneParams
from leap_teleop.msg import Navdata, navdata_altitude
from leap_teleop.ros.ardrone_interface import NAVDATA_ALTITUDE_SIZE, NAVDATA_ALTITUDE_TAG
from leap_teleop.ros.markers import PathTrail, drone_markers
from leap_teleop.ros.node import Param, RateLimitedLog, start_node
from leap_teleop.ros.signals import closed_at_shutdown
from leap_teleop.srv import (
    CamSelect,
    CamSelectResponse,
    FlightAnim,
    FlightAnimResponse,
    LedAnim,
    LedAnimResponse,
    RecordEnable,
    RecordEnableResponse,
)

_D = DroneParams()
# Default camera rates: what 2 shared cores render (in the camera process) while the
# flight keeps real time; measured by bench_drone's sim.drone_rtf_cameras.
FRONT_RATE, BOTTOM_RATE = 5.0, 5.0
# ardrone/snapshot answers failure after this long (the first snapshot also starts its
# renderer process and builds the scene there).
SNAPSHOT_TIMEOUT = 30.0
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
    # Cameras and the driver's options.
    'front_rate': Param(FRONT_RATE, 'ardrone/front/image_raw rate (wall clock); 0 = off',
                        unit='Hz', ge=0.0, le=30.0),
    'bottom_rate': Param(BOTTOM_RATE, 'ardrone/bottom/image_raw rate (wall clock); 0 = off',
                         unit='Hz', ge=0.0, le=30.0),
    'camera_channel': Param(0, 'camera on ardrone/image_raw at start: 0 front, 1 bottom',
                            choices=(0, 1)),
    'enable_navdata_altitude': Param(False, 'publish ardrone/navdata_altitude (driver option)'),
    'tf_prefix': Param('', 'prefix of every TF frame published (driver param), e.g. drone1'),
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
        self.sim.set_camera_channel(int(p['camera_channel']))
        prefix = p['tf_prefix'].strip('/')
        self.frame = (lambda name: '%s/%s' % (prefix, name)) if prefix else (lambda name: name)
        self.base, self.odom = self.frame(p['base_frame']), self.frame(p['odom_frame'])
        self.camera_frames = {'front': self.frame('ardrone_base_frontcam'),
                              'bottom': self.frame('ardrone_base_bottomcam')}
        self.nav_pub = rospy.Publisher('ardrone/navdata', Navdata, queue_size=25)
        self.imu_pub = rospy.Publisher('ardrone/imu', Imu, queue_size=25)
        self.mag_pub = rospy.Publisher('ardrone/mag', Vector3Stamped, queue_size=25)
        self.odom_pub = rospy.Publisher('ardrone/odometry', Odometry, queue_size=25)
        self.alt_pub = (rospy.Publisher('ardrone/navdata_altitude', navdata_altitude,
                                        queue_size=25)
                        if p['enable_navdata_altitude'] else None)
        self.log = RateLimitedLog()
        self.snapshots = cameras.ChaseSnapshots(SNAPSHOT_TIMEOUT)
        self.cameras = CameraStreams(self, {'front': float(p['front_rate']),
                                            'bottom': float(p['bottom_rate'])})
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
        rospy.Service('ardrone/flattrim', EmptySrv, self.on_flat_trim)
        rospy.Service('ardrone/togglecam', EmptySrv, self.on_toggle_camera)
        rospy.Service('ardrone/setcamchannel', CamSelect, self.on_camera_channel)
        rospy.Service('ardrone/setledanimation', LedAnim, self.on_led_animation)
        rospy.Service('ardrone/setrecord', RecordEnable, self.on_record)
        rospy.Service('ardrone/snapshot', Trigger, self.on_snapshot)
        self._last_state = None

    # -- inputs ---------------------------------------------------------------------
    def _call(self, fn, *args):
        with self.lock:
            return fn(*args)

    def on_cmd_vel(self, msg):
        self._call(self.sim.set_cmd_vel, msg.linear.x, msg.linear.y, msg.linear.z,
                   msg.angular.x, msg.angular.y, msg.angular.z)

    # The driver answers true whatever the firmware does with a command; the simulated
    # firmware logs why it ignored one.
    def on_flight_animation(self, req):
        self._call(self.sim.flight_animation, req.type, req.duration)
        return FlightAnimResponse(result=True)

    def on_flat_trim(self, _req):
        if self._call(self.sim.flat_trim):
            rospy.loginfo('ardrone_sim: flat trim done')
        return EmptyResponse()

    def on_toggle_camera(self, _req):
        self._call(self.sim.toggle_camera)
        rospy.loginfo('ardrone_sim: video channel %d', self.sim.camera_channel)
        return EmptyResponse()

    def on_camera_channel(self, req):
        self._call(self.sim.set_camera_channel, req.channel)
        rospy.loginfo('ardrone_sim: video channel %d', self.sim.camera_channel)
        return CamSelectResponse(result=True)

    def on_led_animation(self, req):
        if self._call(self.sim.set_led_animation, req.type, req.freq, req.duration):
            rospy.loginfo('ardrone_sim: LED animation %s at %.1f Hz for %d s',
                          self.sim.led_animation[0], req.freq, req.duration)
        return LedAnimResponse(result=True)

    def on_record(self, req):
        self._call(self.sim.set_record, req.enable)
        rospy.loginfo('ardrone_sim: video recording %s', 'on' if req.enable else 'off')
        return RecordEnableResponse(result=True)

    def on_snapshot(self, _req):
        folder = self.p['snapshot_dir'] or os.environ.get('ROS_HOME') or '/tmp'
        try:
            os.makedirs(folder, exist_ok=True)
            w, h = (int(v) for v in self.p['snapshot_size'])
            with self.lock:     # only the pose: the picture is drawn in another process
                t, pos, quat = self.sim.time, self.sim.pos, self.sim.quat
            path = os.path.join(folder, 'ardrone_%08.3f.png' % t)
            self.snapshots.take(pos, quat, path, w, h, self.sim.p.arm)
        except (OSError, ValueError, RuntimeError) as e:
            return TriggerResponse(success=False, message='snapshot failed: %s' % e)
        return TriggerResponse(success=True, message=path)

    # -- outputs --------------------------------------------------------------------
    def _publish_camera_frames(self):
        frames = []
        if self.p['world_frame']:
            t = TransformStamped()
            t.header.stamp = rospy.Time.now()
            t.header.frame_id, t.child_frame_id = self.p['world_frame'], self.odom   # shared
            xyz = [float(v) for v in self.p['odom_in_world']]
            if len(xyz) != 3:
                raise ValueError('~odom_in_world needs [x, y, z]')
            t.transform.translation.x, t.transform.translation.y, t.transform.translation.z = xyz
            t.transform.rotation.w = 1.0
            frames.append(t)
        # Optical frames (z along the view, x right, y down in the image), mounted where
        # cameras.FRONT / cameras.BOTTOM render from.
        for child, xyz, rpy in ((self.camera_frames['front'], cameras.FRONT.mount,
                                 (-math.pi / 2, 0.0, -math.pi / 2)),
                                (self.camera_frames['bottom'], cameras.BOTTOM.mount,
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
        mag = Vector3Stamped()
        mag.header = msg.header
        mag.vector.x, mag.vector.y, mag.vector.z = msg.magX, msg.magY, msg.magZ
        self.mag_pub.publish(mag)
        if self.alt_pub is not None:
            self.alt_pub.publish(self._navdata_altitude(msg, nav, alt))
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

    def _navdata_altitude(self, msg, nav, alt):
        """The altitude option: vision / raw / reference altitude (mm) are the sim's
        true one, the observer's state its altitude (m) and climb rate (m/s)."""
        out = navdata_altitude()
        out.header = msg.header
        out.drone_time = nav['tm'] / 1e6
        out.tag, out.size = NAVDATA_ALTITUDE_TAG, NAVDATA_ALTITUDE_SIZE
        out.altitude_vision = out.altitude_raw = out.altitude_ref = nav['altd']
        out.altitude_vz = nav['vz']
        out.obs_accZ = nav['az'] * 9.81
        out.obs_alt = max(alt, 0.0)
        out.obs_x.x, out.obs_x.y = max(alt, 0.0), nav['vz'] / 1000.0
        out.est_vb.x = nav['vz'] / 1000.0
        return out

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
        self.cameras.start()
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


class CameraStreams:
    """The cameras' topics, fed from a thread of their own: it copies the drone pose under
    the node's lock, has the renderer process draw it and publishes the images."""

    def __init__(self, node, rates):
        self.node = node
        self.pubs, self.info_pubs, self.info = {}, {}, {}
        for name, spec in cameras.CAMERAS.items():
            self.pubs[name] = rospy.Publisher('ardrone/%s/image_raw' % name, Image, queue_size=2)
            self.info_pubs[name] = rospy.Publisher('ardrone/%s/camera_info' % name, CameraInfo,
                                                   queue_size=2)
            self.info[name] = self._ideal_info(spec, node.camera_frames[name])
            rospy.Service('ardrone/%s/set_camera_info' % name, SetCameraInfo,
                          lambda req, n=name: self.on_set_camera_info(n, req))
        self.active_pub = rospy.Publisher('ardrone/image_raw', Image, queue_size=2)
        self.active_info_pub = rospy.Publisher('ardrone/camera_info', CameraInfo, queue_size=2)
        self.loop = cameras.CameraLoop(rates, self._pose, self._deliver, self._error)

    @staticmethod
    def _ideal_info(spec, frame):
        info = CameraInfo()
        info.header.frame_id = frame
        info.width, info.height = spec.width, spec.height
        info.distortion_model = 'plumb_bob'
        info.D = [0.0] * 5
        info.K, info.P = spec.intrinsics()
        info.R = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]
        return info

    def on_set_camera_info(self, name, req):
        """Like camera_info_manager: any calibration of the camera's size is taken (kept
        for this run; the simulated lens stays ideal)."""
        spec, info = cameras.CAMERAS[name], req.camera_info
        if (info.width, info.height) != (spec.width, spec.height):
            return SetCameraInfoResponse(
                success=False, status_message='%s camera is %dx%d, got %dx%d' % (
                    name, spec.width, spec.height, info.width, info.height))
        info.header.frame_id = self.node.camera_frames[name]
        self.info[name] = info
        return SetCameraInfoResponse(success=True, status_message='')

    def start(self):
        self.loop.start()

    def stop(self):
        self.loop.stop()

    def _pose(self):
        node = self.node
        with node.lock:
            active = 'front' if node.sim.camera_channel == 0 else 'bottom'
            return node.sim.pos, node.sim.quat, (node.stamp(), active)

    def _deliver(self, name, rgb, context):
        stamp, active = context
        self._publish(name, rgb, stamp, name == active)

    def _error(self, e):
        if not rospy.is_shutdown():
            self.node.log.warn('camera', 'ardrone_sim: camera rendering failed: %s', e)

    def _publish(self, name, rgb, stamp, active):
        msg = Image()
        msg.header.stamp, msg.header.frame_id = stamp, self.node.camera_frames[name]
        msg.height, msg.width = rgb.shape[:2]
        msg.encoding, msg.step = 'rgb8', rgb.shape[1] * 3
        msg.data = rgb.tobytes()
        info = self.info[name]
        info.header.stamp = stamp
        self.pubs[name].publish(msg)
        self.info_pubs[name].publish(info)
        if active:
            self.active_pub.publish(msg)
            self.active_info_pub.publish(info)


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
        with closed_at_shutdown():
            node.run()
    except rospy.ROSInterruptException:
        pass
    finally:
        node.cameras.stop()
        node.snapshots.close()
        node.sim.close()
