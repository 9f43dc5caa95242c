"""Model files: existence and sha256 checks with errors a person can act on."""

from __future__ import annotations

import hashlib
from pathlib import Path

OFFICIAL_YOLOX_NANO_URL = (
    "https://github.com/Megvii-BaseDetection/YOLOX/releases/download/0.1.1rc0/yolox_nano.onnx"
)
OFFICIAL_YOLOX_NANO_SHA256 = "c789161ed43c8269fcd4e67c67eeeb4e80c622da2eb296a20bc6007bd18a0b7d"
"""sha256 of the official release file as recorded by several public projects (3,659,407 B)."""


class ModelFileError(ValueError):
    """A model file is missing, unreadable or does not match its checksum."""


def sha256_of(path: str | Path, *, chunk_bytes: int = 1 << 20) -> str:
    """The hex sha256 digest of a file."""
    digest = hashlib.sha256()
    with open(path, "rb") as handle:
        while chunk := handle.read(chunk_bytes):
            digest.update(chunk)
    return digest.hexdigest()


def check_model_file(path: str | Path | None, checksum: str = "", *, what: str = "model") -> Path:
    """Return ``path`` as a Path after checking it exists and, if given, its sha256.

    Raises:
        ModelFileError: no path, missing file, or checksum mismatch (the message says which,
            and where to obtain the official YOLOX weights).
    """
    if not path:
        raise ModelFileError(
            f"no {what} path configured; download e.g. {OFFICIAL_YOLOX_NANO_URL} "
            "and set model_path (or use detector=hog, which needs no file)"
        )
    file = Path(path).expanduser()
    if not file.is_file():
        raise ModelFileError(
            f"{what} file {file} does not exist; download e.g. {OFFICIAL_YOLOX_NANO_URL}"
        )
    if checksum:
        actual = sha256_of(file)
        if actual.lower() != checksum.strip().lower():
            raise ModelFileError(
                f"{what} file {file} has sha256 {actual}, but the config expects {checksum}"
            )
    return file
