"""The MAVLink mission protocol, the ground side, as pure state machines (time injected, s).

Upload (:class:`Upload`): MISSION_COUNT -> the autopilot asks each item with
MISSION_REQUEST_INT (or the older MISSION_REQUEST) -> MISSION_ITEM_INT -> MISSION_ACK.
Download (:class:`Download`): MISSION_REQUEST_LIST -> MISSION_COUNT -> MISSION_REQUEST_INT
for each item -> MISSION_ITEM_INT -> our MISSION_ACK. Clear (:class:`Clear`):
MISSION_CLEAR_ALL -> MISSION_ACK. The same machines carry fences and rally points
(``mission_type``).

The rules: the last message is re-sent when the answer does not come within ``timeout`` s, up
to ``attempts`` sends; a duplicated request is answered again (its item is re-sent, not
counted twice); a request for an item beyond the count, or an answer of another mission type,
is ignored; a MISSION_ACK other than ACCEPTED ends the transfer with the autopilot's reason;
an upload that ends early says how many items the autopilot took (``transferred``).

Each machine is fed :meth:`on_message` (a pymavlink message) and asked :meth:`due` for what to
send now, as typed messages (:data:`~dronewrapper_bridge_mavlink.outgoing.Send`) for the
outbox; ``done`` and ``error`` say how it ended.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any

from pymavlink.dialects.v20 import common as mavlink

from dronewrapper_bridge_mavlink import outgoing as out
from dronewrapper_bridge_mavlink.outgoing import Send

MISSION = mavlink.MAV_MISSION_TYPE_MISSION
FENCE = mavlink.MAV_MISSION_TYPE_FENCE
RALLY = mavlink.MAV_MISSION_TYPE_RALLY
ACCEPTED = mavlink.MAV_MISSION_ACCEPTED


@dataclass(frozen=True)
class Item:
    """One MISSION_ITEM_INT's content: ``x``/``y`` degrees * 1e7, ``z`` metres."""

    frame: int
    command: int
    current: int = 0
    autocontinue: int = 1
    param1: float = 0.0
    param2: float = 0.0
    param3: float = 0.0
    param4: float = math.nan
    x: int = 0
    y: int = 0
    z: float = 0.0

    @classmethod
    def from_message(cls, msg: Any) -> Item:
        """The item a MISSION_ITEM_INT carries."""
        return cls(
            frame=int(msg.frame),
            command=int(msg.command),
            current=int(msg.current),
            autocontinue=int(msg.autocontinue),
            param1=float(msg.param1),
            param2=float(msg.param2),
            param3=float(msg.param3),
            param4=float(msg.param4),
            x=int(msg.x),
            y=int(msg.y),
            z=float(msg.z),
        )


def result_name(result: int) -> str:
    """MAV_MISSION_RESULT's name (``MAV_MISSION_NO_SPACE`` ...)."""
    entry = mavlink.enums["MAV_MISSION_RESULT"].get(result)
    return entry.name if entry is not None else f"MAV_MISSION_RESULT {result}"


class Transfer:
    """What the machines share: targets, the re-send timer, the ending."""

    def __init__(
        self,
        target: tuple[int, int],
        now: float,
        *,
        mission_type: int = MISSION,
        timeout: float = 1.5,
        attempts: int = 5,
    ) -> None:
        if timeout <= 0 or attempts < 1:
            raise ValueError("timeout must be > 0 s and attempts >= 1")
        self.target = target
        self.mission_type = mission_type
        self.timeout = timeout
        self.attempts = attempts
        self.done = False
        self.error = ""
        self.sends = 0  # messages sent, re-sends included
        self._last: Send | None = None
        self._tries = 0
        self._deadline = now
        self._queue: list[Send] = []

    def _send(self, message: Send, now: float, *, expect_answer: bool = True) -> None:
        """Queue a message; with ``expect_answer`` it is re-sent on timeout."""
        self._queue.append(message)
        self.sends += 1
        if expect_answer:
            self._last = message
            self._tries = 1
            self._deadline = now + self.timeout

    def _finish(self, error: str = "") -> None:
        self.done = True
        self.error = error
        self._last = None

    def _ours(self, msg: Any) -> bool:
        return getattr(msg, "mission_type", MISSION) == self.mission_type

    def due(self, now: float) -> list[Send]:
        """The messages to send now (first sends, answers, and re-sends after a timeout)."""
        if not self.done and self._last is not None and now >= self._deadline:
            if self._tries >= self.attempts:
                self._finish(self.timeout_reason())
            else:
                self._tries += 1
                self.sends += 1
                self._deadline = now + self.timeout
                self._queue.append(self._last)
        out, self._queue = self._queue, []
        return out

    def wake_at(self) -> float:
        """When :meth:`due` must be asked again at the latest (monotonic s)."""
        return math.inf if self.done or self._last is None else self._deadline

    def timeout_reason(self) -> str:
        return f"no answer after {self._tries} attempt(s)"

    def on_message(self, msg: Any, now: float) -> None:
        raise NotImplementedError


