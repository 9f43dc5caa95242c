"""The bridge's refusals reach the SDK on the real graph (compose/sim_iris.yaml with the command
lease on: simulator, bridge_mavlink, a loopback router): a setpoint stream from a commander
without the lease is refused by the bridge and the refused commander's DroneWrapper shows it
(``refusals``, ``on_refusal``); a point outside the envelope it holds raises at the call."""

from __future__ import annotations

import threading
import time
from collections.abc import Iterator

import pytest
from sdk_sim_graph import sim_graph

from dronewrapper import CommandRefused, DroneWrapper
from dronewrapper.msgs.refusal import Refusal

pytestmark = pytest.mark.integration

FENCE = [(-10.0, -10.0), (10.0, -10.0), (10.0, 10.0), (-10.0, 10.0)]


@pytest.fixture(scope="module")
def router(tmp_path_factory) -> Iterator[str]:
    log_dir = tmp_path_factory.mktemp("sdk_refusals")
    with sim_graph(log_dir, variables=["command_lease=true"]) as (endpoint, _):
        yield endpoint


def test_a_lease_refusal_reaches_the_refused_commanders_sdk(router):
    with (
        DroneWrapper("drone", router, timeout=30, commander="ada") as ada,
        DroneWrapper("drone", router, timeout=30, commander="bob") as bob,
    ):
        ada.take_command()
        arrived = threading.Event()
        heard: list[tuple[float, Refusal]] = []

        def on_refusal(refusal: Refusal) -> None:
            heard.append((time.monotonic(), refusal))
            arrived.set()

        bob.on_refusal(on_refusal)
        sent = time.monotonic()
        bob.set_cmd_vel(vx=0.5)
        assert arrived.wait(10.0), "no refusal reached bob's SDK"
        bob.stop_commanding()
        _, refusal = heard[0]
        assert (refusal.kind, refusal.commander, refusal.limit) == ("lease", "bob", "command_lease")
        assert "'ada' holds the command lease" in refusal.message
        assert bob.refusals[0] == refusal and ada.refusals == []
        print(f"lease refusal reached the SDK {heard[0][0] - sent:.3f} s after the setpoint")


def test_a_point_outside_the_envelope_held_raises_at_the_call(router):
    with DroneWrapper("drone", router, timeout=30, commander="ada") as drone:
        drone.take_command()
        try:
            drone.set_envelope(max_altitude=15.0, fence=FENCE)
            with pytest.raises(CommandRefused, match="horizontal speed 15") as refused:
                drone.set_cmd_vel(vx=15.0)
            assert refused.value.limit == "max_horizontal_speed"
            drone.wait_for(drone.home, 10.0, "home")  # a position needs home
            with pytest.raises(CommandRefused, match="outside the envelope's fence") as refused:
                drone.set_cmd_pos(30.0, 0.0, 3.0)
            assert refused.value.limit == "fence" and drone.commanding is None
        finally:
            drone.reset_envelope()
