"""The Tello SDK 2.0 command protocol as a pure state machine.

:class:`TelloProtocol` takes each datagram received on port 8889 with its sender and the
time (:meth:`~TelloProtocol.handle`), and returns the replies to send, each to its sender;
:meth:`~TelloProtocol.tick` advances the flight and returns the late replies of blocking
commands (``ok`` once a move has finished) and the auto-landing. No sockets, no clock: the
server owns both. Replies are the real drone's texts: ``ok``, ``error``, ``error Motor stop``
(a flight command while the motors are off, take-off on a low battery), ``error Not joystick``
(a flight command while a blocking one is still running), ``out of range``,
``unknown command: <text>``, or the value of a read command.

The SDK's command table: a small handler per command, with the real drone's replies.

Size: the SDK's command table, one small handler per command beside the state it reads and
changes; the flight itself is tello/flight.py.
"""

from __future__ import annotations

import enum
import math
from collections.abc import Callable
from dataclasses import dataclass

from dronewrapper_sim.tello.flight import Phase, TelloFlight, body_to_enu
from dronewrapper_sim.tello.state_string import acceleration_mg, attitude_deg

Address = tuple[str, int]

MAX_DATAGRAM = 1024
"""Datagrams longer than this (bytes) are answered ``error`` without being parsed."""

SERIAL_NUMBER = "0TQDG0SIM00001"
SDK_VERSION = "20"
WIFI_SNR = 90

DEFAULT_STATE_PORT = 8890
DEFAULT_VIDEO_PORT = 11111

OK = "ok"
ERROR = "error"
MOTOR_STOP = "error Motor stop"
NOT_JOYSTICK = "error Not joystick"
OUT_OF_RANGE = "out of range"


class Kind(enum.Enum):
    """How a command is answered."""

    CONTROL = "control"  # acts, replies ok/error (possibly when finished)
    READ = "read"  # replies a value
    SILENT = "silent"  # rc: no reply


@dataclass(frozen=True)
class Reply:
    """A text to send to ``address``."""

    text: str
    address: Address


@dataclass
class Session:
    """What the SDK mode knows about its client.

    Attributes:
        client: the address that sent ``command`` last (state and video go to its host).
        state_port, video_port: where the state string and the video go (``port`` moves them).
        streaming: video on (``streamon``).
        speed: speed of the moves, m/s (``speed``).
        last_command_s: time of the last valid command or the end of the last manoeuvre
            (auto-landing), s.
    """

    client: Address | None = None
    state_port: int = DEFAULT_STATE_PORT
    video_port: int = DEFAULT_VIDEO_PORT
    streaming: bool = False
    speed: float = 1.0
    last_command_s: float = 0.0


class BadArgs(Exception):
    """The arguments do not parse (``error``)."""


class OutOfRange(Exception):
    """An argument outside the SDK's range (``out of range``)."""


def _ints(args: list[str], count: int) -> list[int]:
    if len(args) != count:
        raise BadArgs
    try:
        values = [int(a) for a in args]
    except ValueError:
        raise BadArgs from None
    return values


def _check(value: int, low: int, high: int) -> int:
    if not low <= value <= high:
        raise OutOfRange
    return value


