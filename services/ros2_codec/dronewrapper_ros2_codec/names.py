"""rmw_zenoh's names on Zenoh: data keys, liveliness tokens and their QoS field.

- data key: ``<domain>/<ROS name without outer slashes>/<pkg>::msg::dds_::<Name>_/<hash>``
  (services: ``::srv::``), rmw_zenoh's ``TopicInfo`` (``liveliness_utils.cpp``);
- node token: ``@ros2_lv/<domain>/<zid>/<nid>/<nid>/NN/<enclave>/<namespace>/<node>``;
- endpoint token: ``@ros2_lv/<domain>/<zid>/<nid>/<eid>/<MP|MS|SS|SC>/<enclave>/<namespace>/
  <node>/<topic>/<type>/<hash>/<qos>``, every name with ``/`` written as ``%`` and an empty
  enclave or namespace as ``%`` (root);
- QoS: ``<rel>:<dur>:<hist>,<depth>:<deadline s>,<ns>:<lifespan s>,<ns>:<liveliness>,<s>,<ns>``,
  each part empty where it equals rmw_zenoh's default (reliable, volatile, keep last 42,
  infinite deadline and lifespan, automatic liveliness), else the ``rmw/types.h`` number.

    >>> topic_key(0, "/drone/mavros/state", "mavros_msgs/msg/State", "RIHS01_ab")
    '0/drone/mavros/state/mavros_msgs::msg::dds_::State_/RIHS01_ab'
    >>> qos_text(depth=10)
    '::,10:,:,:,,'
"""

from __future__ import annotations

from dataclasses import dataclass

from dronewrapper_ros2_codec.interfaces import dds_type_name

ADMIN = "@ros2_lv"
NODE, PUBLISHER, SUBSCRIBER, SERVICE, CLIENT = "NN", "MP", "MS", "SS", "SC"
ENDPOINT_KINDS = (PUBLISHER, SUBSCRIBER, SERVICE, CLIENT)

RELIABLE, BEST_EFFORT = 1, 2
VOLATILE, TRANSIENT_LOCAL = 2, 1
KEEP_LAST, KEEP_ALL = 1, 2
DEFAULT_DEPTH = 42
"""rmw_zenoh's default history depth (``qos.cpp``): a depth equal to it is written empty."""


def mangle(name: str) -> str:
    """A ROS name as one key chunk: every ``/`` becomes ``%`` (``""`` becomes ``%``)."""
    return name.replace("/", "%") if name else "%"


def demangle(chunk: str) -> str:
    return chunk.replace("%", "/")


def topic_key(domain: int, ros_name: str, type_name: str, type_hash: str) -> str:
    """The data key of a topic or service (``type_name``: ``pkg/msg/Name`` or ``pkg/srv/Name``)."""
    return f"{domain}/{ros_name.strip('/')}/{dds_type_name(type_name)}/{type_hash}"


def qos_text(
    *,
    reliability: int = RELIABLE,
    durability: int = VOLATILE,
    history: int = KEEP_LAST,
    depth: int = DEFAULT_DEPTH,
) -> str:
    """The QoS chunk of an endpoint token as rmw_zenoh's ``qos_to_keyexpr`` writes it
    (deadline, lifespan and liveliness at their defaults)."""
    rel = "" if reliability == RELIABLE else str(reliability)
    dur = "" if durability == VOLATILE else str(durability)
    hist = "" if history == KEEP_LAST else str(history)
    dep = "" if depth == DEFAULT_DEPTH else str(depth)
    return f"{rel}:{dur}:{hist},{dep}:,:,:,,"


@dataclass(frozen=True)
class NodeName:
    """Where a ROS 2 node lives: domain, Zenoh session id, node id, enclave, namespace, name."""

    domain: int
    zid: str
    node_id: int
    namespace: str
    name: str
    enclave: str = ""

    def token(self) -> str:
        return (
            f"{ADMIN}/{self.domain}/{self.zid}/{self.node_id}/{self.node_id}/{NODE}/"
            f"{mangle(self.enclave)}/{mangle(self.namespace)}/{mangle(self.name)}"
        )

    def endpoint_token(
        self, entity_id: int, kind: str, ros_name: str, type_name: str, type_hash: str, qos: str
    ) -> str:
        """The liveliness token of one publisher, subscriber, service or client of this node."""
        if kind not in ENDPOINT_KINDS:
            raise ValueError(f"endpoint kind must be one of {ENDPOINT_KINDS}, got {kind!r}")
        return (
            f"{ADMIN}/{self.domain}/{self.zid}/{self.node_id}/{entity_id}/{kind}/"
            f"{mangle(self.enclave)}/{mangle(self.namespace)}/{mangle(self.name)}/"
            f"{mangle(ros_name)}/{mangle(dds_type_name(type_name))}/{mangle(type_hash)}/{qos}"
        )


@dataclass(frozen=True)
class Endpoint:
    """A publisher, subscriber, service or client read back from a liveliness token."""

    domain: int
    zid: str
    kind: str
    node: str  # fully qualified: /namespace/name
    topic: str  # the ROS name, with its leading slash
    type_name: str  # DDS-mangled: pkg::msg::dds_::Name_
    type_hash: str  # RIHS01_<hex>, or TypeHashNotSupported (Humble)
    qos: str


def parse_endpoint(token: str) -> Endpoint | None:
    """The endpoint a liveliness token announces, or None (a node token, or not rmw_zenoh's).

    Accepts the optional 14th chunk later distros add (``backends:...``).
    """
    parts = token.split("/")
    if len(parts) < 13 or parts[0] != ADMIN or parts[5] not in ENDPOINT_KINDS:
        return None
    try:
        domain = int(parts[1])
    except ValueError:
        return None
    namespace = demangle(parts[7])
    node = namespace.rstrip("/") + "/" + demangle(parts[8])
    return Endpoint(
        domain=domain,
        zid=parts[2],
        kind=parts[5],
        node=node,
        topic=demangle(parts[9]),
        type_name=demangle(parts[10]),
        type_hash=demangle(parts[11]),
        qos=parts[12],
    )
