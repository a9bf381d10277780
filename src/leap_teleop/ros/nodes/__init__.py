"""Thin ROS adapters: each module has a main() that scripts/ calls."""
