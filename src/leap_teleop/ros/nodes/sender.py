"""sender: hand source -> LeapInterface -> leapcobot / Hand / GestureEvent topics, and on
request the leap_motion driver's interface (DriverHuman raw and low-pass filtered, its RViz
markers, the old leap and leapros messages).

Publishes once per source frame from the source's thread (event-driven; no polling). The
parameters --help marks live change while it runs (dynamic_reconfigure).
"""
import gc
import time

import rospy
import tf2_ros

from leap_teleop.hands.leap_interface import LeapInterface
from leap_teleop.hands.sender_params import SENDER_PARAMS, SENDER_RECONFIGURABLE, leap_rotation
from leap_teleop.hands.sender_setup import (
    check_outputs,
    recognizer_factory,
    retune_sender,
    source_and_bindings,
)
from leap_teleop.hands.sources import SourceError
from leap_teleop.hands.tracker import DEAD_BANDS
from leap_teleop.package_files import package_path
from leap_teleop.ros.camera_topics import camera_model, camera_view_publisher
from leap_teleop.ros.diagnostics import diagnostics_updater, update_every
from leap_teleop.ros.hand_topics import HandTopics
from leap_teleop.ros.leap_motion_topics import use_driver_globals
from leap_teleop.ros.node import start_node
from leap_teleop.ros.reconfigure import Reconfigure
from leap_teleop.ros.sensor_conversions import transform_msg
from leap_teleop.ros.signals import quiet_at_shutdown

# The declarations live beside the hand source and recognizer; re-exported for --help and
# the docs.
PARAMS = SENDER_PARAMS
RECONFIGURABLE = SENDER_RECONFIGURABLE


def sender_parts(p):
    """What the checked ~params make before any topic exists (a bad one ends the node)."""
    check_outputs(p, rospy.resolve_name)
    use_driver_globals(p, PARAMS)
    p['leap_rotation_xyzw'] = leap_rotation(p['leap_rotation_xyzw'])
    factory = recognizer_factory(p)
    view = camera_view_publisher(p)
    # bindings checked before a camera's CameraInfo wait; a recording's once read (its hands)
    source, bindings = source_and_bindings(
        p, factory(), rospy.get_time, package_path('config', 'gestures', 'wave_hello.yaml'),
        lambda: camera_model(p), view.on_image if view is not None else None)
    return source, view, factory, bindings


def ended_by_itself(interface):
    """Whether the source came to its end, not stopped by a shutdown (Ctrl-C): the
    on_shutdown hook sets `finished` before rospy.is_shutdown() turns true."""
    return interface.finished.is_set() and not rospy.core.is_shutdown_requested()


def main(argv=None):
    p, (source, view, factory, bindings) = start_node(
        'sender.py', 'leap_sender', __doc__, PARAMS, sender_parts, argv, errors=(SourceError, ValueError))
    interface = LeapInterface(source, recognizer_factory=factory, sides=list(p['sides']),
                              dead_bands=DEAD_BANDS if p['rotation_dead_bands'] else None,
                              bindings=bindings)
    topics = HandTopics(p, interface)
    # The stage ages go out from a timer's thread: the source's thread only stamps them.
    diagnostics = update_every(diagnostics_updater('leap_sender', 'hand stages', topics.report,  # noqa: F841
                                                   topics.ages))
    reconfigure = Reconfigure('sender', PARAMS, RECONFIGURABLE, p,  # noqa: F841 (kept alive)
                              lambda changes: retune_sender(interface.recognizers().values(),
                                                            topics.driver.lowpass, changes))
    if view is not None:
        interface.add_listener(quiet_at_shutdown(view.on_frame))    # after the hands: no latency
    if p['publish_tf']:     # a local of main: it lives, and its latched topic with it, as long as the node
        leap_tf = tf2_ros.StaticTransformBroadcaster()
        leap_tf.sendTransform(transform_msg(p['world_frame'], p['frame_id'], p['leap_xyz'],
                                            p['leap_rotation_xyzw'], rospy.Time.now()))
    rospy.loginfo('sender: publishing %s hands from the %s source on %s',
                  '/'.join(topics.sides), p['source'],
                  ', '.join(pubs['leapcobot'].resolved_name for pubs in topics.pubs.values()))
    rospy.on_shutdown(interface.stop)
    # Everything built so far lives as long as the node: keep the cyclic collector off it,
    # so its passes stay short on the per-frame path.
    gc.collect()
    gc.freeze()
    try:
        if p['wait_for_subscribers'] and not topics.wait_for_subscribers(p['wait_topics']):
            return
        if rospy.core.is_shutdown_requested():
            return
        interface.start()
        while not rospy.is_shutdown() and not interface.finished.wait(0.2):
            pass
    finally:
        if rospy.core.is_shutdown_requested():
            interface.stop()    # also when a signal came before on_shutdown was registered
    if interface.error is not None:
        # ends the node whatever ~shutdown_on_end says: a failed source publishes nothing, and
        # only an ended process can be respawned
        rospy.logerr('sender: the hand source failed: %s', interface.error)
        rospy.signal_shutdown('the hand source failed')
        raise SystemExit(2)
    if ended_by_itself(interface):
        rospy.loginfo('sender: source ended after %d frames', interface.frames_seen)
        if p['shutdown_on_end']:
            time.sleep(0.5)     # subscribers drain the last frames (wall time: a /clock gone back raised)
            rospy.signal_shutdown('source ended')
        else:
            rospy.spin()
