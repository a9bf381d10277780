#!/usr/bin/env python3
"""Publishes Leap hand data (leapcobot, Hand, GestureEvent) once per frame."""
from leap_teleop.ros.nodes.sender import main

if __name__ == '__main__':
    main()
