"""The ground side of the three routers test: an SDK app with the fleet, on the ground.

Run inside the ground namespace: ``python fleet_ground_probe.py ENDPOINT COUNT OBSERVER_ENDPOINT
OBSERVER_KEYS``. It prints one JSON line per event and waits for a line on stdin where the test
acts on the link:

1. ``fleet``: the drones found through the ground router, with their kinds; the test measures
   the link meanwhile and answers once it is done (no bulk traffic on it from then on);
2. ``ages``: each drone's pose age at arrival here (our clock minus ``header.stamp``; every
   namespace shares this machine's clock) over a few seconds, p50/p95 per drone;
3. ``took_off``: drone2 alone took off (each drone's altitude: the command reached only it);
   ``observer``: meanwhile, an observer's session straight to the link router
   (``OBSERVER_ENDPOINT``, its certificate in ``OBSERVER_KEYS``) sees drone3's State but its
   arming call reaches no server, and drone3 stays disarmed (the link router's access control);
4. ``cut``: drone2 holds a setpoint; the test cuts the link and answers; meanwhile the app asks
   drone2 to go 3 m east, then withdraws the command (the operator changed her mind) and says
   ``restore``; the test restores the link and answers;
5. ``after``: drone2's position for a few seconds after the link is back: a command withdrawn
   during the cut must not fly; then every drone lands (``landed``).
"""

from __future__ import annotations

import json
import sys
import threading
import time
from collections import defaultdict
from concurrent.futures import ThreadPoolExecutor

from dronewrapper.fleet import Fleet
from dronewrapper.msgs import registry
from dronewrapper.msgs.mavros import CommandBool
from dronewrapper.runtime import ServiceError, ServiceUnavailable, ZenohOptions
from dronewrapper.runtime.session import call_service, open_session

SAMPLE_S = 6.0


def say(**event: object) -> None:
    print(json.dumps(event), flush=True)


def percentile(values: list[float], q: float) -> float:
    ordered = sorted(values)
    return ordered[int(q * (len(ordered) - 1))] if ordered else float("inf")


def observe(endpoint: str, keys: str, ns: str) -> dict[str, object]:
    """An observer on ``endpoint`` watches ``ns``'s State and tries to arm it."""
    options = ZenohOptions(mode="client", connect=[endpoint], identity="olga", keys_dir=keys)
    session = open_session(options, timeout=10.0)
    states: list[bytes] = []
    watch = session.declare_subscriber(registry.STATE.key(ns), lambda s: states.append(b""))
    try:
        try:
            reply = call_service(
                session, registry.ARMING, CommandBool(value=True), ns=ns, timeout=1
            )
            arm = "obeyed" if reply.success else "refused"
        except ServiceUnavailable:
            arm = "no_reply"
        except ServiceError as exc:
            arm = f"{exc.code}: {exc.message}"
        end = time.monotonic() + 3.0
        while not states and time.monotonic() < end:
            time.sleep(0.05)
        watch.undeclare()
    finally:
        session.close()
    return {"arm": arm, "states": len(states)}


def main(endpoint: str, count: int, observer_endpoint: str, observer_keys: str) -> int:
    with Fleet.connect(connect=endpoint, count=count, timeout=120, cameras=()) as fleet:
        say(event="fleet", drones={i.name: i.kind for i in fleet.online()})
        sys.stdin.readline()  # the link is measured and quiet
        ages: dict[str, list[float]] = defaultdict(list)
        lock = threading.Lock()
        recording = threading.Event()

        def on_pose(ns: str):
            def record(msg) -> None:
                if recording.is_set():
                    with lock:
                        ages[ns].append(time.time() - msg.header.stamp)

            return record

        for drone in fleet:
            drone.subscribe(registry.LOCAL_POSE, on_pose(drone.ns))
        recording.set()
        time.sleep(SAMPLE_S)
        recording.clear()
        with lock:
            summary = {
                ns: {"n": len(v), "p50": percentile(v, 0.5), "p95": percentile(v, 0.95)}
                for ns, v in ages.items()
            }
        say(event="ages", ages=summary)

        with ThreadPoolExecutor(1) as pool:  # the observer tries while drone2 takes off
            seen = pool.submit(observe, observer_endpoint, observer_keys, "drone3")
            fleet.each(lambda d: d.takeoff(h=1.0, timeout=90), ["drone2"]).raise_errors()
            altitudes = fleet.each(lambda d: float(d.get_position()[2])).results()
            say(event="took_off", altitudes=altitudes)
            say(event="observer", **seen.result(30), drone3_armed=fleet["drone3"].get_state().armed)

        drone2 = fleet["drone2"]
        x0, y0, z0 = (float(v) for v in drone2.get_position())
        drone2.set_cmd_pos(x0, y0, z0)
        time.sleep(1.0)
        say(event="cut", x0=x0)
        sys.stdin.readline()  # the link is down
        drone2.set_cmd_pos(x0 + 3.0, y0, z0)  # a command that cannot arrive now ...
        time.sleep(2.0)
        drone2.stop_commanding()  # ... withdrawn before the link is back
        say(event="restore")
        sys.stdin.readline()  # the link is back
        xs = []
        end = time.monotonic() + 6.0
        while time.monotonic() < end:
            xs.append(float(drone2.get_position()[0]))
            time.sleep(0.1)
        say(event="after", x0=x0, max_dx=max(abs(x - x0) for x in xs), age=drone2.age("position"))
        result = fleet.land(timeout=90)
        say(event="landed", ok=result.ok, failed={n: str(e) for n, e in result.failed.items()})
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1], int(sys.argv[2]), sys.argv[3], sys.argv[4]))
