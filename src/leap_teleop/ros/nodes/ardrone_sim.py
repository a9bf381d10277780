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
import rospy
import tf2_ros
from geometry_msgs.msg import Twist, Vector3Stamped
from nav_msgs.msg import Odometry, Path
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import CameraInfo, Image, Imu
from sensor_msgs.srv import SetCameraInfo, SetCameraInfoResponse
from std_msgs.msg import Empty
from std_srvs.srv import Empty as EmptySrv
from std_srvs.srv import EmptyResponse, Trigger, TriggerResponse
from visualization_msgs.msg import MarkerArray

from leap_teleop import srv
from leap_teleop.drone.cameras import CAMERAS
from leap_teleop.drone.sim_runner import RUNNER_PARAMS, DroneSimRunner, calibration_error, static_frames
from leap_teleop.msg import Navdata, navdata_altitude
from leap_teleop.ros.conversions import DroneMessages, camera_info_msg, rgb_image_msg, transform_msg
from leap_teleop.ros.markers import PathTrail, drone_markers
from leap_teleop.ros.node import RateLimitedLog, start_node
from leap_teleop.ros.signals import closed_at_shutdown

PARAMS = RUNNER_PARAMS      # declared beside the simulation; --help and docs/nodes.md read it
# The drone state, published each ~looprate tick in this order (DroneMessages' names).
STATE_TOPICS = (('navdata', Navdata), ('mag', Vector3Stamped), ('navdata_altitude', navdata_altitude),
                ('imu', Imu), ('odometry', Odometry))
# Service: (type, answer, DroneSimRunner's command, the request's fields it takes). Like the
# driver, every answer is true: the simulated firmware logs why it ignored a command.
SERVICES = {
    'setflightanimation': (srv.FlightAnim, srv.FlightAnimResponse(result=True), 'flight_animation',
                           ('type', 'duration')),
    'flattrim': (EmptySrv, EmptyResponse(), 'flat_trim', ()),
    'togglecam': (EmptySrv, EmptyResponse(), 'toggle_camera', ()),
    'setcamchannel': (srv.CamSelect, srv.CamSelectResponse(result=True), 'set_camera_channel',
                      ('channel',)),
    'setledanimation': (srv.LedAnim, srv.LedAnimResponse(result=True), 'set_led_animation',
                        ('type', 'freq', 'duration')),
    'setrecord': (srv.RecordEnable, srv.RecordEnableResponse(result=True), 'set_record', ('enable',)),
}


