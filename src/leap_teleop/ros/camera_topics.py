"""The sender's camera topics: the sensor_msgs/CameraInfo a camera source calibrates from,
and the annotated camera image it publishes. Loads no camera library until one is used."""
import rospy

from leap_teleop.hands.sources import SourceError
from leap_teleop.hands.sources.camera_params import CAMERA_SOURCES
from leap_teleop.ros import sensor_conversions


def camera_model(p, timeout=10.0):
    """CameraModel from one sensor_msgs/CameraInfo on ~camera_info_topic; None when unset."""
    if not p['camera_info_topic']:
        return None
    from sensor_msgs.msg import CameraInfo

    from leap_teleop.hands.sources.landmarks import CameraModel
    try:
        info = rospy.wait_for_message(p['camera_info_topic'], CameraInfo, timeout)
    except rospy.ROSException as e:
        # ROSInterruptException is a ROSException: a Ctrl-C while waiting is no bad parameter
        if isinstance(e, rospy.ROSInterruptException) or rospy.core.is_shutdown_requested():
            rospy.loginfo('sender: shut down while waiting for %s', p['camera_info_topic'])
            raise SystemExit(0)
        raise SourceError('no sensor_msgs/CameraInfo on %s within %.0f s (~camera_info_topic)'
                          % (p['camera_info_topic'], timeout))
    try:
        return CameraModel.from_matrix(info.width, info.height, info.K)
    except ValueError as e:
        raise SourceError('~camera_info_topic %s: %s' % (p['camera_info_topic'], e))


def camera_view_publisher(p):
    """The annotated camera view (CameraView publishing on ~annotated_image_topic) when
    that is set and the source is a camera; else None. Its notes are the input ages heard
    on /diagnostics: this sender's capture -> published and each consumer's capture ->
    command."""
    if p['source'] not in CAMERA_SOURCES or not p['annotated_image_topic']:
        return None
    from sensor_msgs.msg import Image

    from leap_teleop.hands.camera_view import CameraView
    from leap_teleop.ros.latency_monitor import LatencyMonitor

    pub = rospy.Publisher(p['annotated_image_topic'], Image, queue_size=2)
    monitor = LatencyMonitor()
    view = CameraView(p['mirror'] != p['input_mirrored'],
                      lambda frame, img: pub.publish(sensor_conversions.bgr_image_msg(img, frame.timestamp,
                                                                   p['frame_id'])),
                      wanted=lambda: pub.get_num_connections() > 0,
                      notes=monitor.notes)
    return view
