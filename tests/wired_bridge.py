"""A bridge's pure core on the wiring every bridge shares (``BridgeNode``: publishers,
setpoint subscription, services behind the lease) over the fake bus, in the bus's time, with no
aircraft: what the service tests of the bridges' shared rules stand on."""

from __future__ import annotations

import logging
from types import ModuleType
from typing import Any

from dronewrapper.runtime.fake import FakeBus, FakeNode
from dronewrapper_bridge_base.bridge_node import BridgeNode


class Wired(BridgeNode):
    """The wiring with its sends to the aircraft dropped."""

    def send(self, out: Any) -> None:
        pass


def wire(core: Any, module: ModuleType, bus: FakeBus) -> Wired:
    """``core`` on a bridge node of ``bus`` publishing ``module.PUBLISHED`` and serving
    ``module.SERVICES`` (``module``: a bridge's ``node`` module): in the bus's time, which the
    node's clock is."""
    node = FakeNode("bridge", bus, ports=module.PORTS)
    bridge = Wired(
        node, core, {t: node.publisher(t) for t in module.PUBLISHED}, logging.getLogger()
    )
    bridge.serve(module.SERVICES)
    return bridge
