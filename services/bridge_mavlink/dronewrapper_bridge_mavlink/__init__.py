"""bridge_mavlink: MAVLink (PX4, ArduPilot) <-> DroneWrapper's MAVROS-equivalent Zenoh keys.

Pure modules (no I/O, no clocks): :mod:`.frames`, :mod:`.modes`, :mod:`.setpoints`,
:mod:`.telemetry`, :mod:`.commands`, :mod:`.failsafe`. I/O: :mod:`.link` (the MAVLink
connection) and :mod:`.node` (the service process).
"""
