"""The runtime through a real Zenoh router, between real processes."""

from __future__ import annotations

import signal
import sys
import time

import pytest

from dronewrapper.msgs import CommandBool, CommandTOL, ControllerStatus, codec, registry
from dronewrapper.runtime import ServiceError, ServiceUnavailable
from support import REPO, client_node, python_module, wait_for

pytestmark = pytest.mark.integration
TOY = str(REPO / "tests" / "data" / "toy_service.py")


def toy_argv(router: str, *extra: str, ns: str = "drone") -> list[str]:
    return [sys.executable, TOY, "--connect", router, "--namespace", ns, *extra]


def alive(node, name: str) -> bool:
    key = registry.ALIVE.key(node.ns, service=name)
    return any(r.ok for r in node.session.liveliness().get(key, timeout=1.0))


def test_undecodable_bytes_are_counted_and_the_subscriber_keeps_working(router, spawn):
    toy = spawn(toy_argv(router), "toy")
    with client_node(router) as node:
        received = []
        node.subscribe(registry.CONTROLLER_STATUS, received.append)
        wait_for(lambda: alive(node, "toy"), 20, what="toy liveliness")
        key = registry.CONTROLLER_STATUS.key("drone")
        for garbage in (b"\xc1\xc1", b"not msgpack", codec.encode({"header": 3}), b""):
            node.session.put(key, garbage)
        wait_for(lambda: node.decode_errors[key] >= 4, 10, what="4 decode errors counted")
        before = len(received)
        wait_for(lambda: len(received) > before + 5, 10, what="valid messages after garbage")
        assert all(isinstance(m, ControllerStatus) for m in received)
    assert toy.alive(), "garbage on its key must not hurt the publisher either"
    assert toy.stop() == 0


def test_echo_prints_decoded_messages_and_flags_garbage(router, spawn):
    spawn(toy_argv(router), "toy")
    with client_node(router) as node:
        wait_for(lambda: alive(node, "toy"), 20, what="toy liveliness")
        echo = spawn(
            python_module("dronewrapper", "echo", "drone/controller/**", "--connect", router,
                          "--count", "8"),
            "echo",
        )  # fmt: skip
        time.sleep(1.0)
        node.session.put(registry.CONTROLLER_STATUS.key("drone"), b"\xc1")
        wait_for(lambda: not echo.alive(), 20, what="echo to print 8 messages and exit")
    out = echo.output()
    assert echo.proc.returncode == 0
    assert out.count("[ControllerStatus]") >= 7
    assert '"mode":"toy"' in out


def test_services_answer_and_bad_requests_get_error_replies(router, spawn):
    spawn(toy_argv(router), "toy")
    with client_node(router) as node:
        wait_for(lambda: alive(node, "toy"), 20, what="toy liveliness")
        assert node.call(registry.ARMING, CommandBool(value=True), timeout=5).success
        with pytest.raises(ServiceError, match="refuses to disarm") as err:
            node.call(registry.ARMING, CommandBool(value=False), timeout=5)
        assert err.value.code == "refused"
        key = registry.ARMING.key("drone")
        for payload, expected in ((b"\x01", "bad CommandBool request"), (None, "empty request")):
            replies = list(node.session.get(key, payload=payload, timeout=5))
            assert len(replies) == 1 and replies[0].err is not None
            from dronewrapper.msgs import ErrorReply

            err_msg = codec.decode(ErrorReply, replies[0].err.payload.to_bytes())
            assert expected in err_msg.message and err_msg.code == "bad_request"
        with pytest.raises(TypeError):
            node.call(registry.ARMING, ControllerStatus())
        t0 = time.monotonic()
        with pytest.raises(ServiceUnavailable, match="cmd/takeoff"):
            node.call(registry.TAKEOFF, CommandTOL.takeoff(), timeout=3)
        assert time.monotonic() - t0 < 6.0  # bounded by the 3 s timeout (2x for a loaded machine)


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_service_exits_cleanly_and_withdraws_its_token(router, spawn, sig):
    toy = spawn(toy_argv(router), "toy")
    with client_node(router) as node:
        wait_for(lambda: alive(node, "toy"), 20, what="toy liveliness")
        toy.proc.send_signal(sig)
        toy.proc.wait(15)
        assert toy.proc.returncode == 0, toy.output()
        wait_for(lambda: not alive(node, "toy"), 10, what="token withdrawn")
    assert "toy stopped" in toy.output()


def test_bad_config_exits_2_naming_the_key(router, spawn):
    toy = spawn(toy_argv(router, "--set", "rate_hzz=3"), "toy")
    toy.proc.wait(30)
    assert toy.proc.returncode == 2
    assert "unknown field `rate_hzz`" in toy.output()


def test_namespaces_keep_drones_apart(router, spawn):
    spawn(toy_argv(router, ns="drone1"), "toy1")
    with client_node(router, namespace="drone2") as node:
        got = []
        node.subscribe(registry.CONTROLLER_STATUS, got.append)
        other = node.latest(
            registry.CONTROLLER_STATUS, key=registry.CONTROLLER_STATUS.key("drone1")
        )
        other.wait(20)
        assert got == []


def test_a_second_sigint_exits_at_once(router, spawn):
    """The first Ctrl-C stops cleanly (here slowly); a second one exits now, with 128 + 2."""
    toy = spawn(toy_argv(router, "--set", "stop_delay_s=60"), "toy")
    wait_for(lambda: "toy up" in toy.output(), 30, what="toy up")
    toy.proc.send_signal(signal.SIGINT)
    wait_for(lambda: "toy stopping slowly" in toy.output(), 10, what="the slow stop")
    toy.proc.send_signal(signal.SIGINT)
    assert toy.proc.wait(20) == 130, toy.output()
    assert "second SIGINT: exiting now" in toy.output()


def test_a_low_latency_service_serves_ordinary_and_low_latency_peers(router, spawn):
    """``--low-latency`` is negotiated per link: a low-latency peer talks to a low-latency
    one over the low-latency transport, and to an ordinary one the ordinary way."""
    spawn(toy_argv(router, "--low-latency"), "toy")
    with (
        client_node(router, name="ordinary") as ordinary,
        client_node(router, name="fast", options_extra={"low_latency": True}) as fast,
    ):
        for node in (ordinary, fast):
            wait_for(lambda n=node: alive(n, "toy"), 20, what=f"toy liveliness at {node.name}")
            received: list[ControllerStatus] = []
            node.subscribe(registry.CONTROLLER_STATUS, received.append)
            wait_for(lambda r=received: len(r) >= 3, 10, what=f"status at {node.name}")
            assert node.call(registry.ARMING, CommandBool(value=True), timeout=5).success
