"""Simulator aircraft cost: physics steps/s, and CPU of the sim process idle and flying.

1. Physics: quadrotor dynamics + position controller steps per second (pure Python, one
   core), and whole autopilot steps per second (commander, controller, dynamics, battery and
   the telemetry of both links, as the real-time loop runs them).
2. Process CPU: ``python -m dronewrapper_sim --no-cameras`` (and with cameras on but nobody
   watching), measured from ``/proc/PID/stat`` (utime + stime) over ``--seconds``: idle on
   the ground, then flying in OFFBOARD (a MAVLink client streaming body velocities at 20 Hz).
   100 % = one core. PX4 SITL (SIH) on this machine kind: ~12 % idle, ~15-16 % flying.
Run: ``python -m bench.sim_physics [--seconds 10]``; writes bench/results/sim_physics.json.
"""

from __future__ import annotations

import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

from bench.common import LoopbackRouter, cpu_seconds, print_table, write_results
from dronewrapper.runtime.arguments import CommandParser, first_line

REPO = Path(__file__).resolve().parents[1]
DT = 1.0 / 250.0


def physics_rates(seconds: float = 3.0) -> dict[str, float]:
    from dronewrapper_sim.dynamics import GRAVITY, QuadParams, QuadState, step
    from dronewrapper_sim.px4.autopilot import Autopilot
    from dronewrapper_sim.px4.flight_control import PositionController, Target

    params, ctrl = QuadParams(), PositionController()
    state = QuadState(z=10.0, on_ground=False, thrust=GRAVITY)
    target = Target(velocity=(2.0, 0.0, 0.0), yaw_rate=0.2)
    n, t0 = 0, time.perf_counter()
    while time.perf_counter() - t0 < seconds:
        for _ in range(1000):
            state = step(state, ctrl.update(target, state, DT), params, DT)
        n += 1000
    dynamics = n / (time.perf_counter() - t0)
    ap = Autopilot()
    n, t0 = 0, time.perf_counter()
    while time.perf_counter() - t0 < seconds:
        for _ in range(1000):
            ap.step(DT)
            ap.poll()
        n += 1000
    return {
        "dynamics_steps_per_s": dynamics,
        "autopilot_steps_per_s": n / (time.perf_counter() - t0),
    }


def cpu_percent(pid: int, seconds: float) -> float:
    c0, t0 = cpu_seconds(pid), time.monotonic()
    time.sleep(seconds)
    return 100.0 * (cpu_seconds(pid) - c0) / (time.monotonic() - t0)


class Pilot:
    """A minimal offboard MAVLink client: heartbeat, 20 Hz body-velocity setpoints, commands."""

    def __init__(self) -> None:
        from pymavlink.dialects.v20 import common as mavlink

        self.mavlink = mavlink
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sock.bind(("127.0.0.1", 0))
        self.sock.settimeout(0.2)
        self.port = self.sock.getsockname()[1]
        self.mav = mavlink.MAVLink(None, srcSystem=245, srcComponent=191)
        self.parser = mavlink.MAVLink(None)
        self.peer = None
        self.z = 0.0
        self.velocity = (0.0, 0.0, 0.0, 0.0)
        self.stop = threading.Event()
        threading.Thread(target=self._read, daemon=True).start()
        threading.Thread(target=self._stream, daemon=True).start()

    def _read(self) -> None:
        while not self.stop.is_set():
            try:
                data, self.peer = self.sock.recvfrom(65535)
            except OSError:
                continue
            for msg in self.parser.parse_buffer(data) or []:
                if msg.get_type() == "LOCAL_POSITION_NED":
                    self.z = -msg.z

    def send(self, msg) -> None:
        if self.peer:
            self.sock.sendto(msg.pack(self.mav), self.peer)
            self.mav.seq = (self.mav.seq + 1) % 256

    def _stream(self) -> None:
        m = self.mavlink
        n = 0
        while not self.stop.wait(0.05):
            vx, vy, vz, yaw_rate = self.velocity
            self.send(m.MAVLink_set_position_target_local_ned_message(
                0, 1, 1, 8, 1991, 0, 0, 0, vx, vy, vz, 0, 0, 0, 0, yaw_rate))  # fmt: skip
            n += 1
            if n % 20 == 0:
                self.send(m.MAVLink_heartbeat_message(18, 8, 0, 0, 4, 3))

    def command(self, command: int, *p: float) -> None:
        p7 = [*p, *[0.0] * (7 - len(p))]
        self.send(self.mavlink.MAVLink_command_long_message(1, 1, command, 0, *p7))


def process_cpu(seconds: float, cameras: bool) -> dict[str, float]:
    zenoh_router = LoopbackRouter()
    zenoh_router.start()
    router = zenoh_router.endpoint
    pilot = Pilot()
    udp = f"{pilot.port}:0"
    argv = [sys.executable, "-m", "dronewrapper_sim", "--scenario", "beacon_static",
            "--connect", router, "--udp-onboard", udp, "--udp-gcs", "off"]  # fmt: skip
    if not cameras:
        argv.append("--no-cameras")
    proc = subprocess.Popen(argv, cwd=REPO, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        deadline = time.monotonic() + 30
        while pilot.peer is None and time.monotonic() < deadline:
            time.sleep(0.1)
        if pilot.peer is None:
            raise RuntimeError("the sim sent no MAVLink within 30 s")
        time.sleep(2.0)
        idle = cpu_percent(proc.pid, seconds)
        pilot.velocity = (0.0, 0.0, -1.5, 0.0)
        time.sleep(1.2)
        pilot.command(176, 1, 6, 0)
        pilot.command(400, 1)
        deadline = time.monotonic() + 20
        while pilot.z < 4.0 and time.monotonic() < deadline:
            time.sleep(0.1)
        pilot.velocity = (3.0, 0.0, 0.0, 0.3)  # a circle
        time.sleep(1.0)
        flying = cpu_percent(proc.pid, seconds)
        altitude = pilot.z
    finally:
        pilot.stop.set()
        proc.send_signal(2)
        proc.wait(15)
        zenoh_router.stop()
    return {"idle_cpu_percent": idle, "flying_cpu_percent": flying, "altitude_m": altitude}


def main(argv: list[str] | None = None) -> int:
    parser = CommandParser(description=first_line(__doc__))
    parser.add_argument("--seconds", type=float, default=10.0, help="each CPU window, s")
    args = parser.parse_args(argv)
    rates = physics_rates()
    dyn, ap = rates["dynamics_steps_per_s"], rates["autopilot_steps_per_s"]
    print_table(
        "physics (one core, pure Python)",
        ["loop", "steps/s", "x real time at 250 Hz"],
        [
            ["dynamics + controller", round(dyn), dyn / 250],
            ["whole autopilot + telemetry", round(ap), ap / 250],
        ],
    )
    no_cams = process_cpu(args.seconds, cameras=False)
    cams = process_cpu(args.seconds, cameras=True)
    print_table(
        f"sim process CPU (% of one core, {args.seconds:g} s windows)",
        ["configuration", "idle on ground", "flying OFFBOARD"],
        [
            ["--no-cameras", no_cams["idle_cpu_percent"], no_cams["flying_cpu_percent"]],
            ["cameras on, nobody watching", cams["idle_cpu_percent"], cams["flying_cpu_percent"]],
            ["PX4 SITL SIH (reference)", "~12", "~15-16"],
        ],
    )
    write_results(
        "sim_physics",
        {"physics": rates, "process_no_cameras": no_cams, "process_cameras_unwatched": cams,
         "seconds": args.seconds},
    )  # fmt: skip
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
