"""The gateway's config schema (strict: unknown keys are errors naming the key)."""

from __future__ import annotations

from typing import Annotated, Literal

import msgspec

from dronewrapper.runtime.config_ranges import Positive, check_ranges

MAX_DOMAIN_ID = 232
"""The highest ROS_DOMAIN_ID (ROS 2's limit, and PX4's ZENOH_DOMAIN_ID's)."""


class Config(msgspec.Struct, kw_only=True, forbid_unknown_fields=True):
    """What the gateway presents, and to which ROS 2 graph.

    Attributes:
        domain_id: the ROS_DOMAIN_ID of the ROS 2 graph (0-232), the first chunk of every key.
        drones: the namespaces presented (each as ``/<ns>/mavros/...``); empty: the process's
            own ``--namespace``.
        keys: the entities presented, by key without the namespace (``mavros/state``,
            ``mavros/cmd/arming``, ``cam_frontal/image_raw`` ...); empty: every one of
            :data:`dronewrapper_ros2_gateway.entities.ENTITIES`.
        node_name: the ROS 2 node each drone appears as (in namespace ``/<ns>``).
        ros_connect: endpoints of the ROS 2 graph's router (``rmw_zenohd``) when it is not
            the drone's router; empty: the ROS 2 entities live on the drone's router.
        ros_mode: the Zenoh mode of that second session (``peer`` or ``client``).
        commander: the name the gateway commands under on the command lease; empty: the
            identity's name, else ``ros2_gateway``.
        service_timeout_s: how long a ROS 2 service call waits for the bridge's reply (s).
        image_check_s: how often the gateway checks whether a ROS 2 subscriber wants images,
            subscribing to a camera only while one does (s).
    """

    domain_id: Annotated[int, msgspec.Meta(ge=0, le=MAX_DOMAIN_ID)] = 0
    drones: list[str] = msgspec.field(default_factory=list)
    keys: list[str] = msgspec.field(default_factory=list)
    node_name: str = "mavros"
    ros_connect: list[str] = msgspec.field(default_factory=list)
    ros_mode: Literal["peer", "client"] = "peer"
    commander: str = ""
    service_timeout_s: Positive = 15.0
    image_check_s: Positive = 0.5

    def __post_init__(self) -> None:
        from dronewrapper_ros2_gateway.entities import ENTITIES

        check_ranges(self)
        for ns in self.drones:
            if not ns or "/" in ns or "*" in ns:
                raise ValueError(f"drones: {ns!r} is not a namespace (one key chunk)")
        unknown = [k for k in self.keys if k not in ENTITIES]
        if unknown:
            raise ValueError(
                f"keys: unknown {', '.join(unknown)}; known: {', '.join(sorted(ENTITIES))}"
            )
        if not self.node_name or "/" in self.node_name:
            raise ValueError(f"node_name must be a ROS node name, got {self.node_name!r}")
