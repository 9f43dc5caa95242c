"""Perception service: colour blobs, YOLOX/HOG people detection and target tracking.

Pure modules: :mod:`color_filter`, :mod:`yolox` (helpers), :mod:`tracking`; the process:
:mod:`node` (``python -m dronewrapper_perception``); offline: :mod:`detect_cli`.
"""
