"""The simulated aircraft and world: a PX4-like MAVLink autopilot over quadrotor physics, a
rendered world with a beacon and people, and frontal/ventral cameras published on Zenoh.

Run it with ``dronewrapper sim`` or ``python -m dronewrapper_sim`` (see sim/README.md).
"""
