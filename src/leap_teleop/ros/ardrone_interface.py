"""The ardrone_autonomy driver's default ROS interface, as the simulator offers it.

One row per endpoint: (kind, name relative to the drone's namespace, the type the
simulator uses, the driver's type). The two type columns differ only in the package
name where the project carries its own MD5-identical copy of a driver type. The node
(`nodes/ardrone_sim.py`, with `drone_state_topics` and `drone_camera_topics`) registers
exactly these; a rostest compares them with the
running node's and a unit test with the table in docs/robots.md.
"""

PUBLISHER, SUBSCRIBER, SERVICE = 'publisher', 'subscriber', 'service'

DRIVER_ENDPOINTS = (
    (SUBSCRIBER, 'cmd_vel', 'geometry_msgs/Twist', 'geometry_msgs/Twist'),
    (SUBSCRIBER, 'ardrone/takeoff', 'std_msgs/Empty', 'std_msgs/Empty'),
    (SUBSCRIBER, 'ardrone/land', 'std_msgs/Empty', 'std_msgs/Empty'),
    (SUBSCRIBER, 'ardrone/reset', 'std_msgs/Empty', 'std_msgs/Empty'),
    (PUBLISHER, 'ardrone/navdata', 'leap_teleop/Navdata', 'ardrone_autonomy/Navdata'),
    (PUBLISHER, 'ardrone/imu', 'sensor_msgs/Imu', 'sensor_msgs/Imu'),
    (PUBLISHER, 'ardrone/mag', 'geometry_msgs/Vector3Stamped', 'geometry_msgs/Vector3Stamped'),
    (PUBLISHER, 'ardrone/odometry', 'nav_msgs/Odometry', 'nav_msgs/Odometry'),
    (PUBLISHER, 'ardrone/image_raw', 'sensor_msgs/Image', 'sensor_msgs/Image'),
    (PUBLISHER, 'ardrone/camera_info', 'sensor_msgs/CameraInfo', 'sensor_msgs/CameraInfo'),
    (PUBLISHER, 'ardrone/front/image_raw', 'sensor_msgs/Image', 'sensor_msgs/Image'),
    (PUBLISHER, 'ardrone/front/camera_info', 'sensor_msgs/CameraInfo', 'sensor_msgs/CameraInfo'),
    (PUBLISHER, 'ardrone/bottom/image_raw', 'sensor_msgs/Image', 'sensor_msgs/Image'),
    (PUBLISHER, 'ardrone/bottom/camera_info', 'sensor_msgs/CameraInfo',
     'sensor_msgs/CameraInfo'),
    (PUBLISHER, '/tf', 'tf2_msgs/TFMessage', 'tf2_msgs/TFMessage'),
    (SERVICE, 'ardrone/setflightanimation', 'leap_teleop/FlightAnim',
     'ardrone_autonomy/FlightAnim'),
    (SERVICE, 'ardrone/flattrim', 'std_srvs/Empty', 'std_srvs/Empty'),
    (SERVICE, 'ardrone/togglecam', 'std_srvs/Empty', 'std_srvs/Empty'),
    (SERVICE, 'ardrone/setcamchannel', 'leap_teleop/CamSelect', 'ardrone_autonomy/CamSelect'),
    (SERVICE, 'ardrone/setledanimation', 'leap_teleop/LedAnim', 'ardrone_autonomy/LedAnim'),
    (SERVICE, 'ardrone/setrecord', 'leap_teleop/RecordEnable', 'ardrone_autonomy/RecordEnable'),
    (SERVICE, 'ardrone/front/set_camera_info', 'sensor_msgs/SetCameraInfo',
     'sensor_msgs/SetCameraInfo'),
    (SERVICE, 'ardrone/bottom/set_camera_info', 'sensor_msgs/SetCameraInfo',
     'sensor_msgs/SetCameraInfo'),
)

# Off by default in the driver too; on with the node's ~enable_navdata_altitude.
OPTIONAL_ENDPOINTS = (
    (PUBLISHER, 'ardrone/navdata_altitude', 'leap_teleop/navdata_altitude',
     'ardrone_autonomy/navdata_altitude'),
)

NAVDATA_ALTITUDE_TAG = 10      # the SDK's option tag of navdata_altitude
NAVDATA_ALTITUDE_SIZE = 56     # bytes of the option on the wire
