"""leap_teleop: hand-gesture teleoperation of UR10 cobots and an AR.Drone 2.0."""
