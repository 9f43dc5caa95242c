"""The SDK's optional extras pin the same ranges as the on-board distributions."""

import tomllib

from support import REPO


def requirement(requirements: list[str], name: str) -> str:
    (found,) = [r for r in requirements if r.split(">")[0].split("<")[0].split("=")[0] == name]
    return found


def test_images_extra_uses_every_distributions_opencv_range():
    sdk = tomllib.loads((REPO / "sdk" / "pyproject.toml").read_text())["project"]
    extra = requirement(sdk["optional-dependencies"]["images"], "opencv-python-headless")
    assert "<5" in extra
    for project in [*REPO.glob("services/*/pyproject.toml"), REPO / "sim" / "pyproject.toml"]:
        deps = tomllib.loads(project.read_text())["project"]["dependencies"]
        if any(d.startswith("opencv-python-headless") for d in deps):
            assert requirement(deps, "opencv-python-headless") == extra, project
