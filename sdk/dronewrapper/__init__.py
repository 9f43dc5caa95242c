"""DroneWrapper: fly real or simulated drones and run vision apps in a few lines of Python.

    from dronewrapper import DroneWrapper
    drone = DroneWrapper()
    drone.takeoff(h=2.5)
    drone.set_cmd_vel(az=1)   # spin
    drone.land()

The SDK talks to the aircraft's bridge over Zenoh (see DESIGN.md for keys, frames and units).
"""

__version__ = "0.1.0"
