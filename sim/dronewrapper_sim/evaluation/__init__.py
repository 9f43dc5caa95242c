"""Judging follow flights from the simulator's ground truth (test and demo side, not flown).

:mod:`metrics` (pure): bearing, elevation and distance to the target and a flight summary;
:mod:`boxes` (pure): each person's box in the camera and which person a detection is;
:mod:`monitor`: records a flight from ``{ns}/sim/ground_truth``, the world objects' poses and
the controller's status. Used by ``make demo`` (``dronewrapper_compose.demo``), the scenario
tests and the benchmarks; the controller process imports none of it.
"""
