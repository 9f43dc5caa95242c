"""Parameter reads and writes as pure operations (see operations.py for the protocol).

PX4 sends integer parameters as their bytes in PARAM_VALUE's float field, ArduPilot as float
values (param_values.py); a write is checked against the parameter's type before anything is
sent, and its reply is the value the autopilot echoes.
"""

from __future__ import annotations

from collections.abc import Callable, Generator
from typing import TYPE_CHECKING

from dronewrapper.msgs.mavros import ParamGet, ParamGetResult, ParamSet, ParamSetResult, ParamValue
from dronewrapper_bridge_mavlink import param_values
from dronewrapper_bridge_mavlink.modes import AUTOPILOT_ARDUPILOT
from dronewrapper_bridge_mavlink.operations import Steps

if TYPE_CHECKING:
    from dronewrapper_bridge_mavlink.core import BridgeCore


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


def decode(core: BridgeCore, raw: float, param_type: int) -> ParamValue:
    """A PARAM_VALUE's value: PX4 sends integers as their bytes, ArduPilot as float values."""
    bytewise = core.autopilot != AUTOPILOT_ARDUPILOT
    return param_values.decode_param(raw, param_type, bytewise=bytewise)


def param_exchange(
    core: BridgeCore, param_id: str, send: Callable[[], None]
) -> Generator[float, None, tuple[float, int] | None]:
    """Send (with retries) until a PARAM_VALUE for ``param_id`` newer than the send."""
    for _ in range(core.config.param_attempts):
        sent_after = core.param_values_received  # only a PARAM_VALUE arriving later answers
        send()
        deadline = core.now + core.config.param_timeout
        while True:
            entry = core.params.get(param_id)
            if entry is not None and entry[2] > sent_after:
                return entry[0], entry[1]
            if core.now >= deadline:
                break
            yield deadline
    return None


def param_read(core: BridgeCore, param_id: str) -> Generator[float, None, tuple | None]:
    """PARAM_REQUEST_READ until answered: (raw float, MAV_PARAM_TYPE) or None."""
    encoded = param_id.encode("ascii")
    return (
        yield from param_exchange(
            core,
            param_id,
            lambda: core.send("param_request_read", *core.target(), encoded, -1),
        )
    )


def param_get(core: BridgeCore, request: ParamGet) -> Steps:
    """PARAM_GET: PARAM_REQUEST_READ; integers are reinterpreted from the float bits."""
    core.require_connected()
    param_id = check_param_id(request.param_id)
    got = yield from param_read(core, param_id)
    if got is None:
        return ParamGetResult(success=False, message=f"{param_id}: no PARAM_VALUE (unknown?)")
    return ParamGetResult(success=True, value=decode(core, *got), message="ok")


def param_set(core: BridgeCore, request: ParamSet) -> Steps:
    """PARAM_SET: write, then report the value the autopilot echoes.

    The value is checked against the parameter's type first (float32 range, integer
    ranges, exactness); a value that does not fit is a bad request naming the field.
    """
    core.require_connected()
    param_id = check_param_id(request.param_id)
    param_values.requested_number(param_id, request.value)  # refuse before any I/O
    known = core.params.get(param_id)
    if known is None:
        known = yield from param_read(core, param_id)
        if known is None:
            return ParamSetResult(success=False, message=f"{param_id}: unknown parameter")
    param_type = known[1]
    bytewise = core.autopilot != AUTOPILOT_ARDUPILOT
    raw = param_values.encode_param(param_id, request.value, param_type, bytewise=bytewise)
    encoded = param_id.encode("ascii")
    got = yield from param_exchange(
        core,
        param_id,
        lambda: core.send("param_set", *core.target(), encoded, raw, param_type),
    )
    if got is None:
        return ParamSetResult(success=False, message=f"{param_id}: no PARAM_VALUE echo")
    echoed = decode(core, *got)
    requested = decode(core, raw, param_type)
    same = echoed.integer == requested.integer and (
        echoed.real == requested.real
        or abs(echoed.real - requested.real) <= 1e-6 * max(1.0, abs(requested.real))
    )
    message = "ok" if same else "the autopilot kept a different value"
    return ParamSetResult(success=same, value=echoed, message=message)
