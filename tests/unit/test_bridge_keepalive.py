"""Each setpoint crosses the link once; the autopilot still gets one at least every keep-alive
period (dronewrapper_bridge_mavlink.keepalive, driven through the core).

Real MAVLink bytes out of the core (bridge_core_rig.py); the app's stream and the stream tick
interleave on injected time at rates whose phases drift, so a re-send at any phase shows.
"""

from __future__ import annotations

import itertools
import math

import pytest
from bridge_core_rig import EPOCH, OFFBOARD, CoreRig, velocity

from dronewrapper.msgs.mavros import MASK_POSITION
from dronewrapper_bridge_mavlink.config import Config
from dronewrapper_bridge_mavlink.keepalive import KeepAlive

TICK_HZ = 30.0


def stream(rig: CoreRig, seconds: float, app_hz: float) -> int:
    """The app's setpoints at ``app_hz`` and the core's ticks at TICK_HZ, in time order, for
    ``seconds``, with autopilot heartbeats at 5 Hz; the number of setpoints the app sent."""
    start = rig.now
    tick_times = [start + (i + 1) / TICK_HZ for i in range(int(seconds * TICK_HZ))]
    app_times = [start + 0.004 + i / app_hz for i in range(int(seconds * app_hz))]
    events = sorted([(t, "tick") for t in tick_times] + [(t, "app") for t in app_times])
    next_heartbeat = start
    for i, (t, what) in enumerate(events):
        rig.now = t
        if t >= next_heartbeat:
            next_heartbeat = t + 0.2
            rig.heartbeat()
        if what == "app":
            rig.setpoint(velocity(1.0 + 1e-4 * i))  # a new target each time
        else:
            rig.core.tick(t, EPOCH + t)
            rig._collect()
    return len(app_times)


def flying(**config: object) -> CoreRig:
    rig = CoreRig(**config).connect(mode=OFFBOARD, armed=True, flying=True)
    stream(rig, 1.0, 20.0)
    assert rig.core.failsafe.engaged
    return rig


def send_times(rig: CoreRig, since: float) -> list[float]:
    return [
        t for t, m in rig.sent if t >= since and m.get_type() == "SET_POSITION_TARGET_LOCAL_NED"
    ]


@pytest.mark.parametrize("app_hz", [12.0, 20.0, 25.0, 30.0, 45.0])
def test_each_fresh_setpoint_goes_out_once_whatever_the_phase(app_hz):
    rig = flying()
    since = rig.now
    arrived = stream(rig, 3.0, app_hz)
    sent = rig.setpoints(since=since)
    assert len(sent) == arrived, "a setpoint crossed the link twice"
    assert [m.vx for m in sent] == sorted(m.vx for m in sent), "each one once, in order"


def test_a_paused_stream_is_kept_alive_once_a_period_until_it_expires():
    rig = flying()
    paused = rig.now
    last = send_times(rig, 0.0)[-1]  # the app's last setpoint, forwarded as it arrived
    rig.run(2.0)  # the app stops: keep-alive, then the hold (setpoint_timeout 0.5 s)
    stale_at = last + rig.core.config.setpoint_timeout
    kept = [t for t in send_times(rig, paused) if t < stale_at]
    keepalive = rig.core.config.setpoint_keepalive_s
    gaps = [b - a for a, b in itertools.pairwise([last, *kept, stale_at])]
    assert max(gaps) <= keepalive + 1.0 / TICK_HZ + 1e-9, "the autopilot went without a setpoint"
    assert min(gaps[:-1]) >= keepalive - 1e-9, (
        "the paused setpoint went out more than once a period"
    )
    assert len(kept) >= 3
    assert rig.core.failsafe.state == "hold"
    assert rig.setpoints(since=stale_at + 0.1, mask=MASK_POSITION)


def test_keepalive_rule():
    k = KeepAlive(0.1, 0.01)
    a, b = object(), object()
    assert k.due(a, 0.0, fresh=True)
    k.sent(a, 0.0)
    assert not k.due(a, 0.05, fresh=True), "the same setpoint again within the period"
    assert k.due(b, 0.05, fresh=True), "another setpoint goes out at once"
    assert k.due(a, 0.1, fresh=True), "the keep-alive"
    assert k.due(a, 0.05, fresh=False), "the bridge's own holds stream on every tick"
    assert not k.due(a, 0.005, fresh=False), "but not right after a send"
    k.sent(a, 0.3)
    assert k.streamed_for(0.4) == pytest.approx(0.4)
    assert k.streamed_for(1.0) == 0.0
    k.sent(a, 1.0)
    assert k.streamed_for(1.2) == pytest.approx(0.2)


@pytest.mark.parametrize("bad", [0.0, -0.1, 0.45, math.inf, math.nan])
def test_the_keepalive_period_is_bounded_by_px4s_2_hz(bad):
    with pytest.raises(ValueError, match="setpoint_keepalive_s"):
        Config(setpoint_keepalive_s=bad)
