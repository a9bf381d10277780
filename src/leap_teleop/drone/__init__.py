"""AR.Drone 2.0: a PyBullet simulation with ardrone_autonomy semantics, and the gesture pilot."""
