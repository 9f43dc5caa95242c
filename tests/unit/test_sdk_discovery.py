"""Connection diagnosis and namespace grouping (pure): every error names what is missing."""

from __future__ import annotations

from dronewrapper.discovery import connection_problem, services_by_namespace

KEYS = {"drone/alive/sim", "drone1/alive/bridge_mavlink", "drone1/alive/sim", "x/alive/perception"}


def problem(**kw) -> str:
    args = {
        "linked": True,
        "alive_keys": set(),
        "state_connected": None,
        "state_age": float("inf"),
        "fresh_s": 3.0,
        "waited": 10.0,
    }
    args.update(kw)
    return connection_problem("drone", "tcp/127.0.0.1:7447", **args)


def test_grouping_by_namespace():
    assert services_by_namespace(KEYS | {"not/a/token/key"}) == {
        "drone": ["sim"],
        "drone1": ["bridge_mavlink", "sim"],
        "x": ["perception"],
    }


def test_no_router():
    assert problem(linked=False).startswith("cannot reach the Zenoh router at tcp/127.0.0.1:7447")


def test_no_bridge_names_what_is_alive_and_the_drones_online():
    text = problem(alive_keys=KEYS)
    assert text.startswith("no bridge for drone 'drone' on the router at tcp/127.0.0.1:7447")
    assert "drone/mavros/state" in text
    assert "alive in 'drone': sim" in text
    assert "drones online: drone1" in text  # a typo in the namespace is easy to spot
    assert "dronewrapper up compose/sim_iris.yaml" in text
    assert "alive in 'drone': nothing" in problem()


def test_bridge_alive_but_silent():
    text = problem(alive_keys={"drone/alive/bridge_mavlink"})
    assert text.startswith("bridge bridge_mavlink is alive in namespace 'drone' but published no")


def test_bridge_without_autopilot_and_a_stale_bridge():
    assert "is up but its autopilot is not connected" in problem(
        state_connected=False, state_age=0.5
    )
    assert "stopped publishing drone/mavros/state 7.0 s ago" in problem(
        state_connected=True, state_age=7.0
    )
