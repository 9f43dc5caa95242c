"""Child processes that never outlive their parent: :func:`die_with_parent`, for
``subprocess.Popen(preexec_fn=die_with_parent)`` wherever the project starts a process (the
graph launcher, the firmware runner, the tests)."""

from __future__ import annotations

import contextlib
import ctypes
import signal

_PR_SET_PDEATHSIG = 1


def die_with_parent() -> None:  # pragma: no cover - runs in the child before exec
    """Ask Linux to send SIGTERM to the child if its parent dies, so nothing is orphaned.

    Called from the thread that lives as long as the children (Linux signals them when the
    forking *thread* ends).
    """
    with contextlib.suppress(OSError):
        ctypes.CDLL("libc.so.6", use_errno=True).prctl(_PR_SET_PDEATHSIG, signal.SIGTERM)
