"""The link's load from its byte counts, and the warning when a line is nearly full (pure)."""

import pytest

from dronewrapper.doctor import describe_link
from dronewrapper.health import FAIL, OK, WARN
from dronewrapper.msgs.link import LinkStatus
from dronewrapper.msgs.registry import LINK_STATUS
from dronewrapper_bridge_mavlink.link_load import CLEAR_MARGIN, LinkLoad, LoadAlarm, Reconnects


def test_rates_over_the_window_and_load_of_the_busier_direction():
    load = LinkLoad(capacity=5760.0, window_s=2.0)
    assert load.rates() == (0.0, 0.0) and load.load() == 0.0
    for second in range(6):
        load.add(float(second), 5400 * second, 1800 * second)
    assert load.rates() == pytest.approx((5400.0, 1800.0))
    assert load.load() == pytest.approx(5400 / 5760)  # 94 %


def test_the_window_forgets_old_counts():
    load = LinkLoad(capacity=5760.0, window_s=2.0)
    for second in range(5):
        load.add(float(second), 5000 * second, 0)  # busy
    for second in range(5, 10):
        load.add(float(second), 20000, 0)  # then silent
    assert load.rates() == (0.0, 0.0)


def test_a_network_link_has_no_load():
    load = LinkLoad(capacity=0.0)
    load.add(0.0, 0, 0)
    load.add(1.0, 10**6, 10**6)
    assert load.load() == 0.0 and load.rates() == (1e6, 1e6)


def test_the_alarm_says_it_once_and_clears_below_a_margin():
    alarm = LoadAlarm(0.8)
    assert alarm.update(0.5, "serial 57600 baud") is None
    warning = alarm.update(0.94, "serial 57600 baud")
    assert warning is not None and warning.startswith("link 94 % full (serial 57600 baud)")
    assert alarm.update(0.95, "x") is None  # said once
    assert alarm.update(0.8 - CLEAR_MARGIN / 2, "x") is None  # not yet cleared
    assert alarm.update(0.6, "x") == "link back to 60 % (x)"
    assert alarm.update(0.85, "x") is not None  # raised again


def status(load: float) -> LinkStatus:
    return LinkStatus(kind="serial", baud=57600, capacity=5760.0, received_rate=load * 5760,
                      sent_rate=1800.0, load=load, lost=3, reconnects=1)  # fmt: skip


def test_doctor_says_how_full_the_link_is():
    key = LINK_STATUS.key("drone")
    assert describe_link("drone", {}) is None  # a Tello's bridge has no link status
    verdict, text = describe_link("drone", {key: status(0.94)})
    assert verdict == WARN
    assert "link 94 % full (serial 57600 baud: 5.4 / 1.8 kB/s down/up), 3 lost, 1 reconnects" in (
        text
    )
    assert describe_link("drone", {key: status(0.3)})[0] == OK
    assert describe_link("drone", {key: status(1.02)})[0] == FAIL


def test_a_network_link_is_described_without_a_load():
    text = LinkStatus(kind="udp", received_rate=12000.0, sent_rate=900.0).describe()
    assert text == "link (udp: 12.0 / 0.9 kB/s down/up), 0 lost, 0 reconnects"


def test_reconnects_count_each_return_once():
    links = Reconnects()
    links.opened()  # the first open
    for connected in (False, True, True):  # heartbeats start: no reconnect
        links.heartbeat(connected)
    assert links.count == 0
    for connected in (False, False, True):  # lost, then back: one
        links.heartbeat(connected)
    assert links.count == 1
    links.heartbeat(False)  # lost, the device reopened, heartbeats back: still one event
    links.opened()
    links.heartbeat(True)
    assert links.count == 2
    links.opened()  # reopened while heartbeats never stopped being seen
    links.heartbeat(True)
    assert links.count == 3
