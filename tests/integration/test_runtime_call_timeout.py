"""A server that receives a request but replies too late: the caller is told so, by name.

Zenoh ends such a query with its own error reply (``Timeout``); that is not the server's
refusal, so it must not reach a user as "command refused": it is a ServiceTimeout, a kind of
ServiceUnavailable (the SDK then tells a missing bridge from a slow one).
"""

from __future__ import annotations

import threading

import pytest

from dronewrapper.msgs import registry
from dronewrapper.msgs.mavros import ParamGet, ParamGetResult, ParamValue
from dronewrapper.runtime import ServiceTimeout, ServiceUnavailable
from support import client_node

pytestmark = pytest.mark.integration


def test_a_reply_later_than_the_timeout_is_a_timeout_not_a_refusal(router):
    release = threading.Event()
    received = threading.Event()

    def slow(request: ParamGet) -> ParamGetResult:
        received.set()
        release.wait(10.0)
        return ParamGetResult(success=True, value=ParamValue(integer=1))

    with client_node(router, name="user") as user, client_node(router, name="server") as server:
        server.serve(registry.PARAM_GET, slow)
        try:
            with pytest.raises(ServiceTimeout, match=r"no reply from .* within 0.5 s") as caught:
                user.call(registry.PARAM_GET, ParamGet(param_id="P"), timeout=0.5)
            assert received.is_set()  # the server did get it
            assert caught.value.code == "timeout"
            assert isinstance(caught.value, ServiceUnavailable)
        finally:
            release.set()
