"""Controller: follows a colour blob or a person with three PIDs (vx, vz, yaw rate).

Subscribes {ns}/perception/detections, commands the aircraft through the DroneWrapper SDK
(setpoints on {ns}/mavros/setpoint_raw/local) and publishes {ns}/controller/status.
"""

from dronewrapper.runtime.service import run_service
from dronewrapper_controller.config import Config
from dronewrapper_controller.node import run

raise SystemExit(run_service("controller", __doc__, Config, run))
