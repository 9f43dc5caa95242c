"""What a bridge's node does around its pure core, for every aircraft: the wiring.

A bridge process is its pure core (a :class:`~dronewrapper_bridge_base.core_driver.PureCore`), the
aircraft's link, and a :class:`BridgeNode`, which owns the rest: the core's driver (one lock,
the time), the publishers of the core's samples, the setpoint subscription, the services (the
take-off and landing operations, the MAVROS-parity ones, the command lease), each request fed
to the core with its commander (the core applies the lease), and the core's tick loop. A
bridge subclasses it with its link: it executes the aircraft's part of the core's outbox
(:meth:`BridgeNode.send`) and runs its receive loops.

Time is the node's (``node.clock``) and only the node's: a bridge makes its core at the clock's
``monotonic()``, the driver feeds the core the clock's ``monotonic()`` and ``time()``, the tick
loop is paced on it, and a bridge's threads are made by it (``node.clock.thread``) and wait
through it. So a bridge on a fake bus runs in the bus's virtual time, threads and all, with
nothing swapped (given a link that waits through the clock too: a thread blocked in a socket
is busy to a virtual clock, which then stands still).
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Iterable, Mapping
from typing import Any, Generic, TypeVar

from dronewrapper.msgs import registry
from dronewrapper.msgs.flight import CommanderBeat
from dronewrapper.msgs.lease import LeaseReply, LeaseRequest
from dronewrapper.msgs.mavros import PositionTarget
from dronewrapper.msgs.registry import Service, Topic
from dronewrapper.runtime.caller import current_commander, current_sent_at
from dronewrapper.runtime.contract import NodeApi
from dronewrapper.runtime.ports import Ports
from dronewrapper.runtime.rate import Ratekeeper
from dronewrapper_bridge_base.core_driver import CoreDriver, PureCore, cancel_steps
from dronewrapper_bridge_base.operation import Steps

C = TypeVar("C", bound=PureCore)

Operation = Callable[[Any, Any], Steps]
"""A service's operation: ``steps(core, request)``."""

COMMANDS: dict[Service[Any, Any], str] = {
    registry.FLIGHT_TAKEOFF: "takeoff",
    registry.FLIGHT_LAND: "land",
    registry.FLIGHT_GOTO: "goto",
    registry.FLIGHT_RETURN: "return",
    registry.FLIGHT_MISSION: "mission",
    registry.MISSION_CONTROL: "mission",
    registry.FLIGHT_CANCEL: "cancel",
    registry.ARMING: "arming",
    registry.TAKEOFF: "takeoff",
    registry.LAND: "land",
    registry.SET_MODE: "set_mode",
    registry.PARAM_SET: "param_set",
}
"""The services that command the aircraft (only the lease holder's requests run), and how a
refusal names them."""