class TelloProtocol:
    """The Tello's SDK command handling over a :class:`TelloFlight` (see module doc).

    Args:
        flight: the flight model it commands (and :meth:`tick` steps).
        baro_origin_m: barometric altitude of the ground (the ``baro?`` reply), m.
    """

    def __init__(self, flight: TelloFlight, baro_origin_m: float = 100.0) -> None:
        self.flight = flight
        self.baro_origin_m = baro_origin_m
        self.session = Session(speed=flight.env.default_speed)
        self.sdk_mode = False
        self._pending: Address | None = None  # sender of the blocking command under way
        self._sender: Address = ("", 0)  # sender of the datagram being handled
        self._handlers: dict[str, tuple[Kind, Callable[[list[str], float], str]]] = {
            "command": (Kind.CONTROL, self._command),
            "takeoff": (Kind.CONTROL, self._takeoff),
            "land": (Kind.CONTROL, self._land),
            "emergency": (Kind.CONTROL, self._emergency),
            "stop": (Kind.CONTROL, self._stop),
            "streamon": (Kind.CONTROL, self._streamon),
            "streamoff": (Kind.CONTROL, self._streamoff),
            "up": (Kind.CONTROL, self._move_cmd(0.0, 0.0, 1.0)),
            "down": (Kind.CONTROL, self._move_cmd(0.0, 0.0, -1.0)),
            "left": (Kind.CONTROL, self._move_cmd(0.0, 1.0, 0.0)),
            "right": (Kind.CONTROL, self._move_cmd(0.0, -1.0, 0.0)),
            "forward": (Kind.CONTROL, self._move_cmd(1.0, 0.0, 0.0)),
            "back": (Kind.CONTROL, self._move_cmd(-1.0, 0.0, 0.0)),
            "cw": (Kind.CONTROL, self._rotate_cmd(-1.0)),
            "ccw": (Kind.CONTROL, self._rotate_cmd(1.0)),
            "flip": (Kind.CONTROL, self._flip),
            "go": (Kind.CONTROL, self._go),
            "curve": (Kind.CONTROL, self._curve),
            "speed": (Kind.CONTROL, self._speed),
            "rc": (Kind.SILENT, self._rc),
            "wifi": (Kind.CONTROL, self._wifi),
            "port": (Kind.CONTROL, self._port),
            "keepalive": (Kind.CONTROL, lambda args, now: OK),
            "battery?": (Kind.READ, lambda args, now: str(self.flight.battery_percent)),
            "speed?": (Kind.READ, lambda args, now: f"{self.session.speed * 100.0:.1f}"),
            "time?": (Kind.READ, lambda args, now: f"{int(self.flight.motor_time_s)}s"),
            "height?": (Kind.READ, lambda args, now: f"{self._height_dm()}dm"),
            "temp?": (Kind.READ, lambda args, now: "{}~{}C".format(*self.temperatures())),
            "attitude?": (Kind.READ, self._attitude),
            "baro?": (Kind.READ, lambda args, now: f"{self.baro_m():.6f}"),
            "tof?": (Kind.READ, lambda args, now: f"{self.tof_cm() * 10}mm"),
            "acceleration?": (Kind.READ, self._acceleration),
            "wifi?": (Kind.READ, lambda args, now: str(WIFI_SNR)),
            "sdk?": (Kind.READ, lambda args, now: SDK_VERSION),
            "sn?": (Kind.READ, lambda args, now: SERIAL_NUMBER),
        }

    # ---- the interface ----

    def handle(self, data: bytes, sender: Address, now: float) -> list[Reply]:
        """Answer one datagram from ``sender`` received at ``now`` (s)."""
        if not data:
            return []
        if len(data) > MAX_DATAGRAM:
            return [Reply(ERROR, sender)]
        try:
            text = data.decode("utf-8")
        except UnicodeDecodeError:
            return [Reply(ERROR, sender)]
        text = text.strip()
        words = text.split()
        if not words:
            return []
        name, args = words[0], words[1:]
        if not self.sdk_mode and name != "command":
            return []  # not in SDK mode yet: the real drone does not answer
        handler = self._handlers.get(name)
        if handler is None:
            return [Reply(f"unknown command: {_printable(text)}", sender)]
        kind, function = handler
        self._sender = sender
        try:
            answer = function(args, now)
        except BadArgs:
            answer = ERROR
        except OutOfRange:
            answer = OUT_OF_RANGE
        if answer != ERROR and answer != OUT_OF_RANGE:
            self.session.last_command_s = now
        if kind is Kind.SILENT:
            return []
        if answer == "":  # blocking: answered by tick() when finished
            self._pending = sender
            return []
        return [Reply(answer, sender)]

    def tick(self, dt: float, now: float) -> list[Reply]:
        """Advance the flight by ``dt`` (s); the replies that became due (finished moves)."""
        flight = self.flight
        flight.step(dt)
        replies = []
        if flight.take_finished():
            self.session.last_command_s = now  # the 15 s count from the end of a manoeuvre
            if self._pending is not None:
                replies.append(Reply(OK, self._pending))
                self._pending = None
        if flight.flying and not flight.busy:
            quiet = now - self.session.last_command_s
            if quiet >= flight.env.auto_land_s or (
                flight.battery_percent <= flight.env.low_battery_land
            ):
                flight.land()  # nobody to answer: the Tello lands by itself
        return replies

    # ---- derived readings ----

    def height_cm(self) -> int:
        """Height above the take-off point, cm (``h`` of the state string)."""
        return round(max(0.0, self.flight.state.z - self.flight.ground_z) * 100.0)

    def _height_dm(self) -> int:
        return round(self.height_cm() / 10.0)

    def tof_cm(self) -> int:
        """The downward time-of-flight range, cm: the height above the ground plus 10 cm (the
        sensor's reading when landed); 6553 out of its range (above ~8 m)."""
        value = round(self.flight.state.z * 100.0) + 10
        return value if value <= 800 else 6553

    def baro_m(self) -> float:
        """Barometric altitude, m."""
        return self.baro_origin_m + self.flight.state.z

    def temperatures(self) -> tuple[int, int]:
        """Lowest and highest board temperature, deg C: warms from 45 towards 90 while on."""
        t = self.flight.time_s
        low = 45.0 + 40.0 * (1.0 - math.exp(-t / 600.0))
        return int(low), int(low) + 2

    # ---- handlers: each returns the reply, "" for a blocking one answered later ----

    def _command(self, args: list[str], now: float) -> str:
        if args:
            raise BadArgs
        self.sdk_mode = True
        self.session.client = self._sender  # state and video go to the last one that asked
        return OK

    def _flight_ok(self) -> str | None:
        """The refusal for a flight command now, or None if it may fly."""
        if not self.flight.flying:
            return MOTOR_STOP
        if self.flight.busy:
            return NOT_JOYSTICK
        return None

    def _takeoff(self, args: list[str], now: float) -> str:
        if args:
            raise BadArgs
        flight = self.flight
        if flight.phase is not Phase.LANDED:
            return ERROR
        if flight.battery_percent <= flight.env.low_battery_takeoff:
            return MOTOR_STOP
        flight.takeoff()
        return ""

    def _land(self, args: list[str], now: float) -> str:
        if args:
            raise BadArgs
        if self.flight.phase is Phase.LANDING:
            return ""  # already landing (by itself): answered on the ground
        if not self.flight.flying:
            return MOTOR_STOP
        self._pending = None
        self.flight.land()
        return ""

    def _emergency(self, args: list[str], now: float) -> str:
        if args:
            raise BadArgs
        self._pending = None
        self.flight.emergency()
        return OK

    def _stop(self, args: list[str], now: float) -> str:
        if args:
            raise BadArgs
        self._pending = None
        self.flight.hover()
        return OK

    def _streamon(self, args: list[str], now: float) -> str:
        if args:
            raise BadArgs
        self.session.streaming = True
        return OK

    def _streamoff(self, args: list[str], now: float) -> str:
        if args:
            raise BadArgs
        self.session.streaming = False
        return OK

    def _move_cmd(
        self, forward: float, left: float, up: float
    ) -> Callable[[list[str], float], str]:
        def move(args: list[str], now: float) -> str:
            (cm,) = _ints(args, 1)
            _check(cm, 20, 500)
            refusal = self._flight_ok()
            if refusal:
                return refusal
            d = cm / 100.0
            self.flight.move(forward * d, left * d, up * d, self.session.speed)
            return ""

        return move

    def _rotate_cmd(self, sign_ccw: float) -> Callable[[list[str], float], str]:
        def rotate(args: list[str], now: float) -> str:
            (deg,) = _ints(args, 1)
            _check(deg, 1, 360)
            refusal = self._flight_ok()
            if refusal:
                return refusal
            self.flight.rotate(sign_ccw * math.radians(deg))
            return ""

        return rotate

    def _flip(self, args: list[str], now: float) -> str:
        if len(args) != 1 or args[0] not in ("l", "r", "f", "b"):
            raise BadArgs
        refusal = self._flight_ok()
        if refusal:
            return refusal
        if self.flight.battery_percent < self.flight.env.flip_battery:
            return ERROR
        self.flight.flip()
        return ""

    def _go(self, args: list[str], now: float) -> str:
        x, y, z, speed = _ints(args, 4)
        for v in (x, y, z):
            _check(v, -500, 500)
        _check(speed, 10, 100)
        if all(-20 <= v <= 20 for v in (x, y, z)):
            raise OutOfRange
        refusal = self._flight_ok()
        if refusal:
            return refusal
        # SDK axes: x forward, y left, z up (cm)
        self.flight.move(x / 100.0, y / 100.0, z / 100.0, speed / 100.0)
        return ""

    def _curve(self, args: list[str], now: float) -> str:
        x1, y1, z1, x2, y2, z2, speed = _ints(args, 7)
        for v in (x1, y1, z1, x2, y2, z2):
            _check(v, -500, 500)
        _check(speed, 10, 60)
        p1 = (x1 / 100.0, y1 / 100.0, z1 / 100.0)
        p2 = (x2 / 100.0, y2 / 100.0, z2 / 100.0)
        if all(abs(v) <= 0.2 for v in p1) or all(abs(v) <= 0.2 for v in p2):
            raise OutOfRange
        arc = arc_through((0.0, 0.0, 0.0), p1, p2)
        if arc is None:
            return ERROR  # collinear points or a radius outside 0.5..10 m
        refusal = self._flight_ok()
        if refusal:
            return refusal
        s = self.flight.state
        start = (s.x, s.y, s.z)
        points = []
        for fwd, left, up in arc:
            d = body_to_enu(fwd, left, up, s.yaw)
            points.append((start[0] + d[0], start[1] + d[1], start[2] + d[2]))
        self.flight.fly_path(points, speed / 100.0)
        return ""

    def _speed(self, args: list[str], now: float) -> str:
        (cm_s,) = _ints(args, 1)
        self.session.speed = _check(cm_s, 10, 100) / 100.0
        return OK

    def _rc(self, args: list[str], now: float) -> str:
        a, b, c, d = _ints(args, 4)
        for v in (a, b, c, d):
            _check(v, -100, 100)
        flight = self.flight
        if flight.flying and not flight.busy:
            flight.set_rc(a / 100.0, b / 100.0, c / 100.0, d / 100.0)
        return OK

    def _wifi(self, args: list[str], now: float) -> str:
        if len(args) != 2:
            raise BadArgs
        return OK  # the simulated drone has no Wi-Fi to rename

    def _port(self, args: list[str], now: float) -> str:
        state_port, video_port = _ints(args, 2)
        _check(state_port, 1025, 65535)
        _check(video_port, 1025, 65535)
        self.session.state_port, self.session.video_port = state_port, video_port
        return OK

    def _attitude(self, args: list[str], now: float) -> str:
        pitch, roll, yaw = self.attitude_deg()
        return f"pitch:{pitch};roll:{roll};yaw:{yaw};"

    def _acceleration(self, args: list[str], now: float) -> str:
        ax, ay, az = self.acceleration_mg()
        return f"agx:{ax:.2f};agy:{ay:.2f};agz:{az:.2f};"

    # ---- attitude and acceleration in the Tello's conventions ----

    def attitude_deg(self) -> tuple[int, int, int]:
        """Pitch (nose up > 0), roll (right side down > 0), yaw (clockwise > 0, from the heading
        at power-on, -180..180), whole degrees."""
        return attitude_deg(self.flight)

    def acceleration_mg(self) -> tuple[float, float, float]:
        """Specific force in the body frame FRD, 0.001 g (agz ~ -1000 at rest)."""
        return acceleration_mg(self.flight.state)