class ArDroneSimNode:
    def __init__(self, p):
        self.log = RateLimitedLog()
        self.use_sim_time = bool(rospy.get_param('/use_sim_time', False))
        self.runner = DroneSimRunner(p, self.use_sim_time, warn=lambda key, text:
                                     rospy.logwarn('ardrone_sim: %s', text))
        self.sim, self.frames, call = self.runner.sim, self.runner.frames, self.runner.call
        pub = rospy.Publisher
        self.state_pubs = {name: pub('ardrone/' + name, kind, queue_size=25) for name, kind in
                           STATE_TOPICS if name != 'navdata_altitude' or p['enable_navdata_altitude']}
        self.clock_pub = pub('/clock', Clock, queue_size=10) if self.use_sim_time else None
        self.image_pubs, self.info_pubs, self.info = {}, {}, {}
        for name in ('front', 'bottom', None):      # None: the video channel's camera
            topic = 'ardrone/%s/' % name if name else 'ardrone/'
            self.image_pubs[name] = pub(topic + 'image_raw', Image, queue_size=2)
            self.info_pubs[name] = pub(topic + 'camera_info', CameraInfo, queue_size=2)
            if name:
                self.info[name] = camera_info_msg(CAMERAS[name], self.frames.cameras[name])
                rospy.Service(topic + 'set_camera_info', SetCameraInfo,
                              lambda req, n=name: self.on_set_camera_info(n, req))
        self.tf = tf2_ros.TransformBroadcaster()
        self.static_tf = tf2_ros.StaticTransformBroadcaster()
        self.static_tf.sendTransform([transform_msg(*f, stamp=rospy.Time.now()) for f in
                                      static_frames(self.frames, p['world_frame'],
                                                    p['odom_in_world'])])
        self.trail = PathTrail(int(p['path_length']), float(p['path_min_step']))
        self.path_pub = pub('ardrone/path', Path, queue_size=2, latch=True)
        if p['markers']:
            self.marker_pub = pub('ardrone/markers', MarkerArray, queue_size=1, latch=True)
            self.marker_pub.publish(drone_markers(self.frames.base))
        rospy.Subscriber('cmd_vel', Twist, lambda m: call(
            self.sim.set_cmd_vel, m.linear.x, m.linear.y, m.linear.z, m.angular.x, m.angular.y,
            m.angular.z), queue_size=10)
        for topic, command in (('takeoff', self.sim.takeoff), ('land', self.sim.land),
                               ('reset', self.sim.reset)):
            rospy.Subscriber('ardrone/' + topic, Empty, lambda _, c=command: call(c))
        for name, (kind, response, command, fields) in SERVICES.items():
            rospy.Service('ardrone/' + name, kind, lambda req, c=getattr(self.runner, command),
                          f=fields, r=response: self.on_command(req, c, f, r))
        rospy.Service('ardrone/snapshot', Trigger, self.on_snapshot)

    def on_command(self, req, command, fields, response):
        said = command(*(getattr(req, f) for f in fields))
        if said:
            rospy.loginfo('ardrone_sim: %s', said)
        return response

    def on_snapshot(self, _req):
        try:
            return TriggerResponse(success=True, message=self.runner.snapshot())
        except (OSError, ValueError, RuntimeError) as e:
            return TriggerResponse(success=False, message='snapshot failed: %s' % e)

    def on_set_camera_info(self, name, req):
        """Any calibration of the camera's size is kept for this run (the lens stays ideal)."""
        info = req.camera_info
        error = calibration_error(name, info.width, info.height)
        if not error:
            info.header.frame_id = self.frames.cameras[name]
            self.info[name] = info
        return SetCameraInfoResponse(success=not error, status_message=error)

    # -- outputs --------------------------------------------------------------------
    def stamp(self, sim_time):
        return rospy.Time.from_sec(sim_time) if self.use_sim_time else rospy.Time.now()

    def publish(self):
        reading = self.runner.read()
        stamp = self.stamp(reading.time)
        if self.clock_pub is not None:
            self.clock_pub.publish(Clock(clock=stamp))
        m = DroneMessages(reading, stamp, self.frames.base, self.frames.odom,
                          with_altitude='navdata_altitude' in self.state_pubs)
        for name, pub in self.state_pubs.items():
            pub.publish(getattr(m, name))
        self.tf.sendTransform(m.transform)
        if reading.new_state:
            rospy.loginfo('ardrone_sim: state %d (%s)', reading.nav['state'], reading.new_state)
        self.publish_path(stamp, (reading.pos[0], reading.pos[1], reading.altitude), reading.quat)

    def publish_path(self, stamp, xyz, quat):
        gate = self.runner.path_gate
        if gate.period is not None:
            self.trail.add(stamp, xyz, quat)
            if self.trail.changed and gate.open(stamp.to_sec()):
                self.path_pub.publish(self.trail.to_msg(self.frames.odom, stamp))
                gate.sent(stamp.to_sec())

    def publish_image(self, name, rgb, stamp, active):
        msg, info = rgb_image_msg(rgb, stamp, self.frames.cameras[name]), self.info[name]
        info.header.stamp = stamp
        for key in (name, None) if active else (name,):
            self.image_pubs[key].publish(msg)
            self.info_pubs[key].publish(info)

    def camera_failed(self, e):
        if not rospy.is_shutdown():
            self.log.warn('camera', 'ardrone_sim: camera rendering failed: %s', e)


def main(argv=None):
    p, node = start_node('ardrone_sim.py', 'ardrone_sim', __doc__, PARAMS, ArDroneSimNode, argv)
    rospy.loginfo('ardrone_sim: ready (%s, %s)', 'GUI' if p['gui'] else 'headless',
                  'sim time x%g' % p['realtime_factor'] if node.use_sim_time else 'wall time')
    if node.runner.pace_warning:
        rospy.logwarn('ardrone_sim: %s', node.runner.pace_warning)
    try:
        with closed_at_shutdown():
            node.publish()
            node.runner.start_cameras(node.publish_image, node.camera_failed, node.stamp)
            node.runner.run(node.publish, rospy.is_shutdown)
    except rospy.ROSInterruptException:
        pass
    finally:
        node.runner.close()
