"""Calling a bridge's services with hand-made payloads, as the fuzz tests do: one raw reply,
the text of an error reply, and the check that every broken request of a shape is refused.
"""

from __future__ import annotations

from typing import Any

from fuzz_inputs import Bad, RequestShape, bad_request
from hypothesis import given

from dronewrapper.msgs import codec, registry
from dronewrapper.msgs.std import ErrorReply


def call_raw(user: Any, service: registry.Service, payload: bytes) -> Any:
    """One reply to a hand-made payload (Zenoh answers with exactly one, OK or error)."""
    replies = list(user.session.get(service.key("drone"), payload=payload, timeout=10))
    assert len(replies) == 1, f"{len(replies)} replies"
    return replies[0]


def error_text(reply: Any) -> str:
    """The message of an error reply (an OK reply fails the test)."""
    assert reply.err is not None, f"accepted: {reply.ok.payload.to_bytes()[:120]!r}"
    return codec.decode(ErrorReply, reply.err.payload.to_bytes()).message


def assert_refused(user: Any, shape: RequestShape, fuzz: Any) -> None:
    """Every broken request of ``shape`` (examples drawn under the hypothesis settings
    ``fuzz``) gets an error reply naming what is wrong."""

    @fuzz
    @given(bad=bad_request(shape))
    def refused(bad: Bad) -> None:
        message = error_text(call_raw(user, shape.service, bad.payload))
        assert bad.named in message, message

    refused()
