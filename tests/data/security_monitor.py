"""The drone-side ground truth for the security tests (inside the drone's namespace, on
loopback): counts forged messages delivered and watches arming, altitude and a parameter.

    security_monitor.py ROUTER OUT.json     writes OUT.json.ready once watching, then runs until
                                            SIGINT/SIGTERM and writes OUT.json
"""

from __future__ import annotations

import json
import sys
import time

import zenoh

from dronewrapper.msgs import codec, registry
from dronewrapper.msgs.mavros import ParamGet, ParamGetResult
from dronewrapper.runtime import Node, ServiceError, ServiceUnavailable, ZenohOptions

PARAM = "MPC_XY_VEL_MAX"
FORGED = "forged"
FORGED_VALUE = 12345.0  # a fake bridge's answer (security_client.py)
FAKE_SERVICE = "bridge_intruder"


def read_param(node: Node, timeout: float) -> float:
    """The parameter's value, asking again while the bridge has no autopilot yet."""
    deadline = time.monotonic() + timeout
    while True:
        try:
            return node.call(registry.PARAM_GET, ParamGet(param_id=PARAM), timeout=5).value.real
        except (ServiceError, ServiceUnavailable):
            if time.monotonic() >= deadline:
                raise
            time.sleep(0.5)


def ask_everyone(node: Node, seen: dict) -> None:
    """Read the parameter from every queryable that answers (a fake bridge's reply counts)."""
    seen["param_asks"] += 1
    replies = node.session.get(
        registry.PARAM_GET.key(node.ns),
        payload=codec.encode(ParamGet(param_id=PARAM)),
        target=zenoh.QueryTarget.ALL,
        consolidation=zenoh.ConsolidationMode.NONE,  # every server's reply, not the latest
        timeout=1.0,
    )
    for reply in replies:
        if reply.ok is None:
            continue
        seen["param_replies"] += 1
        value = codec.decode(ParamGetResult, reply.ok.payload.to_bytes()).value.real
        seen["forged_replies"] += value == FORGED_VALUE


def main() -> int:
    router, out_path = sys.argv[1], sys.argv[2]
    seen = {"states": 0, "forged_states": 0, "poses": 0, "forged_poses": 0, "setpoints": 0}
    seen |= {"armed": False, "max_z": -1e9, "param_asks": 0, "param_replies": 0, "truths": 0}
    seen |= {"forged_replies": 0, "forged_tokens": 0}
    options = ZenohOptions(mode="client", connect=[router], name="security_monitor")

    def on_state(msg) -> None:
        seen["states"] += 1
        if msg.autopilot == FORGED or msg.mode == "FORGED":
            seen["forged_states"] += 1
        else:
            seen["armed"] = seen["armed"] or msg.armed

    def on_pose(msg) -> None:
        seen["poses"] += 1
        seen["forged_poses"] += msg.header.frame_id == FORGED

    def on_text(msg) -> None:  # the autopilot says "Armed by external command" even if the
        # armed State, published on the next heartbeat, comes after a quick disarm
        seen["armed"] = seen["armed"] or msg.text.startswith("Armed")

    def on_token(sample) -> None:
        seen["forged_tokens"] += FAKE_SERVICE in str(sample.key_expr)

    def on_truth(msg) -> None:
        seen["truths"] += 1
        seen["max_z"] = max(seen["max_z"], msg.pose.position.z)

    with Node("security_monitor", options) as node:
        node.subscribe(registry.STATE, on_state)
        node.subscribe(registry.LOCAL_POSE, on_pose)
        node.subscribe(registry.STATUSTEXT, on_text)
        node.subscribe(registry.SIM_GROUND_TRUTH, on_truth)
        node.subscribe(
            registry.SETPOINT_RAW_LOCAL,
            lambda _m: seen.__setitem__("setpoints", seen["setpoints"] + 1),
        )
        seen["param_before"] = read_param(node, 60.0)
        node.session.liveliness().declare_subscriber(registry.ALIVE.wildcard(), on_token)
        node.announce()
        with open(out_path + ".ready", "w") as f:
            f.write("ready\n")
        while not node.stop_event.wait(0.3):
            ask_everyone(node, seen)
        seen["param_after"] = read_param(node, 20.0)
    with open(out_path, "w") as f:
        json.dump(seen, f)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
