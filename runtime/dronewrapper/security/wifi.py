"""Is the Wi-Fi this machine is on open? For bridges to Wi-Fi drones (a Tello's network is an
open access point by default: anyone in range can join it and fly the drone).

    warning = open_wifi_warning()      # None when protected or unknown
    if warning:
        log.warning("%s", warning)

It asks NetworkManager (``nmcli``); without it the answer is "unknown" (None), never a guess.
"""

from __future__ import annotations

import shutil
import subprocess
from dataclasses import dataclass

NMCLI_TIMEOUT_S = 2.0
DOCS = "docs/security.md#tello"


@dataclass(frozen=True)
class WifiNetwork:
    """One network as ``nmcli`` lists it: whether we are on it, its SSID, its security."""

    active: bool
    ssid: str
    security: str  # "" or "--" for an open network, else e.g. "WPA2"

    @property
    def open(self) -> bool:
        return self.security.strip() in ("", "--")


def _split_terse(line: str) -> list[str]:
    """Split one ``nmcli -t`` line on unescaped colons (``\\:`` is a colon inside a field)."""
    fields, current, escaped = [], "", False
    for char in line:
        if escaped:
            current, escaped = current + char, False
        elif char == "\\":
            escaped = True
        elif char == ":":
            fields.append(current)
            current = ""
        else:
            current += char
    fields.append(current)
    return fields


def parse_nmcli(text: str) -> list[WifiNetwork]:
    """Networks from ``nmcli -t -f ACTIVE,SSID,SECURITY dev wifi`` output."""
    networks = []
    for line in text.splitlines():
        fields = _split_terse(line)
        if len(fields) != 3:
            continue
        active, ssid, security = fields
        networks.append(WifiNetwork(active.strip().lower() == "yes", ssid, security))
    return networks


def active_network() -> WifiNetwork | None:
    """The Wi-Fi network this machine is on, or None (no Wi-Fi, no nmcli, or it failed)."""
    nmcli = shutil.which("nmcli")
    if nmcli is None:
        return None
    try:
        done = subprocess.run(
            [nmcli, "-t", "-f", "ACTIVE,SSID,SECURITY", "dev", "wifi"],
            capture_output=True,
            text=True,
            timeout=NMCLI_TIMEOUT_S,
            check=False,
        )
    except (OSError, subprocess.TimeoutExpired):
        return None
    return next((n for n in parse_nmcli(done.stdout) if n.active), None)


def open_wifi_warning(network: WifiNetwork | None = None) -> str | None:
    """A warning if the Wi-Fi we are on (``network``, default: ask nmcli) is open, else None."""
    network = network if network is not None else active_network()
    if network is None or not network.open:
        return None
    return (
        f"the Wi-Fi {network.ssid!r} is open: anyone in range can join it and command the "
        f"drone. Set a WPA2 password on the drone (see {DOCS})"
    )
