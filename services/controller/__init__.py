"""Visual-servoing controller: follows a colour blob or a person with three PIDs (vx, vz, yaw rate).

Pure parts (no I/O, no clocks): :mod:`pid`, :mod:`errors`, :mod:`servo`. The process:
:mod:`node` (run as ``python -m dronewrapper_controller``).
"""
