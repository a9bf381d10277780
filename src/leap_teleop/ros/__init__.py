"""The ROS edge: the only code that imports rospy or message packages. Conversions
between messages and the library's data, node start-up, and the nodes themselves."""
