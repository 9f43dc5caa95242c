"""The demo's plot, rendered for real: matplotlib loads the system's fonts, and on a machine
that never ran it builds its font cache first (starting ``fc-list``), which is why this test is
not in the unit tier."""

from __future__ import annotations

from follow_flight import follow_flight

from dronewrapper_compose.demo import save_plot


def test_plot_is_a_png_of_the_flight(tmp_path):
    samples = follow_flight()
    plot = tmp_path / "follow.png"
    save_plot(samples, 5.0, plot)
    assert plot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and plot.stat().st_size > 10_000
