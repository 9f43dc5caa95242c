"""docs/capabilities.md is rendered from the recorded results: the newest one per call or app
and backend wins, failures say why, and what never ran says so."""

from __future__ import annotations

import json

from bench.capabilities import CALLS, render


def write(path, entries):
    path.write_text("".join(json.dumps(e) + "\n" for e in entries))


def call(name, backend, result, date="2026-11-26", firmware="PX4 v0.0.0 (02e73e3b6f)"):
    return {"kind": "call", "call": name, "backend": backend, "firmware": firmware,
            "date": date, "result": result}  # fmt: skip


def test_matrix_from_records(tmp_path):
    records = tmp_path / "caps.jsonl"
    write(
        records,
        [
            call("takeoff", "px4", "CommandRefused: arming refused", date="2026-11-25"),
            call("takeoff", "px4", "ok"),  # newer: wins
            call("param_get", "tello", "NoData: no such parameter | really", firmware="Tello"),
            {
                "kind": "app",
                "app": "follow_color",
                "scenario": "beacon_smooth",
                "backend": "ardupilot",
                "firmware": "ArduCopter V4.8.0-dev",
                "date": "2026-11-26",
                "passed": False,
                "centred": 0.5,
                "within_distance": 0.25,
            },
        ],
    )
    text = render(records, tmp_path / "capabilities.md")
    assert text == (tmp_path / "capabilities.md").read_text()
    rows = {line.split("|")[1].strip(): line for line in text.splitlines() if line.startswith("| ")}
    assert len([r for r in rows if r.startswith("`")]) == len(CALLS)
    takeoff = [c.strip() for c in rows["`takeoff`"].split("|")[2:-1]]
    assert takeoff == ["not run", "ok", "not run", "not run", "not run"]  # + PX4 over Zenoh
    assert "**fails**: NoData: no such parameter / really" in rows["`param_get`"]
    assert "**fails** (centred 50%, within distance 25%)" in rows["follow_color beacon_smooth"]
    assert "- PX4 SITL (SIH): PX4 v0.0.0 (02e73e3b6f), 2026-11-26\n" in text  # the newest
    assert "- our sim (Iris): not run" in text
