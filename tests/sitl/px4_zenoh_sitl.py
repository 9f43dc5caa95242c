"""Real PX4 over its own Zenoh for the opt-in tier: a ``px4_sitl_zenoh`` build (PX4's ``zenoh``
module, built outside the repository from PX4's documentation), started with
``PX4_PARAM_ZENOH_ENABLE=1`` so its zenoh-pico dials ``tcp/127.0.0.1:7447``, and the graph
whose router listens there (compose/px4_zenoh*.yaml).

PX4 dials a fixed port, so the flights run in a network namespace of their own
(``unshare -n`` as root, loopback up): the router port must be free, or the flight fails
saying so. In a user namespace (``unshare -rn``) PX4 is refused its real-time priorities and
runs as an ordinary process (:func:`realtime_share`).
``PX4_SITL_INSTANCE`` picks PX4's instance (its /tmp/px4-sock-N is shared across namespaces);
unset, the first N in 1..9 with no such socket.
"""

from __future__ import annotations

import contextlib
import itertools
import os
import socket
import struct
import subprocess
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


ECHOED = "offboard_control_mode"
"""The uORB topic PX4's zenoh module is told to publish back (``/fmu/out/...``): PX4 writes
it only from what arrives on ``/fmu/in/offboard_control_mode``, and stamps each with its own
clock on arrival (``fix_timestamp`` of the module's subscriber), so the echo's stamps are the
moments the bridge's writes reached PX4's uORB, whatever the echo's own way back."""


def start_zenoh_with_echo(build: Path, number: int, workdir: Path) -> None:
    """PX4's zenoh module started with the uORB :data:`ECHOED` among its publishers (PX4's
    shell: ``zenoh config add publisher``, then ``zenoh start``)."""
    client = str(build / "bin" / "px4-zenoh")
    topic = f"/fmu/out/{ECHOED}"
    config = workdir / "px4" / "rootfs" / "zenoh" / "pub.csv"
    deadline = time.monotonic() + 60.0
    while not (config.is_file() and topic in config.read_text()):
        assert time.monotonic() < deadline, f"PX4's zenoh config has no {topic} ({config})"
        add = ["config", "add", "publisher", topic, ECHOED]
        subprocess.run([client, "--instance", str(number), *add], capture_output=True)
        time.sleep(1.0)
    started = subprocess.run(
        [client, "--instance", str(number), "start"], capture_output=True, text=True
    )
    assert started.returncode == 0, f"zenoh start failed: {started.stdout}{started.stderr}"


@contextlib.contextmanager
def px4_zenoh(workdir: Path, echo: bool = False) -> Iterator[Firmware]:
    """PX4 SIH with its zenoh module on, in ``workdir`` (PX4's own starter), with PX4's uORB
    :data:`ECHOED` published back when ``echo``; when the body fails, PX4's warnings and
    errors are printed (the workdir of a failed flight does not outlive the next runs)."""
    build = zenoh_build()
    assert build is not None, "PX4_SITL_DIR names no px4_sitl_zenoh build"
    number = instance()
    env = {"PX4_PARAM_ZENOH_ENABLE": "0" if echo else "1"}
    with px4_sih(build, workdir, instance=number, env=env) as firmware:
        if echo:
            start_zenoh_with_echo(build, number, workdir)
        try:
            yield firmware
        except BaseException:
            print(
                f"\nPX4's log ({firmware.log}), warnings and errors:\n{log_problems(firmware.log)}"
            )
            raise


SCHED_FIFO = 1  # the policy field of /proc/<pid>/task/<tid>/stat


def realtime_share(workdir: Path) -> tuple[int, int]:
    """(threads with SCHED_FIFO, threads) of the PX4 running in ``workdir``. PX4 SITL asks for
    real-time priorities (its SIH, estimator, commander, the zenoh module and zenoh-pico's
    read task at 50-99); where they are refused (a user namespace, ``unshare -rn``) it runs
    every thread as an ordinary process at the test's niceness, and on a loaded machine its
    own sensors time out (PX4's "No valid data from Baro"), which no bridge can mend."""
    home = str((workdir / "px4" / "rootfs").resolve())
    for proc in Path("/proc").iterdir():
        with contextlib.suppress(OSError):
            if proc.name.isdigit() and (proc / "comm").read_text().strip() == "px4":
                if os.readlink(proc / "cwd") != home:
                    continue
                policies = []
                for task in (proc / "task").iterdir():
                    with contextlib.suppress(OSError):
                        stat = (task / "stat").read_text()
                        policies.append(int(stat[stat.rindex(")") + 2 :].split()[38]))
                return sum(p == SCHED_FIFO for p in policies), len(policies)
    return 0, 0


