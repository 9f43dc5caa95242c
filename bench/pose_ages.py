"""Every drone's pose age at one subscriber that does nothing else: a process of its own.

The age of a pose is this process's wall clock when the sample arrives minus the pose's
``header.stamp`` (the bridge's wall clock when the MAVLink message arrived), so it counts the
bridge's handling, Zenoh, the router and this subscriber's own wake-up. A measuring process
that also ran other work (a stand-in autopilot, a stream of setpoints, service calls) would
add its own waits for the interpreter to the ages; this one only decodes poses and notes
their ages.

It reads commands, one a line, on stdin: ``start`` (forget what was noted, note from now on),
``stop`` (stop noting; print one JSON line: ``per_drone`` {namespace: percentiles in ms},
``all`` (every pose), ``rate_hz`` {namespace: poses a second while noting}), and ends at the
end of stdin. It prints ``ready`` once it subscribes.

    python -m bench.pose_ages ENDPOINT        (driven by bench.fleet)
"""

from __future__ import annotations

import json
import sys
import time
from collections import defaultdict

from bench.common import percentiles


class PoseAges:
    """Ages of every drone's poses at this subscriber (s), by namespace."""

    def __init__(self) -> None:
        self.ages: dict[str, list[float]] = defaultdict(list)
        self.recording = False
        self.since = time.monotonic()

    def start(self) -> None:
        self.ages = defaultdict(list)
        self.since = time.monotonic()
        self.recording = True

    def on_sample(self, sample) -> None:
        if not self.recording:
            return
        now = time.time()
        try:
            pose = self.decode(sample.payload.to_bytes())
        except Exception:
            return
        self.ages[str(sample.key_expr).split("/", 1)[0]].append(now - pose.header.stamp)

    @staticmethod
    def decode(payload: bytes):
        from dronewrapper.msgs import codec
        from dronewrapper.msgs.geometry import PoseStamped

        return codec.decode(PoseStamped, payload)

    def report(self) -> dict[str, object]:
        self.recording = False
        elapsed = max(time.monotonic() - self.since, 1e-9)
        ages = dict(self.ages)
        return {
            "per_drone": {ns: percentiles(v) for ns, v in ages.items()},
            "all": percentiles([a for v in ages.values() for a in v]),
            "rate_hz": {ns: len(v) / elapsed for ns, v in ages.items()},
        }


def main(argv: list[str] | None = None) -> int:
    import zenoh

    from dronewrapper.msgs import registry
    from dronewrapper.runtime.node import open_session
    from dronewrapper.runtime.options import ZenohOptions

    (endpoint,) = sys.argv[1:] if argv is None else argv
    ages = PoseAges()
    session = open_session(ZenohOptions(mode="client", connect=[endpoint]))
    session.declare_subscriber(
        registry.LOCAL_POSE.wildcard("*"), zenoh.handlers.Callback(ages.on_sample)
    )
    print("ready", flush=True)
    for line in sys.stdin:
        command = line.strip()
        if command == "start":
            ages.start()
        elif command == "stop":
            print(json.dumps(ages.report()), flush=True)
    session.close()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
