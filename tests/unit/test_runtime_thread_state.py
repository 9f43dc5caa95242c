"""Python thread states kept for Zenoh's threads: once per thread, and never beyond the limit."""

from __future__ import annotations

from dronewrapper.runtime.thread_state import ThreadStates


def test_each_thread_keeps_its_state_once_and_no_more_than_the_limit_do():
    ensured: list[int] = []
    current = [1]
    states = ThreadStates(
        ensure=lambda: ensured.append(current[0]), ident=lambda: current[0], limit=2
    )
    for thread in (1, 1, 2, 1, 2, 3, 3):
        current[0] = thread
        states.keep()
    assert ensured == [1, 2]  # one Ensure per thread; the third thread is past the limit
    assert states.kept == 2
