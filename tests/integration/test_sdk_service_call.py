"""Service calls right after a session opens, on a real Zenoh router.

Zenoh may not know a server's queryable for a moment after a session opens or a server starts;
a query then ends at once, unanswered. A call must keep asking (within its timeout) rather than
report "no reply within 10 s" after a few milliseconds.
"""

from __future__ import annotations

import threading
import time

import pytest

from dronewrapper.msgs import registry
from dronewrapper.msgs.mavros import ParamGet, ParamGetResult, ParamValue
from dronewrapper.runtime import ServiceUnavailable
from dronewrapper.runtime.session import ROUTE_WAIT_S
from support import client_node

pytestmark = pytest.mark.integration


def test_a_call_waits_for_a_server_that_starts_a_moment_later(router):
    with client_node(router, name="user") as user, client_node(router, name="server") as server:

        def serve_later() -> None:
            time.sleep(0.3)
            server.serve(
                registry.PARAM_GET,
                lambda req: ParamGetResult(success=True, value=ParamValue(integer=7)),
            )

        thread = threading.Thread(target=serve_later, daemon=True)
        thread.start()
        t0 = time.monotonic()
        reply = user.call(registry.PARAM_GET, ParamGet(param_id="P"), timeout=10)
        assert reply.success and reply.value.integer == 7
        assert time.monotonic() - t0 >= 0.3  # it was asked again after the first, unanswered
        thread.join(5)


def test_a_call_without_server_gives_up_within_its_timeout(router):
    with client_node(router, name="user") as user:
        t0 = time.monotonic()
        with pytest.raises(ServiceUnavailable, match="cmd/arming"):
            user.call(registry.ARMING, registry.ARMING.request(value=False), timeout=1.0)
        elapsed = time.monotonic() - t0
        assert elapsed >= min(1.0, ROUTE_WAIT_S) - 0.1  # kept asking for the route wait
        assert elapsed < 5.0  # and stopped (the timeout is 1 s; generous for a busy machine)
