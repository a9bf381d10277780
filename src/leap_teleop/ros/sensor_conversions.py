"""Images, camera info and TF transforms as messages (sensor_msgs, geometry_msgs), without
a ROS master: the sender's annotated camera view and frames, the drone's cameras and TF."""
import numpy as np
import rospy
from geometry_msgs.msg import TransformStamped, Vector3
from sensor_msgs.msg import CameraInfo, Image


def transform_msg(parent, child, xyz, quat_xyzw, stamp):
    t = TransformStamped()
    t.header.stamp, t.header.frame_id, t.child_frame_id = stamp, parent, child
    t.transform.translation = Vector3(*xyz)
    r = t.transform.rotation
    r.x, r.y, r.z, r.w = quat_xyzw
    return t


def camera_info_msg(spec, frame_id):
    """The ideal (undistorted) calibration of a drone.cameras.CameraSpec."""
    info = CameraInfo()
    info.header.frame_id = frame_id
    info.width, info.height = spec.width, spec.height
    info.distortion_model = 'plumb_bob'
    info.D = [0.0] * 5
    info.K, info.P = spec.intrinsics()
    info.R = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]
    return info


def rgb_image_msg(rgb, stamp, frame_id):
    """sensor_msgs/Image (rgb8) of a (H, W, 3) uint8 picture; stamp a rospy.Time."""
    msg = Image()
    msg.header.stamp, msg.header.frame_id = stamp, frame_id
    msg.height, msg.width = rgb.shape[:2]
    msg.encoding, msg.step = 'rgb8', rgb.shape[1] * 3
    msg.data = rgb.tobytes()
    return msg


def bgr_image_msg(bgr, stamp, frame_id):
    """sensor_msgs/Image (encoding bgr8) of a (H, W, 3) uint8 image (no cv_bridge needed)."""
    img = np.ascontiguousarray(bgr, dtype=np.uint8)
    msg = Image()
    msg.header.stamp = rospy.Time.from_sec(stamp)
    msg.header.frame_id = frame_id
    msg.height, msg.width = img.shape[:2]
    msg.encoding = 'bgr8'
    msg.is_bigendian = 0
    msg.step = msg.width * 3
    msg.data = img.tobytes()
    return msg
