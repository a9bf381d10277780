"""Command-line tools (python -m leap_teleop.tools.NAME)."""
