#!/usr/bin/env python
from dronewrapper import DroneWrapper  # noqa: I001 (the paper's order)
from time import sleep

drone = DroneWrapper()
drone.takeoff(h=2.5)
drone.set_cmd_vel(az=1)  # spin
sleep(5)  # wait for a few seconds
drone.land()
