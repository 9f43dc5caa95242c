"""The shell and Python snippets of README.md and docs/*.md, and how each is checked (pure).

Every fenced ``sh`` or ``python`` block is listed in :data:`PLAN` under its
:attr:`Snippet.key` (``FILE: first command``): run against the one sim graph the docs test
brings up, or excluded with the reason it cannot run here. Inside a shell snippet a command
line can be left out, with its reason, and a command that runs until Ctrl-C gets a bound
(``--duration``). What a snippet needs of this machine (the graph's router, its TLS endpoint,
a key store, a scratch folder) is put in by :func:`adapt`, by plain text replacement of the
documented addresses and paths.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
DOCS = ["README.md", *sorted(f"docs/{p.name}" for p in (REPO / "docs").glob("*.md"))]
FENCE = re.compile(r"^```(\w*)\n(.*?)^```", re.M | re.S)
RUNNABLE = ("sh", "python")


@dataclass(frozen=True)
class Snippet:
    where: str  # FILE:LINE of the opening fence
    language: str
    text: str

    @property
    def key(self) -> str:
        """``FILE: first command`` (its first 50 characters, comment left out): how
        :data:`PLAN` names the snippet, unmoved by edits above it."""
        first = self.text.strip().splitlines()[0]
        code = first.split("#", 1)[0].strip() or first.strip()
        return f"{self.where.split(':')[0]}: {' '.join(code.split())[:50].rstrip()}"


def snippets() -> list[Snippet]:
    """Every ``sh`` and ``python`` block of the README and docs/, in document order."""
    found = []
    for doc in DOCS:
        text = (REPO / doc).read_text(encoding="utf-8")
        for match in FENCE.finditer(text):
            if match.group(1) in RUNNABLE:
                line = text.count("\n", 0, match.start()) + 1
                found.append(Snippet(f"{doc}:{line}", match.group(1), match.group(2)))
    return found


@dataclass(frozen=True)
class Excluded:
    """A snippet that cannot run here, and why."""

    reason: str


@dataclass(frozen=True)
class Run:
    """A snippet run against the graph.

    Attributes:
        skip: a command line containing the key is left out, for the reason given.
        bound: a command line containing the key gets these arguments (it would run until
            Ctrl-C).
        preamble: Python run before the snippet (a snippet that continues the one above it).
        same_as: the code (comments aside) is that of another snippet, which runs instead.
        unsudo: a leading ``sudo`` is dropped (what it runs needs no root once bounded).
    """

    skip: dict[str, str] = field(default_factory=dict)
    bound: dict[str, str] = field(default_factory=dict)
    preamble: str = ""
    same_as: str = ""
    unsudo: bool = False


HARDWARE = "needs the drone's hardware (serial autopilot, USB camera, Jetson GPU)"
LISTING = "README.md: from dronewrapper import DroneWrapper"
ASYNCIO = "docs/api.md: import asyncio"
RECORDING = "README.md: dronewrapper record 'drone/**' 'sim/**' -o flight."

PLAN: dict[str, Run | Excluded] = {
    "README.md: make demo": Excluded(
        "`make demo` brings up a graph of its own and `make test` is the whole suite; the "
        "scenario tier flies the demo"
    ),
    LISTING: Run(),  # the paper's listing, against the graph
    "README.md: .venv/bin/dronewrapper up compose/sim_iris.yaml &": Excluded(
        "brings up sim_iris (the docs test brings up its secure variant), runs "
        "examples/paper_listing.py (README.md:23's code, run here; test_examples.py runs the "
        "file) and a second graph (the scenario tier flies it)"
    ),
    "README.md: .venv/bin/dronewrapper keys init": Run(
        skip={"provision --connection /dev/ttyACM0": "an autopilot on USB (hardware)"}
    ),
    "README.md: .venv/bin/dronewrapper up compose/px4_real_follow_": Run(
        bound={"px4_real_follow_person_secure": "--check"}
    ),
    'README.md: drone = DroneWrapper(connect="tls/192.168.1.50:744': Run(
        preamble="from dronewrapper import DroneWrapper"
    ),
    RECORDING: Run(
        skip={"make demo": "the demo brings up a graph of its own"},
        bound={
            "dronewrapper record '": "--duration 2",
            "dronewrapper foxglove": "--port 0 --duration 1",  # not the fixed 8765
        },
    ),
    "docs/api.md: from dronewrapper import DroneWrapper": Run(same_as=LISTING),
    ASYNCIO: Run(),
    "docs/ardupilot.md: build/sitl/bin/arducopter --model quad --speedup 1": Excluded(
        "builds and runs ArduPilot's SITL (not installed here)"
    ),
    "docs/ardupilot.md: .venv/bin/dronewrapper up compose/ardupilot_sitl.y": Run(
        skip={
            "ardupilot_sitl.yaml &": "needs ArduPilot's SITL listening on 5760",
            "paper_listing.py": "flies the SITL above; the listing runs as README.md:23",
        },
        bound={"sitl_port=5770": "--check"},
    ),
    "docs/ardupilot.md: DRONEWRAPPER_ARDUPILOT_SITL=/path/to/ardupilot/bui": Excluded(
        "the opt-in SITL tier (needs ArduPilot's SITL binary)"
    ),
    "docs/ardupilot.md: python -m dronewrapper_bridge_mavlink --config ser": Excluded(HARDWARE),
    "docs/sitl_world.md: rm -f parameters*.bson dataman": Excluded(
        "runs PX4's SITL from a PX4 build (not installed here)"
    ),
    "docs/sitl_world.md: build/sitl/bin/arducopter --model quad --speedup 1": Excluded(
        "runs ArduPilot's SITL from an ArduPilot build (not installed here)"
    ),
    "docs/sitl_world.md: .venv/bin/dronewrapper up compose/px4_sitl_follow_": Excluded(
        "the graphs wait for PX4's SITL on its fixed ports (tests/sitl flies them, opt-in)"
    ),
    "docs/sitl_world.md: from dronewrapper import DroneWrapper": Excluded(
        "flies the firmware of the world-and-bridge graph above (needs a PX4 or ArduPilot build)"
    ),
    "docs/sitl_world.md: PX4_SITL_DIR=/path/to/PX4-Autopilot AP_SITL_DIR=/p": Excluded(
        "the opt-in firmware tier (needs PX4 and ArduPilot SITL builds)"
    ),
    "docs/px4_zenoh.md: .venv/bin/dronewrapper up compose/px4_zenoh.yaml": Excluded(
        "the graphs wait for px4_sitl_zenoh to dial their router (tests/sitl flies it, opt-in)"
    ),
    "docs/px4_zenoh.md: PX4_SIM_MODEL=sihsim_quadx PX4_SIMULATOR=sihsim HE": Excluded(
        "runs a px4_sitl_zenoh build of PX4 (not installed here)"
    ),
    "docs/px4_real.md: git clone <this repository> dronewrapper && cd dro": Excluded(
        "sets up a Jetson (apt groups, GPU wheels, the model)"
    ),
    "docs/px4_real.md: ls -l /dev/ttyUSB0 /dev/ttyTHS1 /dev/video0": Excluded(HARDWARE),
    "docs/px4_real.md: dronewrapper up compose/px4_real_follow_person_sec": Run(
        bound={"px4_real_follow_person_secure": "--check"}
    ),
    "docs/px4_real.md: pip install ./contract ./runtime './sdk[security,i": Run(
        skip={
            "pip install": "installs into an environment; tests/integration/test_sdk_install.py "
            "installs the SDK alone"
        },
        bound={"dronewrapper echo": "--duration 2"},
    ),
    "docs/px4_real.md: from dronewrapper import DroneWrapper": Run(),
    "docs/security.md: dronewrapper keys init": Run(),
    "docs/security.md: # drone: loopback for its own processes, TLS with": Run(
        skip={
            "dronewrapper router --listen": "a drone's fixed ports 7447 and "
            "7448; the graph the test brings up runs the same listeners on free ports"
        },
        bound={"px4_real_follow_person_secure": "--check"},
    ),
    'docs/security.md: drone = DroneWrapper(connect="tls/192.168.1.50:744': Run(
        preamble="from dronewrapper import DroneWrapper"
    ),
    "docs/security.md: dronewrapper keys mavlink": Run(
        skip={"provision --connection /dev/ttyACM0": "an autopilot on USB (hardware)"}
    ),
    "docs/security.md: # joined to the Tello's open network, from the lap": Excluded(
        "a real Tello's Wi-Fi access point at 192.168.10.1"
    ),
    "docs/fleet.md: dronewrapper up compose/sim_fleet.yaml --var drone": Excluded(
        "starts fleets of its own until Ctrl-C (tests/integration/test_sim_fleet.py runs the "
        "graph with five drones of both kinds)"
    ),
    "docs/fleet.md: from dronewrapper.fleet import Fleet": Excluded(
        "needs five drones online, not the docs test's one (tests/integration/test_sim_fleet.py "
        "and examples/swarm.py fly the same calls on a fleet graph)"
    ),
    "docs/fleet.md: sudo ip addr add 192.168.1.101/24 dev wlan0": Excluded(
        "real Tellos on a classroom's access point, and a Wi-Fi interface to add addresses to"
    ),
    "docs/fleet.md: dronewrapper up compose/classroom_tello.yaml --var": Excluded(
        "starts its own classroom until Ctrl-C (tests/integration/test_classroom_tello.py runs "
        "the same graph and three Tello simulators)"
    ),
    "docs/fleet.md: dronewrapper keys issue field --role drone": Excluded(
        "issues from a key store whose CA was made before (tests/network/test_fleet_routers.py "
        "issues and exports the same three identities with KeyStore, as root)"
    ),
    "docs/fleet.md: # link box: listens for both ends": Excluded(
        "three computers joined by a radio link (tests/network/test_fleet_routers.py builds "
        "them with network namespaces, as root)"
    ),
    "docs/jetson.md: sudo apt-get install -y python3-venv python3-dev g": Excluded(
        "sets up a Jetson: apt packages, a clone, its .venv (make onboard: make setup without "
        "the test tools) and the user's groups"
    ),
    "docs/jetson.md: .venv/bin/pip uninstall -y onnxruntime": Excluded(
        "replaces onnxruntime by NVIDIA's aarch64 build for JetPack 6 (a Jetson only)"
    ),
    'docs/jetson.md: .venv/bin/python -c "import onnxruntime; print(onn': Run(),
    "docs/jetson.md: .venv/bin/dronewrapper doctor --hardware --serial": Excluded(
        "needs the autopilot on /dev/ttyTHS1; tests/integration/test_doctor_hardware.py runs "
        "the same check on a pseudo-terminal with an autopilot's heartbeats"
    ),
    "docs/jetson.md: .venv/bin/dronewrapper keys init": Run(
        skip={"provision --connection /dev/ttyACM0": "an autopilot on USB (hardware)"}
    ),
    "docs/jetson.md: .venv/bin/dronewrapper up compose/px4_real_follow_": Run(
        bound={"dronewrapper install": "--print"}, unsudo=True
    ),
    "docs/jetson.md: systemctl status dronewrapper-px4_real_follow_pers": Excluded(
        "the installed unit on a Jetson booted with systemd (test_install_unit.py installs it "
        "into a temporary root and verifies it; test_doctor.py runs doctor against a graph)"
    ),
    "docs/jetson.md: sudo .venv/bin/dronewrapper uninstall compose/px4_": Excluded(
        "removes the unit from a Jetson (test_install_unit.py uninstalls from a temporary root)"
    ),
}

DRONE_ADDRESSES = ("tls/192.168.1.50:7448",)
"""The drone's router as the docs write it; the test's TLS endpoint replaces it."""
LOCAL_ROUTER = "tcp/127.0.0.1:7447"
"""The default router as the docs write it; the test's graph router replaces it."""


