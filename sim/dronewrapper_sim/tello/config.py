"""Settings of the simulated Tello (the ``tello:`` section of the simulator's config)."""

from __future__ import annotations

import ipaddress

import msgspec

DEFAULT_NETNS_SUBNET = "192.168.10.0/24"
"""The real Tello's Wi-Fi: the drone at .1, the laptop at .2."""


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

    battery_percent: float = 100.0
    video: bool = True
    width: int = 960
    height: int = 720
    fps: float = 30.0
    render_scale: float = 0.5
    bitrate_kbps: int = 1500
    keyframe_interval: int = 30
    packet_bytes: int = 1460
    physics_rate_hz: float = 100.0
    state_rate_hz: float = 10.0
    auto_land_s: float = 15.0
    netns_subnet: str = ""

    def __post_init__(self) -> None:
        if not 1.0 <= self.battery_percent <= 100.0:
            raise ValueError(f"battery_percent must be in 1..100, got {self.battery_percent}")
        for name in ("width", "height"):
            value = getattr(self, name)
            if not 16 <= value <= 4096 or value % 2:
                raise ValueError(f"{name} must be even and in 16..4096 px, got {value}")
        for name in ("fps", "physics_rate_hz", "state_rate_hz"):
            value = getattr(self, name)
            if not 0 < value <= 1000:
                raise ValueError(f"{name} must be in (0, 1000], got {value}")
        if not 0.1 <= self.render_scale <= 1.0:
            raise ValueError(f"render_scale must be in 0.1..1, got {self.render_scale}")
        if not 1.0 <= self.auto_land_s <= 3600.0:
            raise ValueError(f"auto_land_s must be in 1..3600, got {self.auto_land_s}")
        if not 50 <= self.bitrate_kbps <= 50_000:
            raise ValueError(f"bitrate_kbps must be in 50..50000, got {self.bitrate_kbps}")
        if not 1 <= self.keyframe_interval <= 600:
            raise ValueError(f"keyframe_interval must be in 1..600, got {self.keyframe_interval}")
        if not 188 <= self.packet_bytes <= 65_000:
            raise ValueError(f"packet_bytes must be in 188..65000, got {self.packet_bytes}")
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
