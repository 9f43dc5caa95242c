"""Rendering the simulated cameras with numpy and OpenCV: pinhole projection, ground and sky,
the red beacon, procedural people or photo billboards. Pure: no I/O but reading sprites."""
