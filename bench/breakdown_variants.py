"""The variants of ``bench.transport_breakdown``'s 64-byte round trip, and how each opens
its Zenoh sessions, publishers and subscribers (what a variant changes: that module's
docstring)."""

from __future__ import annotations

from dataclasses import dataclass, field

import zenoh

from dronewrapper.msgs import CompressedImage, Header, codec
from dronewrapper.runtime import Node
from dronewrapper.runtime.options import ZenohOptions, zenoh_config
from dronewrapper.runtime.session import encoding_for
from dronewrapper.runtime.thread_state import KEPT

PING_KEY, PONG_KEY = "bench/breakdown/ping", "bench/breakdown/pong"
DATA = bytes(64)
LOW_LATENCY = {"transport/unicast/lowlatency": "true", "transport/unicast/qos/enabled": "false"}
NO_QOS = {"transport/unicast/qos/enabled": "false"}
NO_BATCHING = {"transport/link/tx/queue/batching/enabled": "false"}
ONE_RX = {"ZENOH_RUNTIME": "(rx: (worker_threads: 1))"}
TWO_RX = {"ZENOH_RUNTIME": "(rx: (worker_threads: 2))"}  # the binding's default
SUMMARY = (
    "binding defaults",
    "direct callbacks both",
    "thread states kept",
    "lowlatency transport",
    "one rx thread",
    "recv ping, direct echo, lowlatency, one rx thread",
    "ours: Node defaults",
    "ours: low_latency",
    "socket",
)
"""The variants ``bench.transport`` prints (names containing one of these)."""


@dataclass(frozen=True)
class Variant:
    """One way of doing the 64-byte round trip (see the module docstring)."""

    name: str
    ping: str = "indirect"
    echo: str = "indirect"
    put: str = "publisher"
    config: dict[str, str] = field(default_factory=dict)
    router: bool = False
    priority: str = "DATA"
    congestion: str = "BLOCK"
    env: dict[str, str] = field(default_factory=dict)
    encoding: bool = False
    """Declare the plain publishers with our encoding (MessagePack and the type's schema)."""
    layer: str = "zenoh"
    """``zenoh``: plain zenoh-python bytes; ``ours``: a Node on each end, a 64-byte
    CompressedImage typed, encoded and decoded (``ping``/``echo``: ``indirect`` or ``direct``
    callbacks; ``config`` LOW_LATENCY becomes ``ZenohOptions.low_latency``); ``ours_ping``,
    ``ours_echo``: a Node on that end only."""


VARIANTS = (
    Variant("binding defaults (callbacks on Python threads)"),
    Variant("express publisher", put="express"),
    Variant("session.put", put="session"),
    Variant("with our encoding (schema)", encoding=True),
    Variant("congestion DROP", congestion="DROP"),
    Variant("priority INTERACTIVE_HIGH", priority="INTERACTIVE_HIGH"),
    Variant("QoS off", config=NO_QOS),
    Variant("batching off", config=NO_BATCHING),
    Variant("lowlatency transport (QoS off)", config=LOW_LATENCY),
    Variant("direct callbacks both ends", ping="direct", echo="direct"),
    Variant("recv threads both ends", ping="recv", echo="recv"),
    Variant("direct, thread states kept", ping="kept", echo="kept"),
    Variant("direct, thread states kept, lowlatency", ping="kept", echo="kept", config=LOW_LATENCY),
    Variant("recv ping, direct echo", ping="recv", echo="direct"),
    Variant("recv ping, direct echo, lowlatency", ping="recv", echo="direct", config=LOW_LATENCY),
    Variant("direct both ends, lowlatency", ping="direct", echo="direct", config=LOW_LATENCY),
    Variant("one rx thread", env=ONE_RX),
    Variant(
        "direct both ends, lowlatency, one rx thread",
        ping="direct",
        echo="direct",
        config=LOW_LATENCY,
        env=ONE_RX,
    ),
    Variant(
        "recv ping, direct echo, lowlatency, one rx thread",
        ping="recv",
        echo="direct",
        config=LOW_LATENCY,
        env=ONE_RX,
    ),
    Variant("ours: Node defaults", layer="ours"),
    Variant("ours: ping only", layer="ours_ping"),
    Variant("ours: echo only", layer="ours_echo"),
    Variant("ours: direct callbacks both ends", ping="direct", echo="direct", layer="ours"),
    Variant("ours: low_latency, two rx threads", config=LOW_LATENCY, env=TWO_RX, layer="ours"),
    Variant("ours: low_latency (one rx thread)", config=LOW_LATENCY, layer="ours"),
    Variant(
        "ours: low_latency, direct callbacks",
        ping="direct",
        echo="direct",
        config=LOW_LATENCY,
        layer="ours",
    ),
    Variant("through a router", router=True),
    Variant("through a router, direct callbacks", ping="direct", echo="direct", router=True),
)
SOCKET = "socket (rospy's design, plain Python TCP)"


def session_config(variant: Variant, mode: str, connect: list[str], listen: list[str]):
    """The runtime's own session configuration plus the variant's knobs."""
    conf = zenoh_config(ZenohOptions(mode=mode, connect=connect, listen=listen))
    for key, value in variant.config.items():
        conf.insert_json5(key, value)
    return conf


def qos(variant: Variant) -> dict[str, object]:
    """The variant's publisher options."""
    return {
        "priority": getattr(zenoh.Priority, variant.priority),
        "congestion_control": getattr(zenoh.CongestionControl, variant.congestion),
        "express": variant.put == "express",
    }


def publisher(session: zenoh.Session, key: str, variant: Variant):
    """A ``put(bytes)`` for ``key`` in the variant's way."""
    options = qos(variant)
    if variant.encoding:
        options["encoding"] = encoding_for(CompressedImage)
    if variant.put == "session":
        return lambda payload: session.put(key, payload, **options)
    return session.declare_publisher(key, **options).put


def subscribe(session: zenoh.Session, key: str, how: str, on_payload):
    """Subscribe ``on_payload(bytes)`` to ``key``; for ``recv`` the subscriber is returned
    and the caller receives itself."""
    if how == "recv":
        return session.declare_subscriber(key, zenoh.handlers.FifoChannel(64))
    if how == "kept":  # direct, and Zenoh's thread keeps its Python thread state

        def on_sample(sample: zenoh.Sample) -> None:
            KEPT.keep()
            on_payload(sample.payload.to_bytes())

        return session.declare_subscriber(key, zenoh.handlers.Callback(on_sample, indirect=False))
    handler = zenoh.handlers.Callback(
        lambda sample: on_payload(sample.payload.to_bytes()), indirect=how == "indirect"
    )
    return session.declare_subscriber(key, handler)


def node_for(variant: Variant, side: str, mode: str, connect: list[str], listen: list[str]):
    """Our runtime's Node for one end of an ``ours`` variant."""
    options = ZenohOptions(
        mode=mode,
        connect=connect,
        listen=listen,
        low_latency=variant.config.get("transport/unicast/lowlatency") == "true",
    )
    direct = getattr(variant, side) == "direct"
    return Node(f"breakdown_{side}", options, handle_signals=False, linger=0.0,
                direct_callbacks=direct)  # fmt: skip


def small_message() -> CompressedImage:
    """64 bytes of data in a typed message, stamped now."""
    return CompressedImage(header=Header.now("small"), format="raw", data=DATA)


PAYLOAD = codec.encode(small_message())
"""What plain Zenoh sends: the encoded typed message (so an ``ours`` end decodes it)."""
