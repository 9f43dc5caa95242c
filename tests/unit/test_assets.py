"""The repository carries its own assets, each matching the checksum recorded beside it."""

from pathlib import Path

import pytest

from dronewrapper_perception.model_file import (
    BUNDLED_YOLOX_NANO_SHA256,
    ModelFileError,
    check_model_file,
    sha256_of,
)
from support import ASSETS, REPO, YOLOX_NANO


def recorded_checksums() -> dict[str, str]:
    lines = (ASSETS / "SHA256SUMS").read_text().splitlines()
    return {name.strip(): digest for digest, name in (line.split(maxsplit=1) for line in lines)}


def test_assets_live_in_the_repository():
    assert ASSETS == REPO / "assets"
    assert YOLOX_NANO.is_file()


def test_every_asset_matches_its_recorded_checksum():
    recorded = recorded_checksums()
    on_disk = {
        str(p.relative_to(ASSETS))
        for p in ASSETS.rglob("*")
        if p.is_file() and p.name not in ("SHA256SUMS", "README.md")
    }
    assert on_disk == set(recorded), "SHA256SUMS must list exactly the files in assets/"
    for name, digest in recorded.items():
        assert sha256_of(ASSETS / name) == digest, name


def test_bundled_model_checksum_is_the_recorded_one():
    assert recorded_checksums()["models/yolox_nano.onnx"] == BUNDLED_YOLOX_NANO_SHA256


def test_known_model_name_with_wrong_bytes_is_refused(tmp_path: Path):
    damaged = tmp_path / "yolox_nano.onnx"
    damaged.write_bytes(YOLOX_NANO.read_bytes()[:100_000])
    with pytest.raises(ModelFileError, match="damaged or not the model"):
        check_model_file(damaged)
    assert check_model_file(damaged, checksum=sha256_of(damaged)) == damaged


def test_bundled_model_passes():
    assert check_model_file(YOLOX_NANO) == YOLOX_NANO
