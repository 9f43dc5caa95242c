"""The autopilot's parameters as a part the core owns (:class:`Parameters`): what was heard
(:class:`~dronewrapper_bridge_mavlink.param_cache.ParamCache`), and reads and writes as pure
operations (see operations.py for the protocol) over the few things of the core they use
(:class:`ParamPort`: the time, the autopilot's address and kind, the outbox).

PX4 sends integer parameters as their bytes in PARAM_VALUE's float field, ArduPilot as float
values (param_values.py); a write is checked against the parameter's type before anything is
sent, and its reply is the value the autopilot echoes.

A write's echo is matched to the write. PARAM_VALUE answers a read (PARAM_REQUEST_READ) and
acknowledges a write (PARAM_SET) alike, with the same param_id and, on PX4, the same
param_index, so only the value tells them apart: a PARAM_VALUE heard after the write that holds
the value written (within float32 tolerance) is its echo. One holding another value may answer
a read that overlaps the write (this bridge's own or another ground station's), so it is not
taken as the echo: the write re-sends until its attempts are spent, and only then is it
reported as kept at the last value heard.
"""

from __future__ import annotations

from collections.abc import Callable, Generator
from typing import Any, Protocol

from dronewrapper.msgs.mavros import ParamGet, ParamGetResult, ParamSet, ParamSetResult, ParamValue
from dronewrapper_bridge_base.operation import Steps
from dronewrapper_bridge_mavlink import param_values
from dronewrapper_bridge_mavlink.modes import AUTOPILOT_ARDUPILOT
from dronewrapper_bridge_mavlink.outgoing import AutopilotPort, ParamRequestRead
from dronewrapper_bridge_mavlink.outgoing import ParamSet as ParamSetMessage
from dronewrapper_bridge_mavlink.param_cache import ParamCache


class ParamPort(AutopilotPort, Protocol):
    """What a parameter exchange uses of the core besides its time, the autopilot's address
    and the outbox: the autopilot's kind (``""`` before it is heard), whether it is heard."""

    autopilot: str

    def require_connected(self) -> str: ...


def check_param_id(param_id: str) -> str:
    """``param_id`` if it is 1-16 printable ASCII characters, else ValueError."""
    if (
        not isinstance(param_id, str)
        or not param_id
        or len(param_id) > 16
        or not (param_id.isascii() and param_id.isprintable())
    ):
        raise ValueError(f"param_id must be 1-16 printable ASCII characters, got {param_id!r}")
    return param_id


def same_value(echoed: ParamValue, requested: ParamValue) -> bool:
    """Whether an echoed value is the one requested: integers exactly, reals within float32
    rounding (relative 1e-6, absolute below 1)."""
    return echoed.integer == requested.integer and (
        echoed.real == requested.real
        or abs(echoed.real - requested.real) <= 1e-6 * max(1.0, abs(requested.real))
    )


