"""The world around an external autopilot: the vehicle's pose comes from the truth of a real
autopilot's own simulation (PX4 SIH, ArduCopter SITL) instead of the simulator's physics."""
