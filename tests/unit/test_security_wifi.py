"""The open-Wi-Fi check a Wi-Fi drone's bridge runs (nmcli's terse output parsed, no guess)."""

from __future__ import annotations

from dronewrapper.security.wifi import WifiNetwork, open_wifi_warning, parse_nmcli

NMCLI = """no:HomeNet:WPA2
yes:TELLO-5A1B2C:
no:Cafe\\:Guest:--
no:Lab:WPA1 WPA2
"""


def test_parse_nmcli_terse_output():
    nets = parse_nmcli(NMCLI + "garbage line without fields\n")
    assert [(n.ssid, n.active, n.open) for n in nets] == [
        ("HomeNet", False, False),
        ("TELLO-5A1B2C", True, True),
        ("Cafe:Guest", False, True),
        ("Lab", False, False),
    ]


def test_warns_only_on_an_open_network():
    warning = open_wifi_warning(WifiNetwork(True, "TELLO-5A1B2C", ""))
    assert warning is not None and "TELLO-5A1B2C" in warning and "password" in warning
    assert open_wifi_warning(WifiNetwork(True, "TELLO-5A1B2C", "WPA2")) is None
