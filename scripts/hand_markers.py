#!/usr/bin/env python3
"""Draws the sender's Hand messages as RViz markers (leapmotion/hand_markers)."""
from leap_teleop.ros.nodes.hand_markers import main

if __name__ == '__main__':
    main()
