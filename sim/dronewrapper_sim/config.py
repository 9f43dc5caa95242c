"""The simulator's configuration: a strict schema (YAML/JSON file, ``--set``, CLI flags)."""

from __future__ import annotations

import ipaddress
from typing import Annotated, Literal

import msgspec

from dronewrapper.runtime.config_ranges import Positive, check_ranges
from dronewrapper_sim.mavlink_io import parse_udp_spec
from dronewrapper_sim.tello.config import TelloConfig

ImageSide = Annotated[int, msgspec.Meta(ge=16)]
"""A side of the rendered image (px)."""


class SimConfig(msgspec.Struct, forbid_unknown_fields=True, kw_only=True):
    """Settings of ``dronewrapper sim`` (CLI flags in brackets).

    Attributes:
        scenario: scenario name or YAML path [--scenario].
        instance: vehicle instance N like PX4's ``-i``: ports + N, system id 1 + N,
            namespace ``drone{N}`` when N > 0 [--instance].
        seed: random seed; None = the scenario's [--seed].
        cameras: render and publish the cameras [--no-cameras turns off].
        camera_rate_hz: camera rate (Hz); None = the scenario's (30) [--camera-rate].
        width, height: image size (px); None = the scenario's (640x480) [--width, --height].
        sprites: folder of person sprites (photo billboards); None = procedural people
            [--sprites].
        udp_onboard: onboard/API link ``[HOST:]PORT[:LOCAL]`` or ``off``; "" = PX4's
            127.0.0.1:14540+N from 14580+N [--udp-onboard].
        udp_gcs: GCS link, same form; "" = 127.0.0.1:14550 from 18570+N [--udp-gcs].
        realtime_factor: simulated seconds per wall-clock second [--realtime-factor].
        physics_rate_hz: physics and autopilot step rate (Hz).
        loop_rate_hz: how often the loop wakes at most to step the physics and send the
            telemetry due (Hz); below ``physics_rate_hz`` each wake-up runs the steps owed
            (the physics keeps its fixed step) and sends what is due within half a wake-up
            period, so the streams keep their rates up to this one (a fleet: fewer wake-ups
            of its sims and bridges). MAVLink that arrives still wakes it at once. None =
            ``physics_rate_hz`` (a wake-up a step).
        ground_truth_rate_hz: rate of ``{ns}/sim/ground_truth`` (Hz).
        object_pose_rate_hz: rate of ``sim/objects/{name}/pose`` (Hz).
        compressed: always publish JPEG images too (else only while someone subscribes).
        jpeg_quality: JPEG quality 1..100.
        render_unwatched: render and publish raw images even when nobody subscribes.
        params: PX4 parameter overrides at boot (name: value).
        aircraft: ``iris`` (the PX4-like quadrotor on MAVLink) or ``tello`` (a DJI Tello on
            the Tello SDK) [--aircraft].
        address: Tello only: the address of its UDP port 8889; "" = 127.0.0.(1+N), or the
            drone's address in the namespace with ``netns`` [--address].
        netns: Tello only: live in a network namespace of its own joined to the host by a veth
            pair (root) [--netns].
        tello: the simulated Tello's settings (see ``dronewrapper_sim.tello.config``).
        signing_key_file: MAVLink 2 signing key provisioned at boot, like PX4's key file on the
            SD card (64 hex digits, ``dronewrapper keys mavlink``); "" = none until a
            SETUP_SIGNING arrives [--signing-key].
        autopilot: "" = the simulator's own PX4-like autopilot and physics; ``px4-sih`` or
            ``ardupilot`` = no autopilot of ours: the vehicle pose comes from that external
            autopilot's own simulation (``dronewrapper_sim.external``) [--autopilot].
        autopilot_link: where its truth arrives, ``udp:HOST:PORT`` (bound) or
            ``tcp:HOST:PORT`` (connected to); "" = ``udp:127.0.0.1:19410`` for PX4 SIH,
            ``tcp:127.0.0.1:5762`` (SERIAL1) for ArduCopter SITL [--autopilot-link].
        truth_rate_hz: the truth rate asked of the external autopilot (Hz).
        max_extrapolation_s: a frame's pose is extrapolated at most this far past the newest
            truth (s).
    """

    scenario: str = "beacon_static"
    instance: Annotated[int, msgspec.Meta(ge=0)] = 0
    seed: int | None = None
    cameras: bool = True
    camera_rate_hz: Positive | None = None
    width: ImageSide | None = None
    height: ImageSide | None = None
    sprites: str | None = None
    udp_onboard: str = ""
    udp_gcs: str = ""
    realtime_factor: Positive = 1.0
    physics_rate_hz: Positive = 250.0
    loop_rate_hz: Positive | None = None
    ground_truth_rate_hz: Positive = 50.0
    object_pose_rate_hz: Positive = 20.0
    compressed: bool = False
    jpeg_quality: Annotated[int, msgspec.Meta(ge=1, le=100)] = 80
    render_unwatched: bool = False
    params: dict[str, float] = {}
    aircraft: Literal["iris", "tello"] = "iris"
    address: str = ""
    netns: bool = False
    tello: TelloConfig = msgspec.field(default_factory=TelloConfig)
    signing_key_file: str = ""
    autopilot: str = ""
    autopilot_link: str = ""
    truth_rate_hz: Annotated[float, msgspec.Meta(gt=0, le=1000)] = 50.0
    max_extrapolation_s: Annotated[float, msgspec.Meta(ge=0, le=1)] = 0.1

    def __post_init__(self) -> None:
        check_ranges(self)
        for name in ("udp_onboard", "udp_gcs"):
            spec = getattr(self, name)
            if spec:
                try:
                    parse_udp_spec(spec, 0)
                except ValueError as exc:
                    raise ValueError(f"{name}: {exc}") from None
        if (self.address or self.netns) and self.aircraft != "tello":
            raise ValueError("address and netns are Tello settings (aircraft: tello)")
        if self.address:
            try:
                ipaddress.IPv4Address(self.address)
            except ValueError as exc:
                raise ValueError(f"address: {exc}") from None
        self._check_autopilot()

    def _check_autopilot(self) -> None:
        from dronewrapper_sim.external.links import AUTOPILOTS, parse_link

        if self.autopilot and self.autopilot not in AUTOPILOTS:
            raise ValueError(
                f"autopilot must be one of {', '.join(AUTOPILOTS)} (or empty), "
                f"got {self.autopilot!r}"
            )
        if self.autopilot and self.aircraft != "iris":
            raise ValueError("autopilot: an external autopilot flies the iris aircraft only")
        if self.autopilot_link:
            try:
                parse_link(self.autopilot_link)
            except ValueError as exc:
                raise ValueError(f"autopilot_link: {exc}") from None
