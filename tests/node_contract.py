"""The node contract's checks, run against every class that claims it.

:func:`check_node` takes two nodes on one bus (``a``, ``b``: the same namespace) and
``settle(predicate, what)``, which returns once ``predicate()`` holds: at once on the fake bus
(delivery is synchronous), by waiting on a real router. tests/unit/test_node_contract.py runs it
on :class:`~dronewrapper.runtime.fake.FakeNode`; tests/integration/test_runtime_node_contract.py
on :class:`~dronewrapper.runtime.node.Node` with a loopback router. :func:`check_ports` takes a
node made with :data:`PORTS` and one without: the first refuses what its ports do not declare.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import pytest

from dronewrapper.msgs import registry
from dronewrapper.msgs.control import ControllerStatus
from dronewrapper.msgs.mavros import CommandBool, CommandBoolResult
from dronewrapper.msgs.std import Header
from dronewrapper.runtime.clock import Clock
from dronewrapper.runtime.contract import NodeApi, PublisherApi
from dronewrapper.runtime.errors import ServiceError, ServiceUnavailable
from dronewrapper.runtime.ports import PortRefused, Ports

Settle = Callable[[Callable[[], object], str], None]

PORTS = Ports(
    "contract",
    publishes=(registry.CONTROLLER_STATUS,),
    subscribes=(registry.CONTROLLER_STATUS,),
    serves=(registry.ARMING,),
    calls=(registry.ARMING,),
)
"""The ports :func:`check_ports`'s limited node is made with."""


def status(seq: int) -> ControllerStatus:
    return ControllerStatus(header=Header(seq=seq), mode="contract", state="idle")


def check_node(a: NodeApi, b: NodeApi, settle: Settle) -> None:
    """Every promise of :class:`~dronewrapper.runtime.contract.NodeApi`, on ``a`` and ``b``."""
    for node in (a, b):
        assert isinstance(node, NodeApi), f"{type(node).__name__} misses part of the contract"
        assert isinstance(node.clock, Clock)
        assert node.ns == "drone" and not node.stopping
    check_publish_subscribe(a, b, settle)
    check_latest(a, b, settle)
    check_services(a, b)
    check_liveliness(a, b, settle)
    check_matching(a, b, settle)
    check_stop(a)


def check_publish_subscribe(a: NodeApi, b: NodeApi, settle: Settle) -> None:
    got: list[ControllerStatus] = []
    keyed: list[tuple[str, ControllerStatus]] = []
    sub = b.subscribe(registry.CONTROLLER_STATUS, got.append)
    b.subscribe(
        registry.CONTROLLER_STATUS,
        lambda key, msg: keyed.append((key, msg)),
        key=registry.CONTROLLER_STATUS.wildcard(),
        keyed=True,
    )
    pub = a.publisher(registry.CONTROLLER_STATUS)
    assert isinstance(pub, PublisherApi) and pub.key == "drone/controller/status"
    settle(pub.watched, "the subscriber matched")
    with pytest.raises(TypeError, match="carries ControllerStatus"):
        pub.put(CommandBool(value=True))  # type: ignore[arg-type]
    pub.put(status(1))
    settle(lambda: got and keyed, "the message delivered")
    assert got[0].header.seq == 1 and keyed[0] == ("drone/controller/status", got[0])
    assert pub.count == 1
    sub.undeclare()
    pub.put(status(2))
    settle(lambda: len(keyed) == 2, "the second message to the keyed subscriber")
    assert len(got) == 1, "an undeclared subscription hears nothing more"


def check_latest(a: NodeApi, b: NodeApi, settle: Settle) -> None:
    holder = b.latest(registry.CONTROLLER_STATUS)
    assert holder.value is None and math.isinf(holder.age())
    assert holder.clock is b.clock, "a node's holders age on its clock"
    pub = a.publisher(registry.CONTROLLER_STATUS)
    settle(pub.watched, "the holder's subscription matched")
    pub.put(status(7))
    settle(lambda: holder.value is not None, "the holder filled")
    assert holder.wait(1.0).header.seq == 7
    assert 0.0 <= holder.age() < 5.0


