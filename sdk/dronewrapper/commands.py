"""A DroneWrapper's commands: the bridge's services (arming, modes, parameters, the command
lease), each a request/reply carrying our commander name.

A refusal raises :class:`~dronewrapper.errors.CommandRefused` with the autopilot's reason; no
reply raises :class:`~dronewrapper.errors.Timeout` when a bridge is alive (slow or stuck), else
:class:`~dronewrapper.errors.NotConnected` (see :func:`dronewrapper.connection.no_reply`).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, TypeVar

import numpy as np

from dronewrapper import setpoints
from dronewrapper.client import DroneClient
from dronewrapper.errors import CommandRefused, DroneError, InvalidArgument
from dronewrapper.msgs import registry
from dronewrapper.msgs.lease import LeaseRequest
from dronewrapper.msgs.mavros import (
    CommandBool,
    ParamGet,
    ParamSet,
    ParamValue,
    SetMode,
)
from dronewrapper.msgs.registry import Service
from dronewrapper.runtime.errors import ServiceError, ServiceUnavailable

T = TypeVar("T")


NoReply = Callable[[str, str, float], DroneError]
"""``no_reply(what, key, timeout)``: the error for a call nobody answered, diagnosed."""


class Commands:
    """The service calls of one drone (see the module doc); a part a DroneWrapper owns.

    Args:
        client: the drone client (its calls carry our commander name).
        no_reply: the error for a call nobody answered (NotConnected or Timeout).
        service_timeout: seconds to wait for a reply when a call gives none.
    """

    def __init__(self, client: DroneClient, no_reply: NoReply, service_timeout: float) -> None:
        self.client = client
        self.ns = client.ns
        self.no_reply = no_reply
        self.service_timeout = service_timeout

    def call(self, service: Service[Any, T], request: Any, what: str, timeout: float | None) -> T:
        """One request/reply: CommandRefused on a refusal, ``no_reply`` when unanswered."""
        timeout = self.service_timeout if timeout is None else timeout
        try:
            return self.client.ask(service, request, timeout)
        except ServiceUnavailable as exc:
            waited = timeout if exc.waited is None else exc.waited
            raise self.no_reply(what, service.key(self.ns), waited) from None
        except ServiceError as exc:
            raise CommandRefused(what, exc.message) from None

    def command(self, service: Service[Any, Any], request: Any, what: str, timeout=None) -> Any:
        """:meth:`call`, and CommandRefused when the reply says it failed."""
        reply = self.call(service, request, what, timeout)
        ok = reply.mode_sent if hasattr(reply, "mode_sent") else reply.success
        if not ok:
            raise CommandRefused(what, reply.message, getattr(reply, "result", None))
        return reply

    def take_command(self, *, take_over: bool = True, timeout: float | None = None) -> str:
        """Take this drone's command lease (another operator's too, when ``take_over``): the
        bridge then obeys only our setpoints and commands. Returns the previous holder.

        Raises:
            CommandRefused: ``take_over`` is False and someone else holds the lease.
        """
        action = "take_over" if take_over else "take"
        reply = self.call(registry.COMMAND_LEASE, LeaseRequest(action=action), action, timeout)
        if not reply.granted:
            raise CommandRefused(action, reply.message)
        return reply.previous

    def release_command(self, *, timeout: float | None = None) -> None:
        """Give the command lease back (any authorised operator may then take it)."""
        self.call(registry.COMMAND_LEASE, LeaseRequest(action="release"), "release", timeout)

    def arm(self, *, timeout: float | None = None) -> None:
        """Arm the motors. Raises CommandRefused with the autopilot's reason on refusal.

        PX4 refuses to arm in OFFBOARD without a setpoint stream and says only "Resolve system
        health failures first"; the error then names the real cause.
        """
        try:
            self.command(registry.ARMING, CommandBool(value=True), "arming", timeout)
        except CommandRefused as exc:
            state = self.client.state.value
            if state is not None and state.mode == "OFFBOARD" and self.client.target is None:
                raise CommandRefused(
                    "arming",
                    f"{exc.reason}; the autopilot is in OFFBOARD and no setpoint is being "
                    "streamed: PX4 arms in OFFBOARD only with a setpoint stream (use takeoff(), "
                    "or set_cmd_pos(...) before arm())",
                    exc.result,
                ) from None
            raise

    def disarm(self, *, timeout: float | None = None) -> None:
        """Disarm the motors (the autopilot refuses in flight). Raises CommandRefused."""
        self.command(registry.ARMING, CommandBool(value=False), "disarming", timeout)

    def set_mode(self, mode: str, *, timeout: float | None = None) -> None:
        """Ask for a flight mode by name (``OFFBOARD``, ``AUTO.LOITER``, ``GUIDED`` ...).

        Returns when the autopilot acknowledged it. Raises CommandRefused otherwise.
        """
        if not isinstance(mode, str) or not mode.strip():
            raise InvalidArgument(f"mode must be a mode name, got {mode!r}")
        self.command(registry.SET_MODE, SetMode(custom_mode=mode), f"set_mode {mode}", timeout)

    def param_get(self, param: str, *, timeout: float | None = None) -> int | float:
        """Read an autopilot parameter; an int or a float."""
        if not isinstance(param, str) or not param:
            raise InvalidArgument(f"param must be a parameter name, got {param!r}")
        reply = self.command(
            registry.PARAM_GET, ParamGet(param_id=param), f"param_get {param}", timeout
        )
        return reply.value.as_number()

    def param_set(
        self, param: str, value: int | float, *, timeout: float | None = None
    ) -> int | float:
        """Write an autopilot parameter (ints as integer, floats as real); returns the value
        the autopilot reports after the write."""
        if not isinstance(param, str) or not param:
            raise InvalidArgument(f"param must be a parameter name, got {param!r}")
        if isinstance(value, int | np.integer) and not isinstance(value, bool):
            wrapped = ParamValue(integer=int(value))
        else:
            wrapped = ParamValue(real=setpoints.finite(param, value))
        reply = self.command(
            registry.PARAM_SET,
            ParamSet(param_id=param, value=wrapped),
            f"param_set {param}",
            timeout,
        )
        return reply.value.as_number()
