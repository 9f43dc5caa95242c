"""The uORB topics the bridge uses on PX4's Zenoh, with their px4_msgs types, and their keys.

PX4's ``zenoh`` module publishes ``/fmu/out/<topic>`` and subscribes to ``/fmu/in/<topic>`` under
rmw_zenoh's data keys, ``<domain>/fmu/out/<topic>/px4_msgs::msg::dds_::<Type>_/RIHS01_<hash>``
(``dds_topics.yaml`` of the module lists them; the domain is ``ZENOH_DOMAIN_ID``, 0 by default).
"""

from __future__ import annotations

from dataclasses import dataclass

from dronewrapper_bridge_px4_zenoh.px4_msgs import full_name
from dronewrapper_ros2_codec.interfaces import dds_type_name

OUT, IN = "out", "in"


@dataclass(frozen=True)
class Px4Topic:
    """One uORB topic on Zenoh: its ROS name (``/fmu/out/vehicle_status``), its px4_msgs type
    (short name) and whether PX4 publishes it (``out``) or reads it (``in``)."""

    name: str
    type: str

    @property
    def direction(self) -> str:
        return OUT if self.name.startswith("/fmu/out/") else IN

    @property
    def type_name(self) -> str:
        """The full type name, ``px4_msgs/msg/VehicleStatus``."""
        return full_name(self.type)

    def key(self, domain: int, type_hash: str) -> str:
        """The data key for one firmware's hash of the type."""
        return f"{domain}/{self.name.strip('/')}/{dds_type_name(self.type_name)}/{type_hash}"

    def any_version(self, domain: int) -> str:
        """A key expression matching the topic whatever the type's name and hash (to learn them)."""
        return f"{domain}/{self.name.strip('/')}/*/*"


VEHICLE_STATUS = Px4Topic("/fmu/out/vehicle_status", "VehicleStatus")
LOCAL_POSITION = Px4Topic("/fmu/out/vehicle_local_position", "VehicleLocalPosition")
ATTITUDE = Px4Topic("/fmu/out/vehicle_attitude", "VehicleAttitude")
GLOBAL_POSITION = Px4Topic("/fmu/out/vehicle_global_position", "VehicleGlobalPosition")
BATTERY = Px4Topic("/fmu/out/battery_status", "BatteryStatus")
LAND_DETECTED = Px4Topic("/fmu/out/vehicle_land_detected", "VehicleLandDetected")
COMMAND_ACK = Px4Topic("/fmu/out/vehicle_command_ack", "VehicleCommandAck")
COMMAND = Px4Topic("/fmu/in/vehicle_command", "VehicleCommand")
OFFBOARD_MODE = Px4Topic("/fmu/in/offboard_control_mode", "OffboardControlMode")
TRAJECTORY = Px4Topic("/fmu/in/trajectory_setpoint", "TrajectorySetpoint")

TOPICS: tuple[Px4Topic, ...] = (
    VEHICLE_STATUS,
    LOCAL_POSITION,
    ATTITUDE,
    GLOBAL_POSITION,
    BATTERY,
    LAND_DETECTED,
    COMMAND_ACK,
    COMMAND,
    OFFBOARD_MODE,
    TRAJECTORY,
)
BY_NAME: dict[str, Px4Topic] = {t.name: t for t in TOPICS}


@dataclass(frozen=True)
class DataKey:
    """A data key read back: domain, ROS topic name (leading slash), DDS type name, hash."""

    domain: int
    topic: str
    type_name: str
    type_hash: str


def parse_key(key: str) -> DataKey | None:
    """The parts of a ``<domain>/fmu/.../<type>/<hash>`` data key, or None if it is not one."""
    parts = key.split("/")
    if len(parts) < 5 or parts[1] != "fmu":
        return None
    try:
        domain = int(parts[0])
    except ValueError:
        return None
    return DataKey(domain, "/" + "/".join(parts[1:-2]), parts[-2], parts[-1])
