"""Whether the gateway has what it presents: a router, and each drone's state.

The gateway starts whether or not its router and its drones are there (a ROS 2 graph may well
come up first), so it says what is missing: when, :data:`GRACE_S` after the start, it reaches
no router, or hears no ``mavros/state`` from a drone it presents, it logs a warning naming the
endpoint or the drone (and the drones that are online), once; and once the missing thing
arrives, one line saying so. :class:`Presence` is the rule (pure, times in monotonic seconds);
:class:`PresenceWatch` feeds it from a node.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field

from dronewrapper.discovery import BRIDGE_PREFIX, services_by_namespace
from dronewrapper.msgs import registry
from dronewrapper.runtime.contract import NodeApi

GRACE_S = 5.0
"""How long after the start a missing router or drone state is said (s): a bridge sends its
state at 1 Hz or more, and a router is reached within a second on a working link."""

Line = tuple[int, str]  # (logging level, text)


def _is_bridge(service: str) -> bool:
    return service.startswith(BRIDGE_PREFIX)


@dataclass
class Presence:
    """The rule: what to log, given what the gateway has now.

    Args:
        drones: the namespaces presented.
        connect: the router endpoints the gateway was given (for the message).
        started: when the gateway started (monotonic s).
    """

    drones: Sequence[str]
    connect: str
    started: float
    grace_s: float = GRACE_S
    missing: set[str] = field(default_factory=set)  # what was said missing: "router", drones

    def check(
        self,
        now: float,
        linked: bool,
        heard: Mapping[str, bool],
        online: Callable[[], Sequence[str]],
    ) -> list[Line]:
        """The lines to log now, given whether the router is ``linked`` and which drones' state
        was ``heard``; ``online()`` gives the namespaces with a bridge alive (asked only for a
        warning)."""
        lines: list[Line] = []
        due = now - self.started >= self.grace_s
        if not linked:
            if due and "router" not in self.missing:
                self.missing.add("router")
                lines.append((logging.WARNING, self._no_router()))
            return lines
        if "router" in self.missing:
            self.missing.discard("router")
            lines.append((logging.INFO, f"router reached at {self.connect}"))
        for ns in self.drones:
            if heard.get(ns):
                if ns in self.missing:
                    self.missing.discard(ns)
                    lines.append((logging.INFO, f"drone {ns!r}: state arriving, presented"))
            elif due and ns not in self.missing:
                self.missing.add(ns)
                lines.append((logging.WARNING, self._no_drone(ns, online)))
        return lines

    def _no_router(self) -> str:
        return (
            f"no router reached at {self.connect} after {self.grace_s:g} s: nothing reaches "
            "ROS 2 until one runs there (dronewrapper router, or dronewrapper up GRAPH), or "
            "give its endpoint with --connect"
        )

    def _no_drone(self, ns: str, online: Callable[[], Sequence[str]]) -> str:
        others = ", ".join(online()) or "none"
        return (
            f"no state from drone {ns!r} on {registry.STATE.key(ns)} after {self.grace_s:g} s: "
            f"is its bridge running on this router, and is the namespace right? (drones "
            f"online: {others}; --namespace or --set drones=[...] picks them)"
        )


class PresenceWatch:
    """:class:`Presence` fed from ``node``: its link, each drone's state, the bridges alive.

    :meth:`tick` checks and logs; call it every few tenths of a second."""

    def __init__(
        self, node: NodeApi, drones: Sequence[str], log: Callable[[int, str], None]
    ) -> None:
        self.node = node
        self.log = log
        options = getattr(node, "options", None)
        connect = ", ".join(getattr(options, "connect", None) or []) or "the default router"
        self.presence = Presence(list(drones), connect, node.clock.monotonic())
        self.states = {ns: node.latest(registry.STATE, key=registry.STATE.key(ns)) for ns in drones}

    def online(self) -> list[str]:
        """The namespaces with a bridge alive on the router now."""
        by_ns = services_by_namespace(self.node.alive_services("*"))
        return [
            ns for ns, names in by_ns.items() if any(n.startswith(BRIDGE_PREFIX) for n in names)
        ]

    def tick(self) -> None:
        linked = self.node.linked()
        heard = {ns: latest.value is not None for ns, latest in self.states.items()}
        now = self.node.clock.monotonic()
        for level, text in self.presence.check(now, linked, heard, self.online):
            self.log(level, text)