class BridgeNode(Generic[C]):
    """A pure core on a node: driver, publishers, subscriptions, services, tick loop.

    Args:
        node: the process's node (the bus and the clock).
        core: the bridge's pure core, its time started at ``node.clock.monotonic()``.
        publishers: the node's publisher of each topic the core publishes on.
        log: the bridge's logger.
    """

    def __init__(
        self, node: NodeApi, core: C, publishers: Mapping[Topic[Any], Any], log: logging.Logger
    ) -> None:
        self.node = node
        self.core = core
        self.log = log
        self.driver: CoreDriver[C] = CoreDriver(
            core, self.execute, node.stop_event, clock=node.clock
        )
        self._publishers = publishers

    # ---- the core's effects

    def execute(self, out: Any) -> None:
        """Carry out one outbox: the aircraft's part (:meth:`send`), then the samples."""
        self.send(out)
        for topic, msg in out.samples:
            self._publishers[topic].put(msg)

    def send(self, out: Any) -> None:
        """Send the outbox's messages to the aircraft (the bridge's own link)."""
        raise NotImplementedError

    # ---- inputs from commanders

    def on_setpoint(self, target: PositionTarget) -> None:
        """A PositionTarget from a commander (the core applies the lease and the late rule)."""
        self.driver.feed(self.core.on_setpoint, target, current_commander(), sent=current_sent_at())

    def on_lease(self, request: LeaseRequest) -> LeaseReply:
        """The lease service's handler."""
        return self.driver.feed(self.core.on_lease_request, request, current_commander())

    def serve(
        self,
        services: Mapping[Service[Any, Any], Operation],
        guarded: Iterable[tuple[Service[Any, Any], Operation, str]] = (),
    ) -> None:
        """Subscribe to setpoints, serve each service with its operation and the lease service.
        A command service's request (:data:`COMMANDS`) is refused unless from the lease holder,
        as is one of a ``guarded`` service: (service, operation, the lease action a refusal
        names; "" for a service anyone may call), the bridge's mission services and envelope."""
        self.node.subscribe(registry.SETPOINT_RAW_LOCAL, self.on_setpoint)
        self.node.subscribe(registry.COMMANDER_BEAT, self.on_beat)
        commands = dict(COMMANDS)
        services = {registry.FLIGHT_CANCEL: cancel_steps, **services}
        for service, steps, what in guarded:
            services[service] = steps
            if what:
                commands[service] = what
        for service, steps in services.items():
            self.node.serve(service, self._handler(steps, commands.get(service, "")))
        self.node.serve(registry.COMMAND_LEASE, self.on_lease)

    def _handler(self, steps: Operation, what: str) -> Callable[[Any], Any]:

        def handle(request: Any) -> Any:
            return self.driver.call(steps(self.core, request), current_commander(), what)

        return handle

    # ---- the commanders' processes

    def on_beat(self, beat: CommanderBeat) -> None:
        """A commander's process is alive (:mod:`~dronewrapper_bridge_base.unattended`)."""
        on_alive = getattr(self.core, "on_alive", None)
        if on_alive is not None:
            self.driver.feed(on_alive, {beat.key})

    # ---- the tick

    def tick_loop(self, rate_hz: float, what: str) -> None:
        """Feed the core's ``tick`` at ``rate_hz`` of the node's clock until the node stops
        (errors counted under ``what`` and logged; the loop goes on)."""
        rate = Ratekeeper(rate_hz, stop=self.node.stop_event, clock=self.node.clock)
        while rate.sleep():
            self.tick_once(what)

    def tick_once(self, what: str) -> None:
        """Feed the core's ``tick`` once (an error counted under ``what`` and logged)."""
        try:
            self.driver.feed(self.core.tick)
        except Exception:
            self.node.callback_errors[what] += 1
            self.log.exception("%s loop error", what)


BRIDGE_PUBLISHED = (
    registry.STATE,
    registry.EXTENDED_STATE,
    registry.LOCAL_POSE,
    registry.VELOCITY_BODY,
    registry.VELOCITY_LOCAL,
    registry.BATTERY,
    registry.STATUSTEXT,
    registry.ENVELOPE,  # the envelope and home: each bridge's missions part
    registry.HOME_POSITION,
    registry.REFUSAL,  # what was refused, told to its commander
)
"""What every bridge publishes; each adds its own (:func:`bridge_ports`' ``published``)."""


def bridge_ports(
    process: str,
    published: Iterable[Topic[Any]],
    services: Mapping[Service[Any, Any], Operation],
    guarded: Iterable[tuple[Service[Any, Any], Operation, str]] = (),
) -> Ports:
    """A bridge's ports: its telemetry (``published``), the setpoints and commander beats it
    takes, and what :meth:`BridgeNode.serve` serves for these ``services`` and ``guarded``."""
    return Ports(
        process,
        publishes=published,
        subscribes=(registry.SETPOINT_RAW_LOCAL, registry.COMMANDER_BEAT),
        serves=(
            registry.FLIGHT_CANCEL,
            registry.COMMAND_LEASE,
            *services,
            *(service for service, _steps, _what in guarded),
        ),
    )
