"""A made-up follow flight for the demo's summary, status line and plot: ``n`` samples at
10 Hz, the vehicle creeping east at 2 m, the target 6 m ahead and half a metre left, taking
off for the first second and seen from 1.2 s on."""

from __future__ import annotations

from dronewrapper_sim.evaluation.metrics import FollowSample


def follow_flight(n: int = 60) -> list[FollowSample]:
    return [
        FollowSample(
            t=0.1 * k,
            vehicle=(0.05 * k, 0.0, 2.0),
            yaw=0.01 * k,
            target=(6.0 + 0.05 * k, 0.5, 2.5),
            state="takeoff" if k < 10 else "tracking",
            target_visible=k >= 12,
        )
        for k in range(n)
    ]
