"""The demo's plot, rendered for real: matplotlib loads the system's fonts, and on a machine
that never ran it builds its font cache first (starting ``fc-list``), which is why this test is
not in the unit tier."""

from __future__ import annotations

from dronewrapper_compose.demo import save_plot
from dronewrapper_sim.evaluation.metrics import FollowSample


def test_plot_is_a_png_of_the_flight(tmp_path):
    samples = [
        FollowSample(
            t=0.1 * k,
            vehicle=(0.05 * k, 0.0, 2.0),
            yaw=0.01 * k,
            target=(6.0 + 0.05 * k, 0.5, 2.5),
            state="takeoff" if k < 10 else "tracking",
            target_visible=k >= 12,
        )
        for k in range(60)
    ]
    plot = tmp_path / "follow.png"
    save_plot(samples, 5.0, plot)
    assert plot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and plot.stat().st_size > 10_000
