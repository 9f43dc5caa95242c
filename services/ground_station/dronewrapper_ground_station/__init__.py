"""Web ground station: watch, teleoperate and command drones and the simulated world.

Pure parts (no I/O, time injected): :mod:`access` (who may do what), :mod:`teleop` (stick
validation and the dead-man), :mod:`snapshot` (telemetry with ages and staleness),
:mod:`frames` (latest-only video slots). The process: :mod:`node` (``dronewrapper station``),
the HTTP/WebSocket routes in :mod:`app`, the bus side in :mod:`fleet`.
"""
