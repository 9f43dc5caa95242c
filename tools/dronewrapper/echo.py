"""``dronewrapper echo KEYEXPR``: print decoded messages, like ``rostopic echo``.

Each sample's key is looked up in the registry to find its type; images print as a summary
(size, encoding, stamp) rather than their bytes. When nothing arrives for a few seconds, echo says
so on stderr, with the keys that are being published nearby; a closed output pipe
(``dronewrapper echo ... | head``) ends it quietly. Every few seconds and at the end, echo says on
stderr each key's measured rate and newest sample's age against the rate the registry declares
for it (:func:`dronewrapper.health.describe_stream`), and when a key goes stale.
"""

from __future__ import annotations

import difflib
import json
import math
import os
import sys
import threading
import time
from collections.abc import Callable
from typing import Any, TextIO

import msgspec
import zenoh

from dronewrapper.health import (
    StreamHealth,
    StreamLog,
    describe_stream,
    is_stale,
    judge_stream,
    stale_after,
)
from dronewrapper.msgs import codec
from dronewrapper.msgs.registry import TOPICS, topic_for_key
from dronewrapper.msgs.sensor import CompressedImage, Image

QUIET_AFTER_S = 3.0
"""Seconds without a sample after which echo says that nothing arrives."""
RATES_EVERY_S = 10.0
"""Seconds between two reports of each key's rate and age (stderr)."""
ARRIVALS_KEPT = 64
"""Arrivals kept per key to measure its rate (the newest ones)."""


class RateWatch:
    """Arrival times per key, judged against the registry's rates (pure; time passed in).

    ``add`` records a sample's arrival (monotonic s); ``report`` gives one line per key
    (:func:`describe_stream`); ``newly_stale`` names the keys that went stale since last asked.
    """

    def __init__(self) -> None:
        self.logs: dict[str, StreamLog] = {}
        self._stale: set[str] = set()

    def add(self, key: str, arrival: float, size: int) -> None:
        log = self.logs.setdefault(key, StreamLog())
        log.add(arrival, None, size)
        if len(log.arrivals) > 2 * ARRIVALS_KEPT:
            del log.arrivals[:-ARRIVALS_KEPT]
        self._stale.discard(key)

    def health(self, now: float) -> list[StreamHealth]:
        return [
            judge_stream(key, declared_rate(key), log, now)
            for key, log in sorted(self.logs.items())
        ]

    def report(self, now: float) -> list[str]:
        return [describe_stream(health) for health in self.health(now)]

    def newly_stale(self, now: float) -> list[str]:
        """Lines for the keys whose newest sample became stale since the last call."""
        lines = []
        for key, log in sorted(self.logs.items()):
            rate = declared_rate(key)
            age = now - log.arrivals[-1]
            if key not in self._stale and is_stale(rate, age):
                self._stale.add(key)
                lines.append(
                    f"{key} is stale: nothing for {age:.1f} s (declared {rate:g} Hz, stale "
                    f"after {stale_after(rate):g} s)"
                )
        return lines


def declared_rate(key: str) -> float:
    """The registry's rate for a concrete key (Hz; 0 for event streams and unknown keys)."""
    topic = topic_for_key(key)
    return topic.rate_hz if topic is not None else 0.0


def keyexpr_problem(keyexpr: str) -> str | None:
    """Why ``keyexpr`` cannot be a Zenoh key expression, with a hint; None if it can (pure)."""
    if keyexpr.startswith("/"):
        return f"key expressions have no leading '/': try {keyexpr.lstrip('/')!r}"
    if keyexpr.endswith("/") or "//" in keyexpr or not keyexpr:
        return f"{keyexpr!r} has an empty chunk; chunks are separated by single '/'"
    return None


