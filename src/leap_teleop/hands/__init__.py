"""Everything before a robot, no ROS: hand frames, their sources, the per-hand tracker
and gesture recognition."""
