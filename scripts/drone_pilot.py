#!/usr/bin/env python3
"""Gesture pilot: Leap hand -> AR.Drone commands (ardrone_autonomy interface)."""
from leap_teleop.ros.nodes.drone_pilot import main

if __name__ == '__main__':
    main()
