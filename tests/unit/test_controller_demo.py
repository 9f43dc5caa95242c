"""The demo's pure parts: the live status line and the summary (no flight). The plot loads the
system's fonts (matplotlib's font cache, built with ``fc-list`` on a new machine), so its test is
in tests/integration/test_demo_plot.py."""

from __future__ import annotations

import io
import math

import pytest
from follow_flight import follow_flight

from dronewrapper_compose.demo import intended_distance, print_summary, status_line
from dronewrapper_sim.evaluation.metrics import summarize


def test_status_line_shows_state_visibility_distance_and_bearing():
    sample = follow_flight()[30]
    line = status_line(3.0, sample, 5.0)
    assert "state=tracking" in line and "visible=yes" in line
    assert f"distance= {sample.distance:.2f} m" in line and "goal 5.0" in line
    assert f"{math.degrees(sample.bearing):+6.1f} deg" in line
    assert "waiting" in status_line(0.5, None, 5.0)


def test_summary_printout():
    summary = summarize(follow_flight(), intended_distance=5.0)
    out = io.StringIO()
    print_summary(summary, out)
    text = out.getvalue()
    for words in ("time to acquire", "centred", "distance error mean / p95", "bearing error p95"):
        assert words in text


def test_intended_distance_of_the_beacon_is_about_five_metres():
    """The paper's follow-colour distance: 'about 5 m' for its reference radius."""
    assert intended_distance("beacon_smooth") == pytest.approx(5.0, abs=0.3)
