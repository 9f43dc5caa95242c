"""The drone-side ground truth for the security tests (inside the drone's namespace, on
loopback): counts forged messages delivered and watches arming, altitude and a parameter.

    security_monitor.py ROUTER OUT.json     writes OUT.json.ready once watching, then runs until
                                            SIGINT/SIGTERM and writes OUT.json
"""

from __future__ import annotations

import json
import sys
import time

from dronewrapper.msgs import registry
from dronewrapper.msgs.mavros import ParamGet
from dronewrapper.runtime import Node, ServiceError, ServiceUnavailable, ZenohOptions

PARAM = "MPC_XY_VEL_MAX"
FORGED = "forged"


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


def main() -> int:
    router, out_path = sys.argv[1], sys.argv[2]
    seen = {"states": 0, "forged_states": 0, "poses": 0, "forged_poses": 0, "setpoints": 0}
    seen |= {"armed": False, "max_z": -1e9}
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

    def on_truth(msg) -> None:
        seen["max_z"] = max(seen["max_z"], msg.pose.position.z)

    with Node("security_monitor", options) as node:
        node.subscribe(registry.STATE, on_state)
        node.subscribe(registry.LOCAL_POSE, on_pose)
        node.subscribe(registry.SIM_GROUND_TRUTH, on_truth)
        node.subscribe(
            registry.SETPOINT_RAW_LOCAL,
            lambda _m: seen.__setitem__("setpoints", seen["setpoints"] + 1),
        )
        seen["param_before"] = read_param(node, 60.0)
        node.announce()
        with open(out_path + ".ready", "w") as f:
            f.write("ready\n")
        node.spin()
        seen["param_after"] = read_param(node, 20.0)
    with open(out_path, "w") as f:
        json.dump(seen, f)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