def path_warning(argument: str, exists: Callable[[str], bool] = os.path.exists) -> str | None:
    """A warning when a key expression argument names a file or folder here: the shell expanded
    an unquoted ``sim/**`` into paths (pure apart from ``exists``)."""
    if not exists(argument):
        return None
    return (
        f"{argument!r} is a file or folder in this directory: did the shell expand an unquoted "
        f"key expression? Quote it, as in 'sim/**'"
    )


def light_key_families() -> list[str]:
    """Wildcards of every registered topic that carries no images (cheap to listen to)."""
    heavy = (Image, CompressedImage)
    return sorted({t.wildcard() for t in TOPICS.values() if t.type not in heavy})


def nearby(keyexpr: str, seen: set[str], limit: int = 6) -> list[str]:
    """The keys in ``seen`` that look most like ``keyexpr``, most alike first (pure)."""
    return difflib.get_close_matches(keyexpr, sorted(seen), n=limit, cutoff=0.3)


def published_keys(session: zenoh.Session, listen_s: float) -> set[str]:
    """The concrete keys of the registry's image-free topics published within ``listen_s``."""
    seen: set[str] = set()
    subs = [
        session.declare_subscriber(family, lambda s: seen.add(str(s.key_expr)))
        for family in light_key_families()
    ]
    try:
        time.sleep(listen_s)
    finally:
        for sub in subs:
            sub.undeclare()
    return set(seen)


def silence_notice(keyexpr: str, waited_s: float, seen: set[str]) -> str:
    """What to tell a user who has received nothing on ``keyexpr`` (pure)."""
    head = f"nothing received on {keyexpr!r} in {waited_s:.0f} s"
    close = nearby(keyexpr, seen)
    if close:
        return f"{head}; published nearby: {', '.join(close)}"
    if seen:
        return f"{head}; {len(seen)} other keys are published (see: dronewrapper echo '**')"
    return f"{head}; nothing else is published: is the graph running? (dronewrapper alive)"


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
    quiet_after_s: float = QUIET_AFTER_S,
    rates_every_s: float = RATES_EVERY_S,
    notice: Callable[[str], None] = lambda text: print(
        f"dronewrapper echo: {text}", file=sys.stderr
    ),
) -> int:
    """Print samples on ``keyexpr`` until ``count`` printed, ``duration`` s passed, ``stop``, or
    the output is closed; every ``rates_every_s`` (0: never) and at the end, ``notice`` each
    key's rate and age against the registry. Returns the number printed."""
    stop = stop or threading.Event()
    printed = 0
    lock = threading.Lock()
    rates = RateWatch()

    def on_sample(sample: zenoh.Sample) -> None:
        nonlocal printed
        key, payload = str(sample.key_expr), sample.payload.to_bytes()
        line = format_sample(key, payload)
        with lock:
            rates.add(key, time.monotonic(), len(payload))
            if stop.is_set() or (count and printed >= count):
                return
            try:
                print(line, file=out, flush=True)
            except (BrokenPipeError, ValueError):  # reader gone (| head), or out closed
                stop.set()
                return
            printed += 1
            if count and printed >= count:
                stop.set()

    sub = session.declare_subscriber(keyexpr, on_sample)
    started = time.monotonic()
    deadline = started + duration if duration > 0 else math.inf
    noticed = quiet_after_s <= 0
    next_rates = started + rates_every_s if rates_every_s > 0 else math.inf
    try:
        while not stop.wait(0.1):
            now = time.monotonic()
            if now >= deadline:
                break
            if not noticed and printed == 0 and now - started >= quiet_after_s:
                noticed = True
                notice(silence_notice(keyexpr, now - started, published_keys(session, 1.0)))
            with lock:
                lines = rates.newly_stale(now)
                if now >= next_rates:
                    next_rates = now + rates_every_s
                    lines += rates.report(now)
            for line in lines:
                notice(line)
    finally:
        sub.undeclare()
    if rates_every_s > 0:
        with lock:
            for line in rates.report(time.monotonic()):
                notice(line)
    return printed
