"""The newest-frame mailbox: only the newest item is taken; skipped ones are countable."""

from __future__ import annotations

import threading
import time

from dronewrapper_perception.newest import NewestSlot


def test_take_returns_newest_with_its_number():
    slot: NewestSlot[str] = NewestSlot()
    assert slot.take(0.01, newer_than=0) is None
    for name in ("a", "b", "c"):
        slot.put(name)
    assert slot.take(0.01, newer_than=0) == (3, "c")  # a and b were dropped
    assert slot.take(0.01, newer_than=3) is None  # nothing newer
    slot.put("d")
    assert slot.take(0.01, newer_than=3) == (4, "d")


def test_take_wakes_when_an_item_arrives():
    slot: NewestSlot[int] = NewestSlot()
    threading.Timer(0.05, slot.put, args=(7,)).start()
    start = time.monotonic()
    assert slot.take(5.0, newer_than=0) == (1, 7)
    assert time.monotonic() - start < 4.0
