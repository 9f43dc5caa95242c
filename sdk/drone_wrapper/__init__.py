"""The paper's module name: ``from drone_wrapper import DroneWrapper`` works as in 2022.

Everything here is :mod:`dronewrapper`'s public API under the original import path.
"""

import dronewrapper
from dronewrapper import *  # noqa: F403 - the same names, by definition

__all__ = dronewrapper.__all__
