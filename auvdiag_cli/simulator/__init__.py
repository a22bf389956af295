"""A physically plausible twin-thruster AUV (surge + yaw) that writes real logs with known truth."""
