"""``dronewrapper record|replay|foxglove`` reject bad arguments before touching the network."""

from __future__ import annotations

import pytest

from dronewrapper.cli import main


@pytest.mark.parametrize(
    ("argv", "says"),
    [
        (["record", "drone/**"], "-o FILE.mcap is required"),
        (["record", "-o", "x.mcap", "--jpeg-quality", "0"], "JPEG quality must be 1..100"),
        (["record", "-o", "x.mcap", "--duration", "nan"], "finite number >= 0"),
        (["record", "-o", "x.mcap", "--image-rate", "-1"], "finite number >= 0"),
        (["replay", "x.mcap", "--rate", "0"], "must be > 0"),
        (["replay", "x.mcap", "--start", "inf"], "finite number >= 0"),
        (["foxglove", "--port", "70000"], "--port must be 0..65535"),
    ],
)
def test_bad_arguments_are_named(argv, says, capsys):
    with pytest.raises(SystemExit) as exc:
        main(argv)
    assert exc.value.code == 2
    assert says in capsys.readouterr().err


def test_replay_of_a_missing_file_says_so(tmp_path, capsys):
    assert main(["replay", str(tmp_path / "none.mcap")]) == 1
    assert "no such file" in capsys.readouterr().err


def test_info_of_a_missing_file_says_so(tmp_path, capsys):
    assert main(["record", "--info", str(tmp_path / "none.mcap")]) == 1
    assert "none.mcap" in capsys.readouterr().err


def test_help_lists_the_record_commands(capsys):
    assert main(["--help"]) == 0
    out = capsys.readouterr().out
    assert all(f"dronewrapper {c}" in out for c in ("record", "replay", "foxglove"))
