"""Model files: existence and sha256 checks with errors a person can act on."""

from __future__ import annotations

import hashlib
from pathlib import Path

OFFICIAL_YOLOX_NANO_URL = (
    "https://github.com/Megvii-BaseDetection/YOLOX/releases/download/0.1.1rc0/yolox_nano.onnx"
)
OFFICIAL_YOLOX_NANO_SHA256 = "c789161ed43c8269fcd4e67c67eeeb4e80c622da2eb296a20bc6007bd18a0b7d"
"""sha256 of the official release file as recorded by several public projects (3,659,407 B)."""

BUNDLED_YOLOX_NANO_SHA256 = "3bb7c7746256eca568b2d3f4f934c486f6345bc24154a85bc2bb3f3bbabcf1b1"
"""sha256 of ``assets/models/yolox_nano.onnx``, the export this repository ships (3,659,315 B)."""

KNOWN_MODELS: dict[str, frozenset[str]] = {
    "yolox_nano.onnx": frozenset({BUNDLED_YOLOX_NANO_SHA256, OFFICIAL_YOLOX_NANO_SHA256}),
}
"""File name -> the sha256 digests a file of that name may have. A file named like a known model
is verified even when the config gives no checksum: a truncated download or a stray Git LFS
pointer fails at start with its digest, instead of as an opaque ONNX Runtime error."""


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
    elif file.name in KNOWN_MODELS:
        actual = sha256_of(file)
        if actual not in KNOWN_MODELS[file.name]:
            expected = " or ".join(sorted(KNOWN_MODELS[file.name]))
            raise ModelFileError(
                f"{what} file {file} has sha256 {actual}, but a {file.name} should have {expected}:"
                " the file is damaged or not the model it is named after (a Git LFS pointer or an"
                " interrupted download?); set checksum to accept another export deliberately"
            )
    return file
