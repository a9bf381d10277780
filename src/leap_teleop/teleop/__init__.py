"""Teleoperation logic that turns hand input into robot commands (no ROS here)."""
