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
import os
import signal
import socket
import subprocess
from collections.abc import Iterator
from pathlib import Path

from firmware import px4_dir

from dronewrapper.runtime.children import die_with_parent
from dronewrapper.runtime.options import DEFAULT_ROUTER
from dronewrapper_sim.external.firmware import px4_version

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
def px4_zenoh(workdir: Path) -> Iterator[tuple[str, Path]]:
    """PX4 SIH (``sihsim_quadx``) with its zenoh module on, in ``workdir``: (version, log)."""
    build = zenoh_build()
    assert build is not None, "PX4_SITL_DIR names no px4_sitl_zenoh build"
    home = workdir / "px4"
    (home / "rootfs").mkdir(parents=True, exist_ok=True)
    for name in ("bin", "etc"):
        if not (home / name).exists():
            (home / name).symlink_to(build / name)
    env = {
        **os.environ,
        "PX4_SIM_MODEL": "sihsim_quadx",
        "PX4_SIMULATOR": "sihsim",
        "HEADLESS": "1",
        "PX4_PARAM_ZENOH_ENABLE": "1",
    }
    log_path = workdir / "px4.log"
    with open(log_path, "wb") as log:
        proc = subprocess.Popen(
            ["../bin/px4", "-i", str(instance()), "-d"],
            cwd=home / "rootfs",
            env=env,
            stdin=subprocess.DEVNULL,
            stdout=log,
            stderr=subprocess.STDOUT,
            preexec_fn=die_with_parent,
        )
        try:
            yield px4_version(build), log_path
        finally:
            proc.send_signal(signal.SIGTERM)
            try:
                proc.wait(10)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
