"""Records a follow flight from the simulator's ground truth and the controller's status.

Subscribes ``{ns}/sim/ground_truth`` (vehicle pose), ``sim/objects/*/pose`` (every world
object) and ``{ns}/controller/status``, and samples them at ``rate_hz`` on its own thread into
:class:`~dronewrapper_sim.evaluation.metrics.FollowSample` records. Used by ``make demo`` and the
scenario tests; not part of the controller process.
"""

from __future__ import annotations

import threading

import zenoh

from dronewrapper.msgs import codec, registry
from dronewrapper.msgs.control import ControllerStatus
from dronewrapper.msgs.geometry import PoseStamped
from dronewrapper.runtime import Latest
from dronewrapper.runtime.clock import REAL, Clock
from dronewrapper.telemetry import euler_from_quaternion
from dronewrapper_sim.evaluation.metrics import FollowSample


def _xyz(msg: PoseStamped, lift: float = 0.0) -> tuple[float, float, float]:
    p = msg.pose.position
    return (p.x, p.y, p.z + lift)


class FollowMonitor:
    """Samples vehicle, objects and controller status at ``rate_hz`` into ``samples``.

    Args:
        session: an open Zenoh session connected to the graph's router.
        ns: the vehicle namespace.
        aim_height: metres added to every object's pose to get its aim point: 0 for the beacon
            (its pose is its centre), about half a person's height for people (their pose is
            the base point on the ground).
        rate_hz: sampling rate (Hz).
        clock: what its samples' times and its pacing read (default: the real clocks).
    """

    def __init__(
        self,
        session: zenoh.Session,
        ns: str = "drone",
        *,
        aim_height: float = 0.0,
        rate_hz: float = 10.0,
        clock: Clock = REAL,
    ) -> None:
        self.ns = ns
        self.clock = clock
        self.aim_height = aim_height
        self.period = 1.0 / rate_hz
        self.samples: list[FollowSample] = []
        self.status: Latest[ControllerStatus] = Latest("controller status", clock)
        self.vehicle: Latest[PoseStamped] = Latest("ground truth", clock)
        self.objects: dict[str, PoseStamped] = {}
        self._pose_dec = codec.decoder(PoseStamped)
        self._status_dec = codec.decoder(ControllerStatus)
        self._subs = [
            session.declare_subscriber(
                registry.SIM_GROUND_TRUTH.key(ns),
                lambda s: self.vehicle.update(self._pose_dec.decode(s.payload.to_bytes())),
            ),
            session.declare_subscriber(registry.SIM_OBJECT_POSE.wildcard(), self._on_object),
            session.declare_subscriber(
                registry.CONTROLLER_STATUS.key(ns),
                lambda s: self.status.update(self._status_dec.decode(s.payload.to_bytes())),
            ),
        ]
        self._stop = threading.Event()
        self._t0 = self.clock.monotonic()
        self._thread = clock.thread(self._run, "follow-monitor")

    def _on_object(self, sample: zenoh.Sample) -> None:
        match = registry.SIM_OBJECT_POSE.match(str(sample.key_expr))
        if match is not None:
            self.objects[match["name"]] = self._pose_dec.decode(sample.payload.to_bytes())

    def start(self) -> FollowMonitor:
        self._t0 = self.clock.monotonic()
        self._thread.start()
        return self

    def sample(self) -> FollowSample | None:
        """The current instant, or None while ground truth or the target is missing."""
        vehicle = self.vehicle.fresh(1.0)
        target = self.objects.get("target")
        if vehicle is None or target is None:
            return None
        status = self.status.fresh(1.0)
        lift = self.aim_height
        return FollowSample(
            t=self.clock.monotonic() - self._t0,
            vehicle=_xyz(vehicle),
            yaw=euler_from_quaternion(vehicle.pose.orientation)[2],
            target=_xyz(target, lift),
            others={n: _xyz(p, lift) for n, p in self.objects.items() if n != "target"},
            state=status.state if status else "",
            target_visible=bool(status and status.target_visible),
        )

    def _run(self) -> None:
        clock = self.clock
        next_at = clock.monotonic()
        while not clock.wait(self._stop, next_at - clock.monotonic()):
            next_at += self.period
            sample = self.sample()
            if sample is not None:
                self.samples.append(sample)

    def close(self) -> None:
        self._stop.set()
        if self._thread.is_alive():
            self._thread.join(2.0)
        for sub in self._subs:
            sub.undeclare()