class Upload(Transfer):
    """Upload ``items`` (see module docstring); ``transferred``: items the autopilot asked
    for, in order, so far. ``numbered_from``: the item named item 0 in messages (1 where the
    first item is ArduPilot's home)."""

    def __init__(
        self,
        items: list[Item],
        target: tuple[int, int],
        now: float,
        *,
        numbered_from: int = 0,
        **kw: Any,
    ) -> None:
        super().__init__(target, now, **kw)
        self.numbered_from = numbered_from
        self.items = list(items)
        self.transferred = 0
        self._asked = -1  # the highest item asked for
        self._send(out.MissionCount(*target, len(self.items), self.mission_type), now)

    def timeout_reason(self) -> str:
        return (
            f"upload incomplete: the autopilot stopped asking after {self.transferred} of "
            f"{len(self.items)} item(s) ({self._tries} attempt(s))"
        )

    def on_message(self, msg: Any, now: float) -> None:
        if self.done or not self._ours(msg):
            return
        kind = msg.get_type()
        if kind in ("MISSION_REQUEST_INT", "MISSION_REQUEST"):
            seq = int(msg.seq)
            if not 0 <= seq < len(self.items):
                return
            self._asked = max(self._asked, seq)
            self.transferred = self._asked  # asking for item n: items before it are taken
            self._send(self._item_message(seq), now)
        elif kind == "MISSION_ACK":
            if msg.type == ACCEPTED and self._asked + 1 == len(self.items):
                self.transferred = len(self.items)
                self._finish()
            elif msg.type == ACCEPTED:
                self._finish(
                    f"the autopilot ended the upload after {self.transferred} of "
                    f"{len(self.items)} item(s)"
                )
            else:
                self._finish(
                    f"refused by the autopilot: {result_name(msg.type)}{self._refused_item()} "
                    f"({self.transferred} of {len(self.items)} item(s) taken)"
                )

    def _refused_item(self) -> str:
        """`` at item N (COMMAND, frame F)``: the item sent last, which the autopilot's
        refusal answers; "" before any item was asked."""
        if not 0 <= self._asked < len(self.items):
            return ""
        item = self.items[self._asked]
        entry = mavlink.enums["MAV_CMD"].get(item.command)
        name = entry.name.removeprefix("MAV_CMD_") if entry is not None else str(item.command)
        return f" at item {self._asked - self.numbered_from} ({name}, frame {item.frame})"

    def _item_message(self, seq: int) -> out.MissionItemInt:
        """Item ``seq`` as MISSION_ITEM_INT (an :class:`Item` holds its content's fields)."""
        content = dataclasses.asdict(self.items[seq])
        return out.MissionItemInt(*self.target, seq=seq, mission_type=self.mission_type, **content)


class Download(Transfer):
    """Download the autopilot's list; ``items`` when done."""

    def __init__(self, target: tuple[int, int], now: float, **kw: Any) -> None:
        super().__init__(target, now, **kw)
        self.count: int | None = None
        self.items: list[Item] = []
        self._send(out.MissionRequestList(*target, self.mission_type), now)

    def on_message(self, msg: Any, now: float) -> None:
        if self.done or not self._ours(msg):
            return
        kind = msg.get_type()
        if kind == "MISSION_COUNT" and self.count is None:
            self.count = int(msg.count)
            self._next(now)
        elif kind == "MISSION_ITEM_INT" and self.count is not None:
            if int(msg.seq) == len(self.items):
                self.items.append(Item.from_message(msg))
                self._next(now)
        elif kind == "MISSION_ACK" and msg.type != ACCEPTED:
            self._finish(f"refused by the autopilot: {result_name(msg.type)}")

    def _next(self, now: float) -> None:
        assert self.count is not None
        if len(self.items) >= self.count:
            ack = out.MissionAck(*self.target, ACCEPTED, self.mission_type)
            self._send(ack, now, expect_answer=False)
            self._finish()
            return
        seq = len(self.items)
        self._send(out.MissionRequestInt(*self.target, seq, self.mission_type), now)


class Clear(Transfer):
    """MISSION_CLEAR_ALL until acknowledged."""

    def __init__(self, target: tuple[int, int], now: float, **kw: Any) -> None:
        super().__init__(target, now, **kw)
        self._send(out.MissionClearAll(*target, self.mission_type), now)

    def on_message(self, msg: Any, now: float) -> None:
        if self.done or not self._ours(msg) or msg.get_type() != "MISSION_ACK":
            return
        if msg.type == ACCEPTED:
            self._finish()
        else:
            self._finish(f"refused by the autopilot: {result_name(msg.type)}")


__all__ = [
    "FENCE",
    "MISSION",
    "RALLY",
    "Clear",
    "Download",
    "Item",
    "Transfer",
    "Upload",
    "result_name",
]
