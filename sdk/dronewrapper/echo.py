"""``dronewrapper echo KEYEXPR``: print decoded messages, like ``rostopic echo``.

Each sample's key is looked up in the registry to find its type; images print as a summary
(size, encoding, stamp) rather than their bytes.
"""

from __future__ import annotations

import json
import math
import sys
import threading
import time
from typing import Any, TextIO

import msgspec
import zenoh

from dronewrapper.msgs import codec
from dronewrapper.msgs.registry import topic_for_key


def _summarise(value: Any) -> Any:
    if isinstance(value, dict):
        return {k: _summarise(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_summarise(v) for v in value]
    if isinstance(value, bytes | memoryview):
        return f"<{len(value)} bytes>"
    if isinstance(value, float) and not math.isfinite(value):
        return str(value)
    return value


def format_sample(key: str, payload: bytes) -> str:
    """One printable line for a sample: the key and the decoded message as JSON."""
    topic = topic_for_key(key)
    if topic is None:
        return f"{key}: <unregistered key, {len(payload)} bytes>"
    try:
        msg = codec.decode(topic.type, payload)
    except (msgspec.DecodeError, msgspec.ValidationError) as exc:
        return f"{key}: <undecodable {topic.type.__name__}: {exc}>"
    body = _summarise(msgspec.to_builtins(msg, builtin_types=(bytes, memoryview)))
    return f"{key} [{topic.type.__name__}] {json.dumps(body, separators=(',', ':'))}"


def echo(
    session: zenoh.Session,
    keyexpr: str,
    *,
    count: int = 0,
    duration: float = 0.0,
    stop: threading.Event | None = None,
    out: TextIO = sys.stdout,
) -> int:
    """Print samples on ``keyexpr`` until ``count`` printed, ``duration`` s passed, or ``stop``."""
    stop = stop or threading.Event()
    printed = 0
    lock = threading.Lock()

    def on_sample(sample: zenoh.Sample) -> None:
        nonlocal printed
        line = format_sample(str(sample.key_expr), sample.payload.to_bytes())
        with lock:
            if count and printed >= count:
                return
            print(line, file=out, flush=True)
            printed += 1
            if count and printed >= count:
                stop.set()

    sub = session.declare_subscriber(keyexpr, on_sample)
    deadline = time.monotonic() + duration if duration > 0 else math.inf
    try:
        while not stop.wait(0.1):
            if time.monotonic() >= deadline:
                break
    finally:
        sub.undeclare()
    return printed
