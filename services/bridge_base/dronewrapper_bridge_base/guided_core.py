"""What the two PX4-capable bridges' pure cores share (:class:`GuidedCore`): the guided-mode
failsafe fed with the vehicle's mode and each screened setpoint, its ticks acted on, and State,
ExtendedState and BatteryState published on change or at their configured rates.

bridge_mavlink's ``BridgeCore`` (MAVLink) and bridge_px4_zenoh's ``Px4ZenohCore`` (PX4's uORB
over Zenoh) differ in how they read the vehicle and write a setpoint; each supplies those as
the hooks below (its envelope, its failsafe operations, its setpoint writer, its pose). The
unattended rule's watch of a go-to's commander (:mod:`~dronewrapper_bridge_base.unattended`) is
kept here for both. Times are the core's (``now`` monotonic s, ``stamp`` Unix s).
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable
from typing import Any

import msgspec

from dronewrapper.msgs import registry
from dronewrapper.msgs.mavros import ExtendedState, PositionTarget, State
from dronewrapper.msgs.sensor import BatteryState
from dronewrapper.msgs.std import Header
from dronewrapper_bridge_base.commander_lease import commander_rules
from dronewrapper_bridge_base.core_driver import PureCore
from dronewrapper_bridge_base.guided_failsafe import Failsafe, Tick, is_airborne
from dronewrapper_bridge_base.setpoint_limits import Kind, validate
from dronewrapper_bridge_base.unattended import Unattended


class GuidedCore(PureCore):
    """A PX4-capable bridge's core: the failsafe and State publication (see module docstring).

    Args:
        config: the bridge's Config (``limits``, ``state_rate_hz``, ``extended_state_rate_hz``,
            ``battery_rate_hz``, the lease's and failsafe's settings).
        now: where the core's time starts (monotonic s).
        outbox: makes an empty outbox (the core's own ``Outbox`` dataclass).
        log: the bridge's logger.
    """

    def __init__(
        self, config: Any, now: float, outbox: Callable[[], Any], log: logging.Logger
    ) -> None:
        super().__init__(now, outbox, log, **commander_rules(config))
        self.config = config
        self.limits = config.limits
        self.failsafe = Failsafe(config.failsafe_config())
        self.unattended = Unattended(config.unattended_config())  # a go-to's commander
        self.connected = False
        self.autopilot = ""  # the autopilot kind as State names it ("" until known)
        self.heartbeat_state: State | None = None  # the vehicle's State (the shown mode)
        self.ext = ExtendedState()
        self.battery: BatteryState | None = None
        self.setpoints_sent = 0
        self._last_state_key: tuple | None = None
        self._last_state_pub = -math.inf
        self._last_ext_pub = -math.inf
        self._last_battery_pub = -math.inf

    # ------------------------------------------------------------------ hooks

    def failsafe_steps(self, request: str) -> Any:
        """The operation the failsafe's request (``land`` or ``return``) runs."""
        raise NotImplementedError

    def breach_state(self) -> str:
        """The envelope's breach as State's failsafe shows it (``breach:<action>``), else ""."""
        raise NotImplementedError

    def pose(self) -> tuple[tuple[float, float, float], float] | None:
        """(position ENU m, yaw ENU rad) now, None before the first local position."""
        raise NotImplementedError

    def _send_setpoint(self, target: PositionTarget) -> None:
        raise NotImplementedError

    # ------------------------------------------------------------------ the failsafe

    def update_failsafe_vehicle(self) -> None:
        """The failsafe learns the vehicle's mode, arming and landed state."""
        hb = self.heartbeat_state
        if hb is None:
            return
        airborne = is_airborne(self.ext.landed_state, hb.armed)
        self.failsafe.on_vehicle(mode=hb.mode, armed=hb.armed, airborne=airborne, now=self.now)
        self.watch_vehicle()
        self._act(self.failsafe.tick(self.now, self.pose()), send=False)

    def on_alive(self, keys: set[str], now: float, stamp: float) -> None:
        """A commander's beat (its process's key) arrived now."""
        self._at(now, stamp)
        self.watch_alive(keys)

    # ------------------------------------------------------------------ the unattended rule

    def watch_vehicle(self) -> None:
        """The commander watch learns the vehicle's new mode or arming: a disarm on the ground
        ends it (the aircraft is down)."""
        hb = self.heartbeat_state
        if hb is not None and not hb.armed and not self.failsafe.airborne:
            self.unattended.clear()

    def watch_alive(self, keys: set[str]) -> None:
        """The commander watch learns whose beats arrived (their processes' keys)."""
        self.unattended.on_alive(keys, self.now)

    def unattended_tick(self, holding: Callable[[], bool]) -> None:
        """Take the unattended action when its time has come (once), while airborne:
        ``holding`` says whether the aircraft holds on its own (the bridge's own hold is let
        go, the failsafe's land or return started)."""
        unattended = self.unattended
        if not unattended.what or not self.failsafe.airborne:
            return
        action = unattended.tick(self.now, holding=holding())
        if action:
            self.bridge_text(unattended.reason(self.now))
            self.failsafe.release_hold()
            self.start(self.failsafe_steps(action), self.now, self.stamp, background=True)

    # ------------------------------------------------------------------ setpoints

    def check_setpoint(self, target: PositionTarget) -> Kind:
        return validate(target, self.limits)

    def fly_setpoint(self, target: PositionTarget, kind: Kind) -> None:
        """A commander steers (the unattended action is over): the setpoint is remembered and
        sent to the autopilot at once."""
        self.unattended.clear()
        self.failsafe.on_setpoint(target, kind, self.now)
        self._act(self.failsafe.tick(self.now, self.pose()), send=True)

    def _act(self, tick: Tick, *, send: bool) -> None:
        """Act on a failsafe tick: log and publish transitions, send, start its requests."""
        for transition in tick.transitions:
            self._log.warning(
                "failsafe %r -> %r: %s", transition.old, transition.new, transition.reason
            )
        for event in tick.events:
            self.bridge_text(event)
        if tick.transitions:
            self.publish_state(force=True)
        if send and tick.send is not None:
            self._send_setpoint(tick.send)
        if tick.request:
            steps = self.failsafe_steps(tick.request)
            self.start(steps, self.now, self.stamp, background=True)

    def bridge_text(self, text: str) -> None:
        """Log and publish a warning of the bridge's own."""
        raise NotImplementedError

    # ------------------------------------------------------------------ state publication

    def current_state(self) -> State:
        """State as published now: the vehicle's last (before any, only the autopilot kind)
        with the bridge's own connection, failsafe (its own, else the breach) and commander."""
        hb = self.heartbeat_state or State(autopilot=self.autopilot)
        return msgspec.structs.replace(
            hb,
            header=Header(stamp=self.stamp),
            connected=self.connected,
            failsafe=self.failsafe.state or self.breach_state(),
            commander=self.commander,
        )

    def publish_state(self, *, force: bool = False) -> None:
        """Publish State if it changed (or ``force``, or the periodic time has come)."""
        s = self.current_state()
        key = (
            s.connected,
            s.armed,
            s.guided,
            s.manual_input,
            s.mode,
            s.system_status,
            s.autopilot,
            s.failsafe,
            s.commander,
        )
        due = self.now - self._last_state_pub >= 1.0 / self.config.state_rate_hz
        if force or due or key != self._last_state_key:
            self._last_state_key, self._last_state_pub = key, self.now
            self.publish(registry.STATE, s)

    def publish_periodic(self) -> None:
        """State (if due), then ExtendedState and BatteryState at their configured rates."""
        now = self.now
        self.publish_state()
        if now - self._last_ext_pub >= 1.0 / self.config.extended_state_rate_hz:
            self._last_ext_pub = now
            ext = msgspec.structs.replace(self.ext, header=Header(stamp=self.stamp))
            self.publish(registry.EXTENDED_STATE, ext)
        if self.battery is not None and now - self._last_battery_pub >= (
            1.0 / self.config.battery_rate_hz
        ):
            self._last_battery_pub = now
            battery = msgspec.structs.replace(self.battery, header=Header(stamp=self.stamp))
            self.publish(registry.BATTERY, battery)
