"""A laptop-side client for the security tests (run inside a network namespace).

    security_client.py attack ENDPOINT IDENTITY KEYS_DIR    every command path, a parameter
                                                            write and telemetry forgery
    security_client.py fly ENDPOINT KEYS_DIR                alice flies; carol is refused
                                                            until she takes the lease
    security_client.py spoof ENDPOINT KEYS_DIR              carol holds the lease; alice
                                                            claims to be carol

Prints one JSON line with what happened (the test judges it with the drone's ground truth).
"""

from __future__ import annotations

import json
import os
import sys
import time

from dronewrapper import DroneWrapper, setpoints
from dronewrapper.errors import CommandRefused, DroneError
from dronewrapper.msgs import codec, registry
from dronewrapper.msgs.geometry import PoseStamped
from dronewrapper.msgs.lease import LeaseRequest
from dronewrapper.msgs.mavros import (
    CommandBool,
    CommandTOL,
    ParamGet,
    ParamGetResult,
    ParamSet,
    ParamValue,
    PositionTarget,
    SetMode,
    State,
)
from dronewrapper.msgs.std import Header
from dronewrapper.runtime import ServiceError, ServiceUnavailable, ZenohOptions
from dronewrapper.runtime.caller import commander_attachment
from dronewrapper.runtime.node import call_service, encoding_for, open_session

NS = "drone"
FORGED = "forged"
PARAM = "MPC_XY_VEL_MAX"
CALLS = [
    ("param_get", registry.PARAM_GET, ParamGet(param_id=PARAM)),  # observers may not even read
    ("param_set", registry.PARAM_SET, ParamSet(param_id=PARAM, value=ParamValue(real=0.5))),
    ("take_over_lease", registry.COMMAND_LEASE, LeaseRequest(action="take_over")),
    ("set_mode", registry.SET_MODE, SetMode(custom_mode="OFFBOARD")),
    ("arm", registry.ARMING, CommandBool(value=True)),
    ("takeoff", registry.TAKEOFF, CommandTOL.takeoff(2.0)),
    ("land", registry.LAND, CommandTOL.land()),
    ("disarm", registry.ARMING, CommandBool(value=False)),
]
SETPOINTS = 40  # 2 s at 20 Hz: climb at 1 m/s
FORGERIES = 20  # forged State and pose each
FORGED_VALUE = 12345.0  # what the fake bridge answers for a parameter
FAKE_SERVICE = "bridge_intruder"  # the liveliness token the intruder declares


PLANNED = len(CALLS) + 4  # every call, setpoints, forged telemetry, a fake bridge, a token


def attack(endpoint: str, identity: str, keys: str) -> dict:
    """``attempts``: the attempts made, each ``obeyed``, ``refused`` or ``no_reply``; an
    attacker who never got a session made none (``connected`` False, ``why`` says why)."""
    out = {"identity": identity or "none", "connected": False, "attempts": 0}
    out |= {"planned": PLANNED, "calls": len(CALLS)}
    out |= {"obeyed": 0, "refused": 0, "no_reply": 0, "sent": 0}
    options = ZenohOptions(mode="client", connect=[endpoint], identity=identity, keys_dir=keys)
    try:
        session = open_session(options, timeout=4.0)
    except (ConnectionError, FileNotFoundError) as exc:
        out["why"] = str(exc)[:200]  # nothing reaches the drone without a session
        return out
    out["connected"] = True
    out["attempts"] = PLANNED
    label = commander_attachment(f"intruder-{identity}")
    states = []  # genuine State samples received: observers may watch, the revoked may not

    def on_state(sample) -> None:  # a session also gets its own puts: skip the forged ones
        if codec.decode(State, sample.payload.to_bytes()).autopilot != FORGED:
            states.append(sample)

    watch = session.declare_subscriber(registry.STATE.key(NS), on_state)
    try:
        for name, service, request in CALLS:
            try:
                reply = call_service(
                    session, service, request, ns=NS, timeout=1.0, attachment=label
                )
            except ServiceUnavailable:
                out["no_reply"] += 1
                continue
            except ServiceError as exc:
                out[f"{name}_error"] = exc.message
                # Zenoh's own reply when a query outlives its timeout: no server answered
                zenoh_timeout = exc.code == "internal" and exc.message == "Timeout"
                out["no_reply" if zenoh_timeout else "refused"] += 1
                continue
            ok = getattr(
                reply, "success", getattr(reply, "mode_sent", getattr(reply, "granted", 0))
            )
            out["obeyed" if ok else "refused"] += 1
            out[f"{name}_reply"] = codec.to_builtins(reply)
        # a fake bridge: answers parameter reads with a forged value, claims to be alive
        fake_reply = codec.encode(ParamGetResult(success=True, value=ParamValue(real=FORGED_VALUE)))

        def forge_reply(query) -> None:
            query.reply(query.key_expr, fake_reply, encoding=encoding_for(ParamGetResult))

        fake_bridge = session.declare_queryable(registry.PARAM_GET.key(NS), forge_reply)
        token = session.liveliness().declare_token(registry.ALIVE.key(NS, service=FAKE_SERVICE))
        setpoint = session.declare_publisher(
            registry.SETPOINT_RAW_LOCAL.key(NS), encoding=encoding_for(PositionTarget)
        )
        climb = setpoints.velocity_target(0.0, 0.0, 1.0, 0.0, stamp=time.time())
        for _ in range(SETPOINTS):
            setpoint.put(codec.encode(climb), attachment=label)
            time.sleep(0.05)
        state = session.declare_publisher(registry.STATE.key(NS), encoding=encoding_for(State))
        pose = session.declare_publisher(
            registry.LOCAL_POSE.key(NS), encoding=encoding_for(PoseStamped)
        )
        forged_state = State(connected=True, armed=True, mode="FORGED", autopilot=FORGED)
        forged_pose = PoseStamped(header=Header(frame_id=FORGED))
        for _ in range(FORGERIES):
            state.put(codec.encode(forged_state))
            pose.put(codec.encode(forged_pose))
            time.sleep(0.02)
        out["sent"] = SETPOINTS + 2 * FORGERIES
        time.sleep(1.0)  # the monitor keeps asking the parameter and listing the alive
        token.undeclare()
        fake_bridge.undeclare()
        watch.undeclare()
        out["states_received"] = len(states)
    finally:
        session.close()
    out["sdk_error"] = sdk_error(endpoint, identity, keys)
    return out