class Parameters:
    """The autopilot's parameters as this bridge reads and writes them (module docstring).

    Args:
        port: the core's side an exchange uses (:class:`ParamPort`).
        attempts: sends of a read or write before it gives up.
        timeout: s to wait for a PARAM_VALUE after each send.
    """

    def __init__(self, port: ParamPort, *, attempts: int, timeout: float) -> None:
        self._port = port
        self.attempts = attempts
        self.timeout = timeout
        self.cache = ParamCache()

    def on_value(self, msg: Any) -> None:
        """One PARAM_VALUE heard."""
        self.cache.on_value(msg)

    def decode(self, raw: float, param_type: int) -> ParamValue:
        """A PARAM_VALUE's value: PX4 sends integers as their bytes, ArduPilot as floats."""
        bytewise = self._port.autopilot != AUTOPILOT_ARDUPILOT
        return param_values.decode_param(raw, param_type, bytewise=bytewise)

    def exchange(
        self,
        param_id: str,
        send: Callable[[], None],
        echoes: Callable[[float, int], bool] | None = None,
    ) -> Generator[float, None, tuple[float, int] | None]:
        """Send (with retries) until a PARAM_VALUE for ``param_id`` heard after the first send
        answers: (raw float, MAV_PARAM_TYPE), or None if none was heard.

        A read (``echoes`` None) takes the first one. A write takes the first for which
        ``echoes(raw, type)`` holds (its value written); other values heard may answer an
        overlapping read, so the write re-sends until its attempts are spent and then answers
        with the last of them (the value the autopilot kept)."""
        port, cache = self._port, self.cache
        sent_after = cache.received  # only a PARAM_VALUE arriving later answers
        for _ in range(self.attempts):
            send()
            deadline = port.now + self.timeout
            while True:
                heard = cache.since(param_id, sent_after)
                for raw, param_type, _no in heard:
                    if echoes is None or echoes(raw, param_type):
                        return raw, param_type
                if port.now >= deadline:
                    break
                yield deadline
        heard = cache.since(param_id, sent_after)
        return (heard[-1][0], heard[-1][1]) if heard else None

    def read(self, param_id: str) -> Generator[float, None, tuple[float, int] | None]:
        """PARAM_REQUEST_READ until answered: (raw float, MAV_PARAM_TYPE) or None."""
        port, encoded = self._port, param_id.encode("ascii")

        def send() -> None:
            port.send(ParamRequestRead(*port.target(), encoded))

        return (yield from self.exchange(param_id, send))

    def get(self, request: ParamGet) -> Steps:
        """PARAM_GET: PARAM_REQUEST_READ; integers are reinterpreted from the float bits."""
        self._port.require_connected()
        param_id = check_param_id(request.param_id)
        got = yield from self.read(param_id)
        if got is None:
            return ParamGetResult(success=False, message=f"{param_id}: no PARAM_VALUE (unknown?)")
        return ParamGetResult(success=True, value=self.decode(*got), message="ok")

    def set(self, request: ParamSet) -> Steps:
        """PARAM_SET: write, then report the value the autopilot echoes.

        The value is checked against the parameter's type first (float32 range, integer
        ranges, exactness); a value that does not fit is a bad request naming the field.
        """
        port = self._port
        port.require_connected()
        param_id = check_param_id(request.param_id)
        param_values.requested_number(param_id, request.value)  # refuse before any I/O
        known = self.cache.get(param_id) or (yield from self.read(param_id))
        if known is None:
            return ParamSetResult(success=False, message=f"{param_id}: unknown parameter")
        param_type = known[1]
        bytewise = port.autopilot != AUTOPILOT_ARDUPILOT
        raw = param_values.encode_param(param_id, request.value, param_type, bytewise=bytewise)
        encoded, requested = param_id.encode("ascii"), self.decode(raw, param_type)

        def send() -> None:
            port.send(ParamSetMessage(*port.target(), encoded, raw, param_type))

        def echoes(echo_raw: float, echo_type: int) -> bool:
            return same_value(self.decode(echo_raw, echo_type), requested)

        got = yield from self.exchange(param_id, send, echoes)
        if got is None:
            return ParamSetResult(success=False, message=f"{param_id}: no PARAM_VALUE echo")
        echoed = self.decode(*got)
        same = same_value(echoed, requested)
        reply = "ok" if same else "the autopilot kept a different value"
        return ParamSetResult(success=same, value=echoed, message=reply)


class HasParameters(Protocol):
    """A core that owns its :class:`Parameters` (what the services' operations are given)."""

    parameters: Parameters


def param_get(core: HasParameters, request: ParamGet) -> Steps:
    """The PARAM_GET service's operation (:meth:`Parameters.get` of the core's part)."""
    return core.parameters.get(request)


def param_set(core: HasParameters, request: ParamSet) -> Steps:
    """The PARAM_SET service's operation (:meth:`Parameters.set` of the core's part)."""
    return core.parameters.set(request)
