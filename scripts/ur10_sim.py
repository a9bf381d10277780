#!/usr/bin/env python3
"""Simulated UR10 work cell (one or two arms) with ros_control-like topics."""
from leap_teleop.ros.nodes.ur10_sim import main

if __name__ == '__main__':
    main()