def sdk_error(endpoint: str, identity: str, keys: str) -> str:
    """What the SDK tells this identity when it connects and arms: its exception and text."""
    os.environ["DRONEWRAPPER_KEYS"] = keys  # where DroneWrapper(identity=NAME) looks
    try:
        with DroneWrapper(
            connect=endpoint, identity=identity, cameras=(), timeout=5, service_timeout=2
        ) as drone:
            drone.arm()
    except DroneError as exc:
        return f"{type(exc).__name__}: {exc}"
    return "obeyed"


def fly(endpoint: str, keys: str) -> dict:
    out: dict = {}
    os.environ["DRONEWRAPPER_KEYS"] = keys  # where DroneWrapper(identity=NAME) looks
    alice = DroneWrapper(connect=endpoint, identity="alice", cameras=(), timeout=30)
    carol = DroneWrapper(connect=endpoint, identity="carol", cameras=(), timeout=30)
    try:
        out["param"] = alice.param_get(PARAM)
        alice.takeoff(h=1.5, timeout=40)
        out["alice_flew_to"] = float(alice.get_position()[2])
        time.sleep(0.6)
        out["commander_after_takeoff"] = alice.get_state().commander
        try:
            carol.arm()
            out["carol_arm"] = "obeyed"
        except CommandRefused as exc:
            out["carol_arm"] = f"refused: {exc}"
        x, y, _ = (float(v) for v in alice.get_position())
        carol.set_cmd_pos(x, y, 2.5, alice.get_yaw())
        time.sleep(2.5)  # carol streams; the bridge drops every setpoint of hers
        out["z_while_carol_refused"] = float(alice.get_position()[2])
        out["carol_took_over_from"] = carol.take_command()
        time.sleep(0.5)
        out["commander_after_take_over"] = alice.get_state().commander
        carol.wait_for_altitude(2.5, timeout=20, tolerance=0.2)
        out["carol_flew_to"] = float(carol.get_position()[2])
        try:
            alice.land()
            out["alice_land"] = "obeyed"
        except CommandRefused as exc:
            out["alice_land"] = f"refused: {exc}"
        alice.stop_commanding()
        carol.land(timeout=60)
        out["landed"] = not carol.is_flying()
    finally:
        carol.close()
        alice.close()
    return out


def spoof(endpoint: str, keys: str) -> dict:
    """Carol takes the lease; alice sends a parameter write in carol's name: through the SDK
    (``commander="carol"``), and on a raw session with her certificate whose attachment names
    carol, on the plain key, on carol's bound key and on her own."""
    os.environ["DRONEWRAPPER_KEYS"] = keys
    out: dict = {}
    carol = DroneWrapper(connect=endpoint, identity="carol", cameras=(), timeout=30)
    alice = DroneWrapper(
        connect=endpoint, identity="alice", commander="carol", cameras=(), timeout=30
    )
    try:
        out["carol_took_from"] = carol.take_command()
        out["param_before"] = carol.param_get(PARAM)
        out["alice_commander"] = alice.commander
        try:
            alice.param_set(PARAM, 0.5)
            out["sdk"] = "obeyed"
        except CommandRefused as exc:
            out["sdk"] = f"refused: {exc}"
        options = ZenohOptions(mode="client", connect=[endpoint], identity="alice", keys_dir=keys)
        session = open_session(options, timeout=10.0)
        claim = commander_attachment("carol")
        try:
            for bound in ("", "carol", "alice"):
                request = ParamSet(param_id=PARAM, value=ParamValue(real=0.5))
                try:
                    reply = call_service(
                        session, registry.PARAM_SET, request, ns=NS, timeout=1.0,
                        attachment=claim, bound_to=bound,
                    )  # fmt: skip
                    outcome = "obeyed" if reply.success else f"refused: {reply.message}"
                except ServiceUnavailable:
                    outcome = "no_reply"
                except ServiceError as exc:
                    outcome = "no_reply" if exc.message == "Timeout" else f"refused: {exc.message}"
                out[f"raw_{bound or 'plain'}"] = outcome
        finally:
            session.close()
        out["holder"] = carol.get_state().commander
        out["param_after"] = carol.param_get(PARAM)
    finally:
        alice.close()
        carol.close()
    return out


def main() -> int:
    mode, endpoint = sys.argv[1], sys.argv[2]
    if mode == "attack":
        result = attack(endpoint, sys.argv[3], sys.argv[4])
    elif mode == "spoof":
        result = spoof(endpoint, sys.argv[3])
    else:
        result = fly(endpoint, sys.argv[3])
    print(json.dumps(result), flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
