"""The simulated drone's camera topics, as the ardrone_autonomy driver offers them:
ardrone/front/* and ardrone/bottom/* (image_raw, camera_info and the set_camera_info
service), and the video channel's camera again on ardrone/image_raw and
ardrone/camera_info."""
import rospy
from sensor_msgs.msg import CameraInfo, Image
from sensor_msgs.srv import SetCameraInfo, SetCameraInfoResponse

from leap_teleop.drone.cameras import CAMERAS
from leap_teleop.drone.sim_runner import calibration_error
from leap_teleop.ros.sensor_conversions import camera_info_msg, rgb_image_msg
from leap_teleop.ros.signals import closed_at_shutdown


class DroneCameraTopics:
    """Each rendered image with its camera's calibration (ideal, or what set_camera_info
    gave); `frames` maps 'front' and 'bottom' to their TF frames."""

    def __init__(self, frames):
        self.frames = frames
        self.image_pubs, self.info_pubs, self.info = {}, {}, {}
        for name in ('front', 'bottom', None):      # None: the video channel's camera
            topic = 'ardrone/%s/' % name if name else 'ardrone/'
            self.image_pubs[name] = rospy.Publisher(topic + 'image_raw', Image, queue_size=2)
            self.info_pubs[name] = rospy.Publisher(topic + 'camera_info', CameraInfo,
                                                   queue_size=2)
            if name:
                self.info[name] = camera_info_msg(CAMERAS[name], frames[name])
                rospy.Service(topic + 'set_camera_info', SetCameraInfo,
                              lambda req, n=name: self.on_set_camera_info(n, req))

    def on_set_camera_info(self, name, req):
        """A calibration calibration_error takes is kept for this run (the lens stays
        ideal); any other is refused with its reason."""
        info = req.camera_info
        error = calibration_error(name, info.width, info.height, info.K, info.D, info.R, info.P,
                                  info.distortion_model)
        if not error:
            info.header.frame_id = self.frames[name]
            self.info[name] = info
        return SetCameraInfoResponse(success=not error, status_message=error)

    def publish(self, name, rgb, stamp, active):
        """Camera `name`'s picture (an RGB array) taken at `stamp`, also on the video
        channel's topics when it is the `active` camera. Called on the cameras' thread,
        which may deliver one more picture while the node shuts down: that one is dropped."""
        msg, info = rgb_image_msg(rgb, stamp, self.frames[name]), self.info[name]
        info.header.stamp = stamp
        with closed_at_shutdown():
            for key in (name, None) if active else (name,):
                self.image_pubs[key].publish(msg)
                self.info_pubs[key].publish(info)
