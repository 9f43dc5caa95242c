"""The SDK installs alone in a fresh virtual environment and pulls only its light dependencies.

A laptop installs the client with the contract and the runtime below it
(``pip install ./contract ./runtime ./sdk``), none of the tools; the tools
(``pip install ./tools``) add the ``dronewrapper`` command.
"""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
import textwrap

import pytest

from support import REPO, free_endpoint

pytestmark = pytest.mark.integration

LIGHT = {
    *("dronewrapper", "dronewrapper-contract", "dronewrapper-runtime"),
    *("eclipse-zenoh", "msgspec", "numpy"),
}
PARTS = ("contract", "runtime", "sdk")
"""The distributions a laptop installs; ``tools`` comes after, for the command."""
BASE = {"pip", "setuptools", "wheel"}

PROBE = textwrap.dedent(
    """
    import sys
    before = set(sys.modules)
    import dronewrapper
    on_import = sorted(set(sys.modules) - before)
    import json, importlib.metadata as md
    from dronewrapper import DroneWrapper, NotConnected, list_drones
    from drone_wrapper import DroneWrapper as PaperName
    assert PaperName is DroneWrapper
    try:
        DroneWrapper("drone", sys.argv[1], timeout=0.5)
    except NotConnected as exc:
        error = str(exc)
    from dronewrapper import DroneError
    try:
        DroneWrapper("drone", sys.argv[1], timeout=0.5, compressed_images=True)
    except NotConnected:
        jpeg_error = "reached the router: OpenCV was not checked first"
    except DroneError as exc:
        jpeg_error = str(exc)
    heavy = [m for m in ("cv2", "pymavlink", "onnxruntime", "yaml", "matplotlib")
             if m in sys.modules]
    import importlib.util
    tools = [m for m in ("dronewrapper.cli", "dronewrapper.doctor", "dronewrapper.record")
             if importlib.util.find_spec(m) is not None]
    dists = sorted(d.metadata["Name"].lower() for d in md.distributions())
    import importlib.resources
    typed = importlib.resources.files("dronewrapper").joinpath("py.typed").is_file()
    print(json.dumps({"error": error, "jpeg_error": jpeg_error, "heavy_imported": heavy,
                      "dists": dists, "typed": typed, "tools": tools,
                      "on_import": on_import}))
    """
)


def test_sdk_installs_alone_with_light_dependencies(tmp_path):
    for part in (*PARTS, "tools"):
        shutil.copytree(
            REPO / part,
            tmp_path / part,
            ignore=shutil.ignore_patterns("__pycache__", "build", "*.egg-info", "dist"),
        )
    venv = tmp_path / "venv"
    # a bare venv, filled by this interpreter's pip (`pip --python`): the same install, without
    # bootstrapping pip into the venv or compiling numpy's sources (seconds on a busy machine)
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(venv)], check=True)
    python = venv / "bin" / "python"
    pip = [sys.executable, "-m", "pip", "--python", str(python), "--disable-pip-version-check"]
    install = subprocess.run(
        [*pip, "install", "-q", "--no-compile", *(str(tmp_path / part) for part in PARTS)],
        capture_output=True,
        text=True,
        timeout=240,
    )
    assert install.returncode == 0, install.stdout + install.stderr

    probe = subprocess.run(
        [str(python), "-c", PROBE, free_endpoint()],
        capture_output=True,
        text=True,
        timeout=60,
        cwd=tmp_path,  # not the repository: import the installed copy
    )
    assert probe.returncode == 0, probe.stderr
    report = json.loads(probe.stdout.strip().splitlines()[-1])
    assert set(report["dists"]) - BASE == LIGHT, report["dists"]
    for heavy in ("opencv-python-headless", "opencv-python", "pymavlink", "onnxruntime"):
        assert heavy not in report["dists"]
    assert report["heavy_imported"] == []
    assert report["typed"]  # PEP 561: an app's type checker reads the SDK's annotations
    assert report["tools"] == []  # the client alone: no tool
    assert report["on_import"] == ["dronewrapper"]  # `import dronewrapper` loads nothing else
    assert not (venv / "bin" / "dronewrapper").exists()
    assert "cannot reach the Zenoh router" in report["error"]
    assert "pip install 'dronewrapper[images]'" in report["jpeg_error"]  # cv2 is optional

    tools = subprocess.run(
        [*pip, "install", "-q", "--no-compile", "--no-deps", str(tmp_path / "tools")],
        capture_output=True,
        text=True,
        timeout=240,
    )
    assert tools.returncode == 0, tools.stdout + tools.stderr
    cli = subprocess.run(
        [str(venv / "bin" / "dronewrapper"), "up", "compose/sim_iris.yaml"],
        capture_output=True,
        text=True,
        timeout=60,
        cwd=tmp_path,
    )
    assert cli.returncode == 2 and "needs the on-board stack" in cli.stderr
