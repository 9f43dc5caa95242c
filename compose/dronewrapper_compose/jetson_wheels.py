"""Whether every runtime dependency installs as a binary wheel on a Jetson (JetPack 6).

JetPack 6 is Ubuntu 22.04 on aarch64 with Python 3.10 and glibc 2.35, so it takes wheels tagged
``manylinux2014_aarch64`` and ``manylinux_2_17`` up to ``manylinux_2_35_aarch64``. A
dependency with no such wheel would be built from source on the Jetson (minutes to hours, and
a compiler and headers it may not have), or not install at all.

    python -m dronewrapper_compose.jetson_wheels

asks pip to resolve the third-party requirements of every distribution of the
stack (``pyproject.toml`` of the repository, the SDK's extras included) for that platform,
``--only-binary=:all:``, as ``pip download`` would, but as a dry-run install that reads each
wheel's metadata from the index (PEP 658) instead of downloading the wheels: nothing is
downloaded, built, installed or emulated. It names what has no wheel.
"""

from __future__ import annotations

import json
import re
import subprocess
import sys
import tempfile
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
PYTHON_VERSION = "3.10"
GLIBC_MINOR = 35  # Ubuntu 22.04
PLATFORMS = ("manylinux2014_aarch64", *(f"manylinux_2_{m}_aarch64" for m in range(17, 36)))
_NAME = re.compile(r"^\s*([A-Za-z0-9][A-Za-z0-9._-]*)\s*(?:\[([^\]]*)\])?")
_MISSING = re.compile(r"No matching distribution found for ([^\s]+)")


def normalize(name: str) -> str:
    """A distribution name as pip compares it (PEP 503)."""
    return re.sub(r"[-_.]+", "-", name).lower()


def parse_requirement(text: str) -> tuple[str, list[str]]:
    """(normalized name, extras) of a requirement string."""
    match = _NAME.match(text)
    if match is None:
        raise ValueError(f"not a requirement: {text!r}")
    extras = [e.strip() for e in (match.group(2) or "").split(",") if e.strip()]
    return normalize(match.group(1)), extras


def local_projects(repo: Path = REPO) -> dict[str, dict]:
    """Each distribution of the repository (normalized name -> its ``[project]`` table)."""
    import tomllib  # type: ignore[import-not-found]  # novermin: the check runs on CI, not a Jetson

    files = [repo / "pyproject.toml", *sorted(repo.glob("*/pyproject.toml"))]
    files += sorted(repo.glob("services/*/pyproject.toml"))
    projects = {}
    for path in files:
        project = tomllib.loads(path.read_text())["project"]
        projects[normalize(project["name"])] = project
    return projects


def third_party_requirements(repo: Path = REPO, root: str = "dronewrapper-stack") -> list[str]:
    """The requirements of ``root`` and everything of ours it pulls in (with their extras),
    that are not ours: what pip must find on an index."""
    projects = local_projects(repo)
    out: list[str] = []
    seen: set[tuple[str, tuple[str, ...]]] = set()
    todo: list[tuple[str, tuple[str, ...]]] = [(normalize(root), ())]
    while todo:
        name, extras = todo.pop()
        if (name, tuple(extras)) in seen:
            continue
        seen.add((name, tuple(extras)))
        project = projects[name]
        requirements = list(project.get("dependencies", []))
        for extra in extras:
            requirements += project.get("optional-dependencies", {})[extra]
        for requirement in requirements:
            dep, dep_extras = parse_requirement(requirement)
            if dep in projects:
                todo.append((dep, tuple(sorted(dep_extras))))
            elif requirement not in out:
                out.append(requirement)
    return sorted(out, key=lambda r: parse_requirement(r)[0])


def pip_resolve_argv(requirements: list[str], target: Path, report: Path) -> list[str]:
    """``pip install --dry-run`` of ``requirements`` as wheels for a Jetson, writing what pip
    would install to the JSON ``report`` (``target`` is a folder pip is told to install to and
    never writes)."""
    platforms = [arg for p in PLATFORMS for arg in ("--platform", p)]
    return [
        sys.executable, "-m", "pip", "install", "--dry-run", "--ignore-installed",
        "--target", str(target), "--report", str(report),
        "--only-binary=:all:", "--python-version", PYTHON_VERSION, "--implementation", "cp",
        *platforms, "--quiet", *requirements,
    ]  # fmt: skip


def wheel_names(report: dict) -> list[str]:
    """The wheel file names in a ``pip install --report`` (its format is version 1)."""
    return sorted(item["download_info"]["url"].rsplit("/", 1)[-1] for item in report["install"])


def missing_wheel(pip_output: str) -> str | None:
    """The requirement pip found no wheel for, from its output, or None."""
    match = _MISSING.search(pip_output)
    return match.group(1) if match else None


def main() -> int:
    requirements = third_party_requirements()
    print(f"checking {len(requirements)} requirements for aarch64, Python {PYTHON_VERSION}:")
    print("  " + " ".join(requirements))
    with tempfile.TemporaryDirectory() as scratch:
        report = Path(scratch) / "report.json"
        done = subprocess.run(
            pip_resolve_argv(requirements, Path(scratch) / "target", report),
            capture_output=True,
            text=True,
        )
        wheels = wheel_names(json.loads(report.read_text())) if done.returncode == 0 else []
    if done.returncode != 0:
        missing = missing_wheel(done.stderr + done.stdout)
        print(done.stderr[-3000:], file=sys.stderr)
        what = f"{missing} has no wheel for it" if missing else "pip failed"
        print(f"FAIL {what}: see docs/jetson.md (what to do)", file=sys.stderr)
        return 1
    print(f"ok   every requirement resolves to binary wheels ({len(wheels)} wheels):")
    for wheel in wheels:
        print(f"  {wheel}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