def code_lines(text: str) -> list[str]:
    """The code of a snippet without comments and blank lines (to compare two snippets)."""
    out = []
    for line in text.splitlines():
        code = line.split("#", 1)[0].rstrip()
        if code:
            out.append(code)
    return out


def adapt(
    snippet: Snippet, plan: Run, *, router: str, tls: str, bin_dir: str, scratch: str
) -> tuple[str, list[str]]:
    """The snippet as it runs here (in ``scratch``), and the lines left out with their reasons."""
    text = snippet.text
    for address in DRONE_ADDRESSES:
        text = text.replace(address, tls)
    text = text.replace(LOCAL_ROUTER, router).replace("/media/usb/", f"{scratch}/usb/")
    text = text.replace(".venv/bin/", f"{bin_dir}/")
    text = re.sub(r"(?<=\s)(compose|examples)/", lambda m: f"{REPO}/{m.group(1)}/", text)
    if snippet.language == "python":
        return (plan.preamble + "\n" + text if plan.preamble else text), []
    kept, left_out = [], []
    for line in _commands(text):
        reason = next((why for key, why in plan.skip.items() if key in line), None)
        if reason is not None:
            left_out.append(f"{line.strip()}  ({reason})")
            continue
        for key, extra in plan.bound.items():
            if key in line:
                line = _insert_before_comment(line, extra)
        if plan.unsudo:
            line = re.sub(r"^(\s*)sudo\s+", r"\1", line)
        kept.append(_without_placeholders(line))
    return "\n".join(kept), left_out


def _commands(text: str) -> list[str]:
    """The shell text as one line per command (backslash continuations joined)."""
    return [line for line in text.replace("\\\n", " ").splitlines() if line.strip()]


def _insert_before_comment(line: str, extra: str) -> str:
    code, hash_, comment = line.partition(" #")
    return f"{code.rstrip().removesuffix('&').rstrip()} {extra}" + (
        f"  #{comment}" if hash_ else ""
    )


def _without_placeholders(line: str) -> str:
    """``[--loop]``-style optional arguments dropped (they document, they do not run)."""
    code, hash_, comment = line.partition(" #")
    code = re.sub(r"\s\[[^\]]*\]", "", code)
    return code + (f" #{comment}" if hash_ else "")
