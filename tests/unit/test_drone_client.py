"""The DroneClient on the fake bus: setpoints streamed by the loop, calls as Pending, ready;
one holder per key; the DroneWrapper a facade over one client."""

from __future__ import annotations

import itertools
import math
import threading
from concurrent.futures import Future

import pytest
from bus_autopilot import BusAutopilot

from dronewrapper.client import DroneClient, Pending
from dronewrapper.drone import DroneWrapper
from dronewrapper.errors import InvalidArgument
from dronewrapper.flights import Flights
from dronewrapper.msgs import registry
from dronewrapper.msgs.mavros import (
    MASK_VELOCITY,
    CommandBool,
    CommandBoolResult,
    SetMode,
    SetModeResult,
)
from dronewrapper.runtime import ServiceError, ServiceUnavailable
from dronewrapper.runtime.caller import origin_of
from dronewrapper.runtime.fake import FakeBus, FakeNode

T0 = 1_700_000_000.0
SETPOINTS = registry.SETPOINT_RAW_LOCAL.key("drone")


def commander(bus: FakeBus, **kwargs) -> DroneClient:
    node = FakeNode("svc", bus)
    kwargs.setdefault("inline_calls", True)
    return DroneClient(node, name="svc", **kwargs)


def published(bus: FakeBus) -> list:
    return [(d.time, d.msg) for d in bus.published[SETPOINTS]]


def test_a_setpoint_goes_out_at_once_and_repeats_each_period_until_stopped():
    bus = FakeBus(start=T0)
    c = commander(bus, rate_hz=30.0)
    c.set_velocity(1.0, 0.0, 0.5, -0.2, bus.clock(), stamp=T0 - 0.08)
    assert len(published(bus)) == 1 and c.next_due() == pytest.approx(T0 + 1 / 30)
    for i in range(1, 301):  # poll at 1 kHz for 0.3 s
        bus.clock.advance_to(T0 + i / 1000)
        c.poll(bus.clock())
    sent = published(bus)
    assert len(sent) == 10  # now + 9 repetitions in 0.3 s
    assert all(
        b[0] - a[0] == pytest.approx(1 / 30, abs=1.1e-3) for a, b in itertools.pairwise(sent)
    )
    first = sent[0][1]
    assert first.type_mask == MASK_VELOCITY and first.header.stamp == T0 - 0.08  # data's stamp
    assert (first.velocity.x, first.velocity.z, first.yaw_rate) == (1.0, 0.5, -0.2)
    assert [sp.header.seq for _, sp in sent] == list(range(10))
    c.stop()
    bus.clock.advance_to(T0 + 1.0)
    assert not c.poll(bus.clock()) and len(published(bus)) == 10 and c.next_due() == math.inf


def test_after_a_stall_the_stream_resumes_without_a_burst():
    bus = FakeBus(start=T0)
    c = commander(bus, rate_hz=20.0)
    c.set_velocity(0, 0, 0, 0, bus.clock())
    bus.clock.advance_to(T0 + 1.0)  # the loop stalled a second
    assert c.poll(bus.clock()) and not c.poll(bus.clock())
    assert c.next_due() == pytest.approx(T0 + 1.05)


def test_a_new_setpoint_restarts_the_period_and_a_bad_one_is_refused():
    bus = FakeBus(start=T0)
    c = commander(bus)
    c.set_velocity(0, 0, 0, 0, bus.clock())
    bus.clock.advance_to(T0 + 0.02)
    c.set_velocity(1, 0, 0, 0, bus.clock())
    assert c.next_due() == pytest.approx(T0 + 0.02 + 1 / 30)
    with pytest.raises(InvalidArgument, match="vx"):
        c.set_velocity(math.nan, 0, 0, 0, bus.clock())
    assert c.target.velocity.x == 1.0 and len(published(bus)) == 2
    with pytest.raises(ValueError, match=">= 20 Hz"):
        commander(bus, rate_hz=10.0)


def test_calls_return_a_pending_that_holds_the_reply_or_the_error():
    bus = FakeBus(start=T0)
    autopilot = BusAutopilot(bus, flying=False, refuse={"arming": "no GPS"})
    c = commander(bus)
    mode = c.call(registry.SET_MODE, SetMode(custom_mode="OFFBOARD"), T0, timeout=1.0)
    assert mode.done(T0) and mode.result(T0).mode_sent and autopilot.mode == "OFFBOARD"
    arm = c.call(registry.ARMING, CommandBool(value=True), T0, timeout=1.0)
    reply = arm.result(T0)
    assert not reply.success and reply.message == "no GPS"
    with pytest.raises(ValueError, match="timeout"):
        c.call(registry.ARMING, CommandBool(value=True), T0, timeout=0.0)


def test_a_call_nobody_serves_fails_with_service_unavailable():
    bus = FakeBus(start=T0)
    c = commander(bus)
    pending = c.call(registry.ARMING, CommandBool(value=True), T0, timeout=1.0)
    assert pending.done(T0)
    with pytest.raises(ServiceUnavailable):
        pending.result(T0)


