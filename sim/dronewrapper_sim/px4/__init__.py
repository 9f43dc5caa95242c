"""A PX4-like autopilot: modes, commander, offboard setpoints, parameters and telemetry.

The behaviour reproduced is the one measured on real PX4 SITL (see sim/README.md). Everything in
this package is pure logic (time is passed in as arguments); MAVLink sockets live in
``dronewrapper_sim.mavlink_io``.
"""