LEFT_ON_ITS_OWN = "without a request from the bridge"  # the bridge's words when PX4 leaves
STOPPING = "SIGINT received"  # a graph's process told to stop: the flight is over


def left_offboard_in_flight(graph_log: str) -> bool:
    """True if the bridge saw PX4 leave OFFBOARD on its own (its offboard-loss failsafe)
    before the graph began to stop: a flight cut short, which may still have enough samples
    to pass the thresholds."""
    lines = graph_log.splitlines()
    left = next((i for i, line in enumerate(lines) if LEFT_ON_ITS_OWN in line), None)
    stop = next((i for i, line in enumerate(lines) if STOPPING in line), len(lines))
    return left is not None and left < stop


def log_problems(path: Path, limit: int = 60) -> str:
    """The last ``limit`` WARN / ERROR lines of PX4's log (its own words: failsafes, zenoh)."""
    lines = path.read_text(errors="replace").splitlines() if path.is_file() else []
    problems = [line for line in lines if "WARN" in line or "ERROR" in line]
    return "\n".join(problems[-limit:])


class LinkWatch:
    """When, on the router PX4 dials, the bridge's ``offboard_control_mode`` writes, PX4's
    ``vehicle_local_position`` samples and (with PX4's echo, :func:`px4_zenoh`) PX4's uORB
    ``offboard_control_mode`` arrive (Unix s, to read beside the logs): their longest pauses
    tell a bridge that stopped writing from a PX4 link that stopped carrying (PX4 leaves
    OFFBOARD after 1 s without an ``offboard_control_mode`` in its uORB). The echo's own
    stamps (PX4's clock, s) tell when the writes reached PX4's uORB, whatever the echo's way
    back. It connects once the graph's router is up."""

    KEYS: ClassVar[dict[str, str]] = {
        "bridge writes": "0/fmu/in/offboard_control_mode/**",
        "PX4 samples": "0/fmu/out/vehicle_local_position/**",
        "PX4 uORB echo": f"0/fmu/out/{ECHOED}/**",
    }

    def __init__(self) -> None:
        self.times: dict[str, list[float]] = {name: [] for name in self.KEYS}
        self.px4_stamps: list[float] = []  # the echo's stamps: arrival in PX4's uORB, PX4's s
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
                    session.declare_subscriber(key, self._arrived(name))
                self._session = session
                return
            self._stop.wait(1.0)

    def _arrived(self, name: str):
        times = self.times[name]
        echo = name == "PX4 uORB echo"

        def on_sample(sample) -> None:
            times.append(time.time())
            if echo:  # CDR: a 4-byte header, then the uint64 timestamp (PX4's us)
                payload = sample.payload.to_bytes()
                self.px4_stamps.append(struct.unpack_from("<Q", payload, 4)[0] / 1e6)

        return on_sample

    @staticmethod
    def longest_pause(times: list[float]) -> tuple[float, float]:
        """The longest pause between two of ``times`` (s) and when it began."""
        return max(((b - a, a) for a, b in itertools.pairwise(times)), default=(0.0, 0.0))

    def describe(self) -> str:
        """The longest pause of each stream, and how many samples it had."""
        parts = []
        for name, times in self.times.items():
            gap, since = self.longest_pause(list(times))
            at = time.strftime("%H:%M:%S", time.gmtime(since))
            parts.append(f"{name}: {len(times)}, longest pause {gap:.2f} s from {at} UTC")
        if self.px4_stamps:
            gap, _ = self.longest_pause(list(self.px4_stamps))
            parts.append(f"PX4 uORB stamps: longest pause {gap:.2f} s (PX4's clock)")
            # a stall that lasts to the end of the record is no pause between two arrivals
            last = self.times["PX4 uORB echo"][-1]
            late = sum(t > last for t in self.times["bridge writes"])
            parts.append(f"bridge writes after PX4's last echo: {late}")
        return "; ".join(parts)

    def dump(self, path: Path) -> None:
        """Every arrival and stamp, as JSON, for a closer look beside other records."""
        import json

        path.write_text(json.dumps({**self.times, "PX4 uORB stamps": self.px4_stamps}))
