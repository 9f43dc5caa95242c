"""The PX4 Zenoh bridge's pure core facing a scripted PX4 in given time, over real bytes.

No sockets, threads or clock: PX4's side is the recording of a real PX4 SIH
(tests/data/px4_zenoh/sih_ground.json: its tokens and one CDR sample per topic); a test changes
fields of the recorded values (arming, nav state, position, landed), the rig encodes them with
the project's CDR codec on the recorded keys and feeds the bytes to the core. Every value the
core writes to PX4 is encoded and decoded again, so a test reads what PX4 would receive.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import msgspec
import targets

from dronewrapper.msgs.mavros import (
    PositionTarget,
)
from dronewrapper_bridge_base.bridge_node import COMMANDS
from dronewrapper_bridge_base.operation import Operation
from dronewrapper_bridge_px4_zenoh import commands as cmds
from dronewrapper_bridge_px4_zenoh import topics as t
from dronewrapper_bridge_px4_zenoh.config import Config
from dronewrapper_bridge_px4_zenoh.core import Px4ZenohCore
from dronewrapper_bridge_px4_zenoh.versions import Versions
from dronewrapper_ros2_codec import cdr
from dronewrapper_ros2_codec.names import parse_endpoint

RECORDING = json.loads(
    (Path(__file__).resolve().parents[1] / "data" / "px4_zenoh" / "sih_ground.json").read_text()
)
T0 = 1000.0  # monotonic s at the rig's start
EPOCH = 1.7e9  # wall-clock s added to the monotonic time for stamps
USER = "user"
NAV_LOITER, NAV_OFFBOARD, NAV_LAND, NAV_RTL, NAV_POSCTL = 4, 14, 18, 5, 2
ARMED, DISARMED = 2, 1


ACK = {  # PX4 acks nothing on the ground unasked: no recorded sample, its fields here
    "timestamp": 0,
    "command": 0,
    "result": 0,
    "result_param1": 0,
    "result_param2": 0,
    "target_system": 255,
    "target_component": 190,
    "from_external": False,
}


def recorded_key(topic: t.Px4Topic) -> str:
    """The recorded data key of one of PX4's topics (the bridge's own for the ack's)."""
    if topic is t.COMMAND_ACK:
        return Versions().key(topic)
    (key,) = [k for k in RECORDING["samples"] if t.parse_key(k).topic == topic.name]
    return key


def recorded(topic: t.Px4Topic) -> dict[str, Any]:
    """The recorded value of one of PX4's topics, decoded."""
    if topic is t.COMMAND_ACK:
        return dict(ACK)
    payload = bytes.fromhex(RECORDING["samples"][recorded_key(topic)]["payload"])
    return cdr.decode(topic.type_name, payload)


def velocity(vx: float = 1.0) -> PositionTarget:
    """A body-velocity setpoint (forward ``vx`` m/s)."""
    return targets.velocity(vx)


