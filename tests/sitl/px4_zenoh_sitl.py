"""Real PX4 over its own Zenoh for the opt-in tier: a ``px4_sitl_zenoh`` build (PX4's ``zenoh``
module, built outside the repository from PX4's documentation), started with
``PX4_PARAM_ZENOH_ENABLE=1`` so its zenoh-pico dials ``tcp/127.0.0.1:7447``, and the graph
whose router listens there (compose/px4_zenoh*.yaml).

PX4 dials a fixed port, so the flights run in a network namespace of their own
(``unshare -rn``, loopback up): the router port must be free, or the flight fails saying so.
``PX4_SITL_INSTANCE`` picks PX4's instance (its /tmp/px4-sock-N is shared across namespaces);
unset, the first N in 1..9 with no such socket.
"""

from __future__ import annotations

import contextlib
import itertools
import os
import socket
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import ClassVar

from firmware import px4_dir

from dronewrapper.runtime.node import open_session
from dronewrapper.runtime.options import DEFAULT_ROUTER, ZenohOptions
from dronewrapper_sim.external.firmware import Firmware, px4_sih

ROUTER_PORT = int(DEFAULT_ROUTER.rsplit(":", 1)[1])  # 7447: where PX4's zenoh-pico dials


def zenoh_build() -> Path | None:
    """The ``px4_sitl_zenoh`` build ``PX4_SITL_DIR`` names (the build, or a PX4 tree holding
    build/px4_sitl_zenoh), None when it names none with PX4's zenoh module."""
    root = px4_dir()
    if root is None:
        return None
    for build in (root, root / "build" / "px4_sitl_zenoh"):
        if (build / "bin" / "px4").is_file() and (build / "src" / "modules" / "zenoh").is_dir():
            return build
    return None


def instance() -> int:
    """PX4's instance: ``PX4_SITL_INSTANCE``, else the first without a lock socket."""
    chosen = os.environ.get("PX4_SITL_INSTANCE", "").strip()
    if chosen:
        return int(chosen)
    for n in range(1, 10):
        if not Path(f"/tmp/px4-sock-{n}").exists():
            return n
    raise RuntimeError("no free PX4 SITL instance (1..9)")


def router_port_free() -> bool:
    with socket.socket() as sock:
        return sock.connect_ex(("127.0.0.1", ROUTER_PORT)) != 0


@contextlib.contextmanager
def px4_zenoh(workdir: Path) -> Iterator[Firmware]:
    """PX4 SIH with its zenoh module on, in ``workdir`` (PX4's own starter); when the body
    fails, PX4's warnings and errors are printed (the workdir of a failed flight does not
    outlive the next runs)."""
    build = zenoh_build()
    assert build is not None, "PX4_SITL_DIR names no px4_sitl_zenoh build"
    env = {"PX4_PARAM_ZENOH_ENABLE": "1"}
    with px4_sih(build, workdir, instance=instance(), env=env) as firmware:
        try:
            yield firmware
        except BaseException:
            print(
                f"\nPX4's log ({firmware.log}), warnings and errors:\n{log_problems(firmware.log)}"
            )
            raise


def log_problems(path: Path, limit: int = 60) -> str:
    """The last ``limit`` WARN / ERROR lines of PX4's log (its own words: failsafes, zenoh)."""
    lines = path.read_text(errors="replace").splitlines() if path.is_file() else []
    problems = [line for line in lines if "WARN" in line or "ERROR" in line]
    return "\n".join(problems[-limit:])


class LinkWatch:
    """When, on the router PX4 dials, the bridge's ``offboard_control_mode`` writes and PX4's
    ``vehicle_local_position`` samples arrive (Unix s, to read beside the logs): their longest
    pauses tell a bridge that stopped writing from a PX4 link that stopped carrying (PX4 leaves
    OFFBOARD after 1 s without an ``offboard_control_mode``). It connects once the graph's
    router is up."""

    KEYS: ClassVar[dict[str, str]] = {
        "bridge writes": "0/fmu/in/offboard_control_mode/**",
        "PX4 samples": "0/fmu/out/vehicle_local_position/**",
    }

    def __init__(self) -> None:
        self.times: dict[str, list[float]] = {name: [] for name in self.KEYS}
        self._stop = threading.Event()
        self._session = None
        self._thread = threading.Thread(target=self._connect, daemon=True)

    def __enter__(self) -> LinkWatch:
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        self._thread.join(timeout=5.0)
        if self._session is not None:
            self._session.close()

    def _connect(self) -> None:
        while not self._stop.is_set():
            with contextlib.suppress(Exception):  # the router is not up yet
                session = open_session(ZenohOptions(mode="client", connect=[DEFAULT_ROUTER]))
                for name, key in self.KEYS.items():
                    session.declare_subscriber(key, self._arrived(self.times[name]))
                self._session = session
                return
            self._stop.wait(1.0)

    @staticmethod
    def _arrived(times: list[float]):
        return lambda _sample: times.append(time.time())

    def describe(self) -> str:
        """The longest pause of each stream, and how many samples it had."""
        parts = []
        for name, times in self.times.items():
            gaps = [(b - a, a) for a, b in itertools.pairwise(list(times))]
            gap, since = max(gaps, default=(0.0, 0.0))
            at = time.strftime("%H:%M:%S", time.gmtime(since))
            parts.append(f"{name}: {len(times)}, longest pause {gap:.2f} s from {at} UTC")
        return "; ".join(parts)
