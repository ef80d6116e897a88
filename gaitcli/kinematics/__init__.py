"""kinematics stage family."""
