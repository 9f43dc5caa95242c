"""What one process may do on the bus: the registry topics it publishes and subscribes to, the
services it serves and the services it calls.

A service declares its ``PORTS`` next to its ``run``;
:func:`~dronewrapper.runtime.service.run_service` hands them to the node, and the node (real or
fake) refuses any publisher, subscriber, queryable or call outside them with a
:class:`PortRefused` naming the key, the process and what it declared. A node without ports
(an SDK app, a tool, a test) is unrestricted.

Ports name registry entries, never key strings: a wildcard subscription
(``subscribe(TOPIC, key=TOPIC.wildcard(), keyed=True)``) and a namespaced or parametrised key
(``camera=...``, ``ns=...``) are the same port as the plain topic.

    >>> from dronewrapper.msgs import registry
    >>> ports = Ports("cam", publishes=(registry.CAMERA_INFO,))
    >>> ports.check("publishes", registry.CAMERA_INFO)
    >>> try:
    ...     ports.check("publishes", registry.STATE)
    ... except PortRefused as exc:
    ...     print(exc)
    cam does not publish {ns}/mavros/state: it declares publishes ['{ns}/{camera}/camera_info']
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import Any, Literal

from dronewrapper.msgs.keys import Service, Topic

Kind = Literal["publishes", "subscribes", "serves", "calls"]
KINDS: tuple[Kind, ...] = ("publishes", "subscribes", "serves", "calls")


class PortRefused(PermissionError):
    """A node was asked for a publisher, subscriber, queryable or call its ports do not hold."""


@dataclass(frozen=True)
class Ports:
    """The registry entries one process (``process``) publishes, subscribes to, serves and calls."""

    process: str
    publishes: frozenset[Topic[Any]] = field(default=frozenset())
    subscribes: frozenset[Topic[Any]] = field(default=frozenset())
    serves: frozenset[Service[Any, Any]] = field(default=frozenset())
    calls: frozenset[Service[Any, Any]] = field(default=frozenset())

    def __init__(
        self,
        process: str,
        *,
        publishes: Iterable[Topic[Any]] = (),
        subscribes: Iterable[Topic[Any]] = (),
        serves: Iterable[Service[Any, Any]] = (),
        calls: Iterable[Service[Any, Any]] = (),
    ) -> None:
        object.__setattr__(self, "process", process)
        for kind, entries in zip(KINDS, (publishes, subscribes, serves, calls), strict=True):
            entries = frozenset(entries)
            wanted = Topic if kind in ("publishes", "subscribes") else Service
            for entry in entries:
                if not isinstance(entry, wanted):
                    raise TypeError(f"{process}: {kind} holds {entry!r}, not a {wanted.__name__}")
            object.__setattr__(self, kind, entries)

    def check(self, kind: Kind, entry: Topic[Any] | Service[Any, Any]) -> None:
        """Return if ``entry`` is among this process's ``kind`` ports, else raise PortRefused."""
        declared: frozenset[Any] = getattr(self, kind)
        if entry in declared:
            return
        verb = {"publishes": "publish", "subscribes": "subscribe to", "serves": "serve"}
        raise PortRefused(
            f"{self.process} does not {verb.get(kind, 'call')} {entry.template}: it declares "
            f"{kind} {sorted(e.template for e in declared)}"
        )

    def __or__(self, other: Ports) -> Ports:
        """The ports of both (one process made of two parts), named after this one."""
        return Ports(
            self.process,
            publishes=self.publishes | other.publishes,
            subscribes=self.subscribes | other.subscribes,
            serves=self.serves | other.serves,
            calls=self.calls | other.calls,
        )


def check(ports: Ports | None, kind: Kind, entry: Topic[Any] | Service[Any, Any]) -> None:
    """As :meth:`Ports.check`; a node without ports (``None``) may do anything."""
    if ports is not None:
        ports.check(kind, entry)
