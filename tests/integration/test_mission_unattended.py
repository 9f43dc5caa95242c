"""A mission flown by an app that is stopped with Ctrl-C: real processes (compose/sim_iris.yaml:
router, simulator, bridge) and the app as its own Python process.

The app takes off, uploads a local-frame mission and starts it, then waits; SIGINT ends it
(its Zenoh session, and with it its liveliness token, go). The bridge lets the mission finish,
then returns home and lands (``unattended_action``, docs/design.md "Long actions"). An
observer judges from the positions the bridge publishes (the simulator's local position, the
local origin at home): every item passed within 1 m, then on the ground and disarmed near home
within :data:`BOUND_S` of the Ctrl-C.
"""

from __future__ import annotations

import math
import signal
import sys
import time

import pytest
from sdk_sim_graph import sim_graph

from dronewrapper import DroneWrapper

POINTS = [(6.0, 0.0, 3.0), (6.0, 6.0, 3.0), (0.0, 6.0, 3.0)]
BOUND_S = 120.0
"""From the Ctrl-C to on the ground at home: the rest of the mission (under 30 s), the
commander's absence (5 s, looked at each second), the return (under 30 s), with room for a
loaded machine."""

# The app as a user runs it in a terminal, where Ctrl-C raises KeyboardInterrupt: it says so
# itself, since a test runner started in the background (`cmd &` in a script) passes SIGINT
# on ignored, and Python then never raises it.
APP = f"""
import signal, time
signal.signal(signal.SIGINT, signal.default_int_handler)  # Ctrl-C raises, as in a terminal
from dronewrapper import DroneWrapper
drone = DroneWrapper("drone", {{router!r}}, timeout=60)
drone.takeoff(3.0)
drone.upload_mission({POINTS!r}, frame="local")
drone.start_mission()
print("mission started", flush=True)
while True:
    time.sleep(1)
"""


@pytest.fixture
def router(tmp_path):
    with sim_graph(tmp_path) as (endpoint, _):
        yield endpoint


def test_ctrl_c_during_a_mission_ends_on_the_ground_at_home(router, spawn):
    with DroneWrapper("drone", router, timeout=30) as observer:
        app = spawn([sys.executable, "-c", APP.format(router=router)], name="app")
        track: list[tuple[float, float, float]] = []
        stopped = math.inf
        deadline = time.monotonic() + 120.0  # the app's take-off and start, then BOUND_S
        while time.monotonic() < deadline:
            home = observer.home() if observer._home.value is not None else None
            if home is not None:
                x, y, z = observer.get_position()
                track.append((x - home.x, y - home.y, z - home.z))
            if stopped == math.inf and "mission started" in app.output():
                app.proc.send_signal(signal.SIGINT)  # Ctrl-C
                stopped = time.monotonic()
                deadline = stopped + BOUND_S
            assert stopped < math.inf or app.alive(), app.output()[-3000:]
            down = not observer.get_state().armed and observer.get_landed_state() == 1
            if down and time.monotonic() - stopped > 5.0:
                break
            time.sleep(0.1)
        took = time.monotonic() - stopped
        exited = not app.alive()
        app.stop(10)
        assert exited, f"the app did not end on Ctrl-C:\n{app.output()[-3000:]}"
        assert not observer.get_state().armed, f"still armed {took:.0f} s after Ctrl-C"
    for point in POINTS:
        approach = min(math.dist(p, point) for p in track)
        print(f"\nitem {point}: passed within {approach:.2f} m")
        assert approach <= 1.0
    x, y, z = track[-1]
    print(f"on the ground {math.hypot(x, y):.2f} m from home, {took:.1f} s after Ctrl-C")
    assert math.hypot(x, y) < 1.5 and z < 0.5