def test_a_pending_without_a_reply_times_out_at_its_deadline_on_the_loop_clock():
    never: Future = Future()
    pending = Pending("arming", never, deadline=10.0, timeout=2.0)
    assert not pending.done(9.99)
    with pytest.raises(RuntimeError, match="still pending"):
        pending.result(9.99)
    assert pending.done(10.0)
    with pytest.raises(TimeoutError, match=r"arming: no reply within 2 s"):
        pending.result(10.0)


def test_calls_on_the_worker_thread_do_not_block_the_caller():
    bus = FakeBus(start=T0)
    node = FakeNode("svc", bus)
    gate = threading.Event()

    def slow_arming(_req) -> CommandBoolResult:
        gate.wait(10.0)
        return CommandBoolResult(success=True, result=0)

    bridge = FakeNode("bridge", bus)
    bridge.serve(registry.ARMING, slow_arming)
    bridge.serve(registry.SET_MODE, lambda _req: SetModeResult(mode_sent=True, result=0))
    c = DroneClient(node, name="svc")
    try:
        pending = c.call(registry.ARMING, CommandBool(value=True), T0, timeout=5.0)
        assert not pending.done(T0)  # returned while the server still works
        # a call left waiting never holds up the next one
        mode = c.call(registry.SET_MODE, SetMode(custom_mode="AUTO.LAND"), T0, timeout=5.0)
        assert mode._future.result(timeout=10.0).mode_sent and not pending.done(T0)
        gate.set()
        pending._future.result(timeout=10.0)
        assert pending.done(T0) and pending.result(T0).success
    finally:
        c.close()


def test_ready_once_connected_with_a_landed_state_and_a_position():
    bus = FakeBus(start=T0)
    c = commander(bus)
    assert not c.ready() and "no State" in c.not_ready_reason()
    autopilot = BusAutopilot(bus, flying=False)
    autopilot.connected = False
    autopilot.tick(bus.clock())
    assert not c.ready() and "not connected" in c.not_ready_reason()
    autopilot.connected = True
    autopilot.tick(bus.clock())
    assert c.ready() and c.connected_state().autopilot == "px4"
    bus.clock.advance_to(T0 + 3.5)  # the bridge went quiet
    assert not c.ready() and "3.5 s old" in c.not_ready_reason()


def subscriptions(bus: FakeBus, key: str) -> int:
    return sum(1 for s in bus._subs if s.active and str(s.keyexpr) == key)


def test_each_key_is_one_holder_and_one_subscription_whoever_reads_it():
    bus = FakeBus(start=T0)
    c = commander(bus)
    state_key = registry.STATE.key("drone")
    assert c.inputs.latest(registry.STATE) is c.state is c.inputs.state
    assert subscriptions(bus, state_key) == 1
    battery_key = registry.BATTERY.key("drone")
    assert subscriptions(bus, battery_key) == 0  # a loop's client reads only what it flies by
    battery = c.inputs.battery  # a stream read later: subscribed on the first read, once
    assert c.inputs.latest(registry.BATTERY) is battery and subscriptions(bus, battery_key) == 1
    c.close()
    assert subscriptions(bus, state_key) == 0  # every subscription ends with the client


def test_every_setpoint_names_us_and_its_send_time():
    bus = FakeBus(start=T0)
    seen: list[tuple[str, float | None]] = []
    bus.subscribe(
        SETPOINTS, lambda key, payload, attachment=None: seen.append(origin_of(attachment))
    )
    c = commander(bus)
    c.set_velocity(1.0, 0, 0, 0, bus.clock())
    bus.clock.advance_to(T0 + 0.1)
    c.poll(bus.clock())
    assert seen == [("svc", T0), ("svc", pytest.approx(T0 + 0.1))]  # the repetition's own time


def test_a_role_that_may_not_command_is_refused_unsent():
    bus = FakeBus(start=T0)
    autopilot = BusAutopilot(bus, flying=False)
    c = commander(bus, forbidden="the observer role may not command")
    pending = c.call(registry.ARMING, CommandBool(value=True), T0, timeout=1.0)
    with pytest.raises(ServiceError, match="may not command") as refused:
        pending.result(T0)
    assert refused.value.code == "forbidden" and autopilot.calls == []


def test_the_wrapper_is_a_facade_over_one_client_that_owns_its_parts():
    bus = FakeBus(start=T0)
    drone = DroneWrapper("drone", node=FakeNode("app", bus), wait=False, commander="ada")
    try:
        assert DroneWrapper.__mro__ == (DroneWrapper, object)  # parts, not mixins
        assert drone.inputs is drone.client.inputs and drone.getters.inputs is drone.inputs
        assert subscriptions(bus, registry.STATE.key("drone")) == 1
        assert DroneWrapper.takeoff.__doc__ == Flights.takeoff.__doc__  # help() shows the part's
        drone.set_cmd_vel(vx=0.5)
        assert drone.client.target is drone.commanding and drone.setpoints_sent == 1
    finally:
        drone.close()
