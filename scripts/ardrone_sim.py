#!/usr/bin/env python3
"""Simulated AR.Drone 2.0 with the ardrone_autonomy interface."""
from leap_teleop.ros.nodes.ardrone_sim import main

if __name__ == '__main__':
    main()