def check_services(a: NodeApi, b: NodeApi) -> None:
    def arming(request: CommandBool) -> CommandBoolResult:
        if not request.value:
            raise ValueError("refuses to disarm")
        return CommandBoolResult(success=True)

    a.serve(registry.ARMING, arming)
    assert b.call(registry.ARMING, CommandBool(value=True), timeout=5.0).success
    with pytest.raises(ServiceError, match="refuses to disarm") as refused:
        b.call(registry.ARMING, CommandBool(value=False), timeout=5.0)
    assert refused.value.code == "bad_request"
    with pytest.raises(ServiceUnavailable):
        b.call(registry.ARMING, CommandBool(value=True), ns="nobody", timeout=0.3)


def check_liveliness(a: NodeApi, b: NodeApi, settle: Settle) -> None:
    token = registry.ALIVE.key("drone", service=a.name)
    a.announce()
    settle(lambda: token in b.alive_services("drone"), "the token seen")
    assert token in b.alive_services("*") and not b.alive_services("nobody")
    assert b.linked()


def check_matching(a: NodeApi, b: NodeApi, settle: Settle) -> None:
    changes: list[bool] = []
    pub = a.publisher(registry.SETPOINT_RAW_LOCAL)
    listener = pub.on_matching(changes.append)
    sub = b.subscribe(registry.SETPOINT_RAW_LOCAL, lambda msg: None)
    settle(lambda: changes[-1:] == [True], "matching heard")
    sub.undeclare()
    settle(lambda: changes[-1:] == [False], "not matching heard")
    listener.undeclare()


def check_stop(node: NodeApi) -> None:
    assert node.sleep(0.01) is True
    node.stop()
    assert node.stopping and node.stop_event.is_set()
    assert node.sleep(10.0) is False, "a stopped node's sleep returns at once"


def check_ports(limited: NodeApi, free: NodeApi, settle: Settle) -> None:
    """``limited`` (made with :data:`PORTS`) does what they declare, on any namespace and
    through wildcards, and refuses the rest naming the key, the process and what it declared;
    ``free`` (no ports) may do anything."""
    topic = registry.CONTROLLER_STATUS
    keyed: list[tuple[str, ControllerStatus]] = []
    limited.subscribe(
        topic, lambda key, msg: keyed.append((key, msg)), key=topic.wildcard(), keyed=True
    )
    holder = limited.latest(topic, key=topic.key("drone7"))
    pub = limited.publisher(topic, key=topic.key("drone7"))  # another namespace: the same port
    settle(pub.watched, "the limited node's subscriptions matched")
    pub.put(status(3))
    settle(lambda: keyed and holder.value is not None, "delivered to the limited node")
    assert keyed[0][0] == "drone7/controller/status" and holder.wait(1.0).header.seq == 3
    limited.serve(registry.ARMING, lambda request: CommandBoolResult(success=request.value))
    assert free.call(registry.ARMING, CommandBool(value=True), timeout=5.0).success

    state = registry.STATE
    refusals: list[tuple[str, Callable[[], object]]] = [
        ("publish", lambda: limited.publisher(state)),
        ("subscribe to", lambda: limited.subscribe(state, lambda msg: None)),
        (
            "subscribe to",
            lambda: limited.subscribe(state, print, key=state.wildcard(), keyed=True),
        ),
        ("subscribe to", lambda: limited.latest(state, key=state.key("drone3"))),
        ("serve", lambda: limited.serve(registry.TAKEOFF, lambda request: None)),
        ("call", lambda: limited.call(registry.LAND, CommandBool(value=True), timeout=0.1)),
    ]
    for verb, attempt in refusals:
        with pytest.raises(PortRefused, match=f"^contract does not {verb} ") as refused:
            attempt()
        message = str(refused.value)
        assert "{ns}/" in message and "it declares " in message, message
    with pytest.raises(PortRefused, match=r"publishes \['{ns}/controller/status'\]"):
        limited.publisher(registry.DETECTIONS)
    free.publisher(state)  # a node without ports: unrestricted
    free.serve(registry.TAKEOFF, lambda request: None)
