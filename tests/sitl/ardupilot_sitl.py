"""Run real ArduCopter SITL (ArduPilot's software-in-the-loop build, built-in quad physics)
for a test: a free instance number, its own working directory, stopped at the end."""

from __future__ import annotations

import contextlib
import os
import signal
import socket
import subprocess
from collections.abc import Iterator
from pathlib import Path

from dronewrapper.runtime.children import die_with_parent

ENV = "DRONEWRAPPER_ARDUPILOT_SITL"  # names the arducopter binary; unset: tier deselected
BASE_TCP_PORT = 5760  # SERIAL0 of instance N listens on 5760 + 10 N


def sitl_binary() -> Path | None:
    """The arducopter binary named by the environment, or None when the tier is off."""
    value = os.environ.get(ENV, "").strip()
    return Path(value).expanduser() if value else None


def defaults_of(binary: Path) -> Path:
    """Tools/autotest/default_params/copter.parm of the tree the binary was built in."""
    tree = binary.resolve().parents[3]  # <tree>/build/sitl/bin/arducopter
    return tree / "Tools" / "autotest" / "default_params" / "copter.parm"


def _tcp_free(port: int) -> bool:
    with socket.socket() as sock:
        try:
            sock.bind(("127.0.0.1", port))
        except OSError:
            return False
    return True


def free_instance(first: int = 1, last: int = 60) -> int:
    """An instance number whose SERIAL0 port (and the next two) is free now."""
    for instance in range(first, last):
        base = BASE_TCP_PORT + 10 * instance
        if all(_tcp_free(base + k) for k in range(3)):
            return instance
    raise RuntimeError("no free ArduPilot SITL instance")


@contextlib.contextmanager
def arducopter_sitl(binary: Path, workdir: Path) -> Iterator[tuple[int, Path]]:
    """Start ``arducopter --model quad`` (wiped parameters, copter defaults) in ``workdir``;
    yields (SERIAL0 TCP port, log path). It waits for a client on that port before flying."""
    if not binary.is_file():
        raise FileNotFoundError(f"{binary}: no such arducopter SITL binary")
    defaults = defaults_of(binary)
    instance = free_instance()
    log_path = workdir / "arducopter.log"
    argv = [
        str(binary),
        "--model", "quad", "--speedup", "1", f"-I{instance}", "-w",
        "--defaults", str(defaults),
    ]  # fmt: skip
    with open(log_path, "wb") as log:
        proc = subprocess.Popen(
            argv, cwd=workdir, stdout=log, stderr=subprocess.STDOUT, preexec_fn=die_with_parent
        )
        try:
            yield BASE_TCP_PORT + 10 * instance, log_path
        finally:
            proc.send_signal(signal.SIGTERM)
            try:
                proc.wait(10)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait(5)