def arc_through(
    p0: tuple[float, float, float],
    p1: tuple[float, float, float],
    p2: tuple[float, float, float],
    samples: int = 24,
) -> list[tuple[float, float, float]] | None:
    """Points along the circular arc from ``p0`` through ``p1`` to ``p2`` (m), or None when they
    are collinear or the radius is outside the SDK's 0.5..10 m."""
    import numpy as np

    a, b, c = (np.asarray(p, dtype=float) for p in (p0, p1, p2))
    ab, ac = b - a, c - a
    normal = np.cross(ab, ac)
    n2 = float(normal @ normal)
    if n2 < 1e-9:
        return None
    center = a + (np.cross(normal, ab) * (ac @ ac) + np.cross(ac, normal) * (ab @ ab)) / (2 * n2)
    radius = float(np.linalg.norm(a - center))
    if not 0.5 <= radius <= 10.0:
        return None
    u = (a - center) / radius
    w = np.cross(normal / math.sqrt(n2), u)

    def angle(p: np.ndarray) -> float:
        d = p - center
        return math.atan2(float(d @ w), float(d @ u)) % (2 * math.pi)

    end = angle(c)
    if angle(b) > end:  # p1 lies on the other way round: go the long way in reverse
        end -= 2 * math.pi
    points = [
        center + radius * (math.cos(t) * u + math.sin(t) * w)
        for t in np.linspace(0.0, end, samples + 1)
    ]
    return [(float(p[0]), float(p[1]), float(p[2])) for p in points]


def _printable(text: str, limit: int = 64) -> str:
    """``text`` cut to ``limit`` characters with control characters replaced."""
    cleaned = "".join(ch if ch.isprintable() else "?" for ch in text)
    return cleaned[:limit]
