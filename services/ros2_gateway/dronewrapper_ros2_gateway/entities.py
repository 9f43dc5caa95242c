"""Which registry key is which ROS 2 entity (pure).

Our keys are MAVROS's names, so a key's ROS 2 name is ``/`` + the key: ``drone/mavros/state``
is ``/drone/mavros/state``. Each entity here is a key without its namespace, its registry entry,
the ROS 2 type, which way it goes and the QoS its token announces.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from dronewrapper.msgs import registry
from dronewrapper.runtime.ports import Ports
from dronewrapper_ros2_codec.convert import ROS_SERVICES, ROS_TYPES
from dronewrapper_ros2_codec.names import BEST_EFFORT, qos_text

OUT, IN, SERVE = "out", "in", "serve"

TELEMETRY_QOS = qos_text(depth=10)
"""rclcpp's ``QoS(10)``: reliable, volatile, keep last 10 (what MAVROS 2 publishes with)."""
SENSOR_QOS = qos_text(reliability=BEST_EFFORT, depth=5)
"""rclcpp's ``SensorDataQoS``: best effort, keep last 5 (camera drivers)."""
SERVICE_QOS = qos_text(depth=10)
"""rmw's services default: reliable, volatile, keep last 10."""


@dataclass(frozen=True)
class Entity:
    """One ROS 2 topic or service of a drone.

    ``registry_entry`` is the Topic or Service; ``parts`` fill its key's other fields.
    """

    name: str
    registry_entry: Any
    direction: str
    parts: tuple[tuple[str, str], ...] = ()

    @property
    def ros_type(self) -> str:
        """``pkg/msg/Name`` of a topic, ``pkg/srv/Name`` of a service."""
        if self.direction == SERVE:
            return ROS_SERVICES[self.registry_entry.request]
        return ROS_TYPES[self.registry_entry.type]

    @property
    def qos(self) -> str:
        if self.direction == SERVE:
            return SERVICE_QOS
        if self.registry_entry.transport == registry.STREAM:
            return SENSOR_QOS
        return TELEMETRY_QOS

    def key(self, ns: str) -> str:
        """Our key of this entity for drone ``ns``."""
        return self.registry_entry.key(ns, **dict(self.parts))

    def ros_name(self, ns: str) -> str:
        """Its ROS 2 name for drone ``ns`` (``/drone/mavros/state``)."""
        return "/" + self.key(ns)


def _entities() -> dict[str, Entity]:
    out = [
        Entity("mavros/state", registry.STATE, OUT),
        Entity("mavros/extended_state", registry.EXTENDED_STATE, OUT),
        Entity("mavros/local_position/pose", registry.LOCAL_POSE, OUT),
        Entity("mavros/local_position/velocity_body", registry.VELOCITY_BODY, OUT),
        Entity("mavros/local_position/velocity_local", registry.VELOCITY_LOCAL, OUT),
        Entity("mavros/global_position/global", registry.GLOBAL_POSITION, OUT),
        Entity("mavros/battery", registry.BATTERY, OUT),
        Entity("mavros/setpoint_raw/local", registry.SETPOINT_RAW_LOCAL, IN),
        Entity("mavros/cmd/arming", registry.ARMING, SERVE),
        Entity("mavros/cmd/takeoff", registry.TAKEOFF, SERVE),
        Entity("mavros/cmd/land", registry.LAND, SERVE),
        Entity("mavros/set_mode", registry.SET_MODE, SERVE),
        Entity("mavros/param/get", registry.PARAM_GET, SERVE),
        Entity("mavros/param/set", registry.PARAM_SET, SERVE),
    ]
    for camera in registry.CAMERAS:
        parts = (("camera", camera),)
        out.append(Entity(f"{camera}/image_raw", registry.IMAGE_RAW, OUT, parts))
        out.append(Entity(f"{camera}/image_raw/compressed", registry.IMAGE_COMPRESSED, OUT, parts))
    return {e.name: e for e in out}


ENTITIES: dict[str, Entity] = _entities()
"""Every entity the gateway can present, by name (a key without its namespace)."""

PORTS = Ports(
    "ros2_gateway",
    publishes={e.registry_entry for e in ENTITIES.values() if e.direction == IN},
    subscribes={
        registry.STATE,  # presence.py: which drones are online
        *(e.registry_entry for e in ENTITIES.values() if e.direction == OUT),
    },
    calls={e.registry_entry for e in ENTITIES.values() if e.direction == SERVE},
)
"""What the gateway publishes, subscribes to and calls on the registry's keys: what its
entities can carry (:mod:`dronewrapper.runtime.ports`); the ROS 2 side is declared on its
session."""


def selected(keys: list[str]) -> list[Entity]:
    """The entities named in ``keys`` (empty: all), in table order."""
    return [e for name, e in ENTITIES.items() if not keys or name in keys]
