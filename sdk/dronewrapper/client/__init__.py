"""The drone client: one class every program reaches a drone through (see
:mod:`dronewrapper.client.drone_client`); the SDK's blocking ``DroneWrapper`` stands on it."""

from dronewrapper.client.calls import Pending
from dronewrapper.client.drone_client import STATE_FRESH_S, DroneClient
from dronewrapper.client.inputs import Inputs

__all__ = ["STATE_FRESH_S", "DroneClient", "Inputs", "Pending"]
