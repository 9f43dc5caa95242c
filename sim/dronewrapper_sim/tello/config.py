"""Settings of the simulated Tello (the ``tello:`` section of the simulator's config)."""

from __future__ import annotations

import ipaddress
from typing import Annotated

import msgspec

from dronewrapper.runtime.config_ranges import check_ranges

DEFAULT_NETNS_SUBNET = "192.168.10.0/24"
"""The real Tello's Wi-Fi: the drone at .1, the laptop at .2."""
VideoSide = Annotated[int, msgspec.Meta(ge=16, le=4096, multiple_of=2)]
"""A side of the encoded video (px; even)."""
Rate = Annotated[float, msgspec.Meta(gt=0, le=1000)]
"""A rate of the simulated Tello (Hz)."""


class TelloConfig(msgspec.Struct, forbid_unknown_fields=True, kw_only=True):
    """The simulated Tello's own settings.

    Attributes:
        battery_percent: charge at power-on, % (1..100).
        video: encode and send the video after ``streamon`` (false: ``streamon`` is accepted
            and nothing is sent).
        width, height: video size, px (the real drone's 960x720).
        fps: video frame rate, Hz (the real drone's 30).
        render_scale: the camera is rendered at this fraction of the video size and scaled up
            (0.5: 480x360 rendered, 960x720 encoded; halves the sim's CPU while turning).
        bitrate_kbps: H.264 bit rate, kbit/s.
        keyframe_interval: frames between key frames (each carries SPS and PPS).
        packet_bytes: largest video datagram payload, bytes (the real drone's 1460).
        physics_rate_hz: flight model step rate, Hz.
        state_rate_hz: state datagram rate, Hz (the real drone's 10).
        auto_land_s: lands after this long without a command, s (the real drone's 15).
        netns_subnet: the /24 (or smaller) of ``--netns``: the drone at the first host address,
            the host side at the second; "" = 192.168.10.0/24 (192.168.(10+N).0/24 for
            instance N).
    """

    battery_percent: Annotated[float, msgspec.Meta(ge=1, le=100)] = 100.0
    video: bool = True
    width: VideoSide = 960
    height: VideoSide = 720
    fps: Rate = 30.0
    render_scale: Annotated[float, msgspec.Meta(ge=0.1, le=1)] = 0.5
    bitrate_kbps: Annotated[int, msgspec.Meta(ge=50, le=50_000)] = 1500
    keyframe_interval: Annotated[int, msgspec.Meta(ge=1, le=600)] = 30
    packet_bytes: Annotated[int, msgspec.Meta(ge=188, le=65_000)] = 1460
    physics_rate_hz: Rate = 100.0
    state_rate_hz: Rate = 10.0
    auto_land_s: Annotated[float, msgspec.Meta(ge=1, le=3600)] = 15.0
    netns_subnet: str = ""

    def __post_init__(self) -> None:
        check_ranges(self, "tello.")
        if self.netns_subnet:
            netns_addresses(self.netns_subnet)


def netns_addresses(subnet: str) -> tuple[str, str, int]:
    """(drone address, host address, prefix length) of a ``--netns`` subnet.

    Raises:
        ValueError: not an IPv4 network with room for two hosts.
    """
    try:
        net = ipaddress.IPv4Network(subnet, strict=True)
    except ValueError as exc:
        raise ValueError(f"netns_subnet: {exc}") from None
    if net.prefixlen > 30:
        raise ValueError(f"netns_subnet: {subnet} has no room for two hosts")
    hosts = net.hosts()
    drone, host = next(hosts), next(hosts)
    return str(drone), str(host), net.prefixlen


def default_netns_subnet(instance: int) -> str:
    """192.168.10.0/24 for instance 0, 192.168.(10+N).0/24 for instance N."""
    if not 0 <= instance <= 245:
        raise ValueError(f"no default netns subnet for instance {instance}")
    return f"192.168.{10 + instance}.0/24"


def default_address(instance: int) -> str:
    """The loopback address of instance N without ``--netns``: 127.0.0.(1+N)."""
    if not 0 <= instance <= 253:
        raise ValueError(f"no default loopback address for instance {instance}")
    return f"127.0.0.{1 + instance}"
