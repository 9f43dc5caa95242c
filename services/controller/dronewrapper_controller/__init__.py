"""Visual-servoing controller: follows a colour blob or a person with three PIDs (vx, vz, yaw rate).

Pure parts (no I/O, no clocks): :mod:`pid`, :mod:`errors`, :mod:`servo`, :mod:`loop`,
:mod:`inputs`. The process: :mod:`node` (one loop that never blocks, commanding through
:class:`dronewrapper.client.DroneClient`; run as ``python -m dronewrapper_controller``). Flight
evaluation lives on the test/demo side, in :mod:`dronewrapper_sim.evaluation`.
"""
