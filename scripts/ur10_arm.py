#!/usr/bin/env python3
"""Drives one UR10 from one hand's leapcobot messages."""
from leap_teleop.ros.nodes.ur10_arm import main

if __name__ == '__main__':
    main()
