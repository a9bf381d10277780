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
firmware ignores what it cannot do; the reason is logged), but setflightanimation refuses
(false) a duration beyond 10 s. Inputs of another type are warned about. With
~enable_navdata_altitude it also publishes ardrone/navdata_altitude. Extras: the flown path
(nav_msgs/Path, ardrone/path, bounded) at ~path_rate, a latched drone body of markers
(ardrone/markers) and ardrone/snapshot (std_srvs/Trigger: writes a chase-view PNG, returns
its path). With /use_sim_time true it publishes /clock and can run faster than real time.
Everything is relative to the node's namespace, so drones run side by side in their own
namespaces (~tf_prefix keeps their TF frames apart, as with the driver).
"""
import rospy
from std_srvs.srv import Empty as EmptySrv
from std_srvs.srv import EmptyResponse, Trigger, TriggerResponse

from leap_teleop import srv
from leap_teleop.drone.sim_runner import RUNNER_PARAMS, DroneSimRunner
from leap_teleop.ros.drone_camera_topics import DroneCameraTopics
from leap_teleop.ros.drone_inputs import subscribe_ardrone_sim_inputs
from leap_teleop.ros.drone_state_topics import DroneStateTopics
from leap_teleop.ros.node import RateLimitedLog, start_node
from leap_teleop.ros.signals import closed_at_shutdown

PARAMS = RUNNER_PARAMS      # declared beside the simulation; --help and docs/nodes.md read it
# Service: (type, answer, DroneSimRunner's command, the request's fields it takes). Like the
# driver, answers are true (the sim logs what it ignored) unless the command says False.
SERVICES = {
    'setflightanimation': (srv.FlightAnim, srv.FlightAnimResponse(result=True), 'flight_animation',
                           ('type', 'duration')),
    'flattrim': (EmptySrv, EmptyResponse(), 'flat_trim', ()),
    'togglecam': (EmptySrv, EmptyResponse(), 'toggle_camera', ()),
    'setcamchannel': (srv.CamSelect, srv.CamSelectResponse(result=True), 'set_camera_channel',
                      ('channel',)),
    'setledanimation': (srv.LedAnim, srv.LedAnimResponse(result=True), 'set_led_animation',
                        ('type', 'freq', 'duration')),
    'setrecord': (srv.RecordEnable, srv.RecordEnableResponse(result=True), 'set_record',
                  ('enable',)),
}


class ArDroneSimNode:
    def __init__(self, p):
        self.log = RateLimitedLog()
        self.use_sim_time = bool(rospy.get_param('/use_sim_time', False))
        self.runner = DroneSimRunner(p, self.use_sim_time,
                                     warn=lambda _, text: rospy.logwarn('ardrone_sim: %s', text))
        self.state = DroneStateTopics(p, self.runner.frames, self.runner.path_gate,
                                      self.use_sim_time)
        self.cameras = DroneCameraTopics(self.runner.frames.cameras)
        self.type_watch = subscribe_ardrone_sim_inputs(self.runner.sim, self.runner.call, self.log)
        for name, (kind, response, command, fields) in SERVICES.items():
            rospy.Service('ardrone/' + name, kind, lambda req, c=getattr(self.runner, command),
                          f=fields, r=response: self.on_command(req, c, f, r))
        rospy.Service('ardrone/snapshot', Trigger, self.on_snapshot)

    def on_command(self, req, command, fields, response):
        said = command(*(getattr(req, f) for f in fields))
        if said is False:               # refused (the runner warned)
            return type(response)(result=False)
        if said:
            rospy.loginfo('ardrone_sim: %s', said)
        return response

    def on_snapshot(self, _req):
        try:
            return TriggerResponse(success=True, message=self.runner.snapshot())
        except (OSError, ValueError, RuntimeError) as e:
            return TriggerResponse(success=False, message='snapshot failed: %s' % e)

    def publish(self):
        """One loop tick's state (on the loop's thread)."""
        reading = self.runner.read()
        self.state.publish(reading)
        if reading.new_state:
            rospy.loginfo('ardrone_sim: state %d (%s)', reading.nav['state'], reading.new_state)

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
            node.runner.start_cameras(node.cameras.publish, node.camera_failed, node.state.stamp)
            node.runner.run(node.publish, rospy.is_shutdown)
    except rospy.ROSInterruptException:
        pass
    finally:
        node.runner.close()