class Px4Rig:
    """A :class:`Px4ZenohCore` (``config`` overrides) and the recorded PX4 it talks to."""

    def __init__(self, **config: Any) -> None:
        self.now = T0
        self.core = Px4ZenohCore(msgspec.convert(config, Config), self.now)
        self.values = {
            topic.name: recorded(topic) for topic in t.TOPICS if topic.direction == t.OUT
        }
        self.written: list[tuple[str, dict[str, Any]]] = []
        self.samples: list[tuple[Any, Any]] = []
        self.errors: list[str] = []

    # ---- time and effects

    @property
    def stamp(self) -> float:
        return EPOCH + self.now

    def drain(self) -> None:
        out = self.core.take()
        for topic, value in out.writes:  # through the wire format, as PX4 reads it
            payload = cdr.encode(topic.type_name, value)
            self.written.append((topic.name, cdr.decode(topic.type_name, payload)))
        self.samples.extend(out.samples)
        self.errors.extend(out.errors)

    def writes(self, topic: t.Px4Topic) -> list[dict[str, Any]]:
        return [value for name, value in self.written if name == topic.name]

    def commands(self) -> list[dict[str, Any]]:
        return self.writes(t.COMMAND)

    def published(self, registry_topic: Any) -> list[Any]:
        return [msg for topic, msg in self.samples if topic is registry_topic]

    def clear(self) -> None:
        self.written.clear()
        self.samples.clear()

    def tick(self) -> None:
        self.core.tick(self.now, self.stamp)
        self.drain()

    def run(self, seconds: float, step: float = 1 / 30, *, status_every: float = 0.5) -> None:
        """Advance ``seconds`` in ticks, PX4's status and position arriving meanwhile."""
        end, next_status = self.now + seconds, self.now
        while self.now < end - 1e-9:
            self.now += step
            if self.now >= next_status:
                next_status = self.now + status_every
                self.send(t.VEHICLE_STATUS)
            self.send(t.LOCAL_POSITION)
            self.tick()

    # ---- PX4's side

    def tokens(self, doctor: str = "") -> None:
        """PX4's recorded liveliness tokens (``doctor``: the topic name whose hash is changed)."""
        for token in RECORDING["tokens"]:
            endpoint = parse_endpoint(token)
            if doctor and endpoint.topic == doctor:
                token = token.replace(endpoint.type_hash, "RIHS01_" + "ab" * 32)
                endpoint = parse_endpoint(token)
            self.core.on_token(endpoint, self.now, self.stamp)
        self.drain()

    def send(self, topic: t.Px4Topic, *, key: str = "", **changes: Any) -> None:
        """PX4 publishes ``topic``: its last value with ``changes``, encoded."""
        value = self.values[topic.name]
        value.update(changes)
        payload = cdr.encode(topic.type_name, value)
        self.core.on_data(key or recorded_key(topic), payload, self.now, self.stamp)
        self.drain()

    def boot(self, doctor: str = "") -> None:
        """Tokens (``doctor``: as for :meth:`tokens`), then one recorded sample of every topic
        (attitude before position)."""
        self.tokens(doctor)
        for topic in (
            t.ATTITUDE,
            t.LOCAL_POSITION,
            t.GLOBAL_POSITION,
            t.BATTERY,
            t.LAND_DETECTED,
            t.VEHICLE_STATUS,
        ):
            self.send(topic)
        self.tick()

    def vehicle(
        self, *, armed: bool | None = None, nav_state: int | None = None, landed: bool | None = None
    ) -> None:
        """PX4's arming, navigation state and landed state change."""
        if landed is not None:
            self.send(t.LAND_DETECTED, landed=landed)
        changes: dict[str, Any] = {}
        if armed is not None:
            changes["arming_state"] = ARMED if armed else DISARMED
        if nav_state is not None:
            changes["nav_state"] = nav_state
        self.send(t.VEHICLE_STATUS, **changes)

    def at(self, x: float, y: float, z_up: float) -> None:
        """PX4's local position (ENU m)."""
        self.send(t.LOCAL_POSITION, x=y, y=x, z=-z_up)

    def ack(self, command: int, result: int = cmds.ACCEPTED) -> None:
        self.send(t.COMMAND_ACK, command=command, result=result)

    def flying_offboard(self, height: float = 3.0) -> None:
        """Booted, armed and airborne at ``height`` in OFFBOARD."""
        self.boot()
        self.at(0.0, 0.0, height)
        self.vehicle(armed=True, nav_state=NAV_OFFBOARD, landed=False)
        self.tick()

    # ---- commanders

    def setpoint(self, target: PositionTarget, commander: str = USER, sent: float | None = None):
        self.core.on_setpoint(target, commander, self.now, self.stamp, sent=sent)
        self.drain()

    def request(self, steps: Any, what: str = "", commander: str = USER) -> Operation:
        op = self.core.request(steps, commander, what, self.now, self.stamp)
        self.drain()
        return op

    def command(self, service: Any, steps: Any, commander: str = USER) -> Operation:
        return self.request(steps, COMMANDS.get(service, ""), commander)
