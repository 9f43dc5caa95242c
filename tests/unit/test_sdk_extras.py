"""The SDK's optional extras pin the same ranges as the on-board stack."""

import tomllib

from support import REPO


def requirement(requirements: list[str], name: str) -> str:
    (found,) = [r for r in requirements if r.split(">")[0].split("<")[0].split("=")[0] == name]
    return found


def test_images_extra_uses_the_stacks_opencv_range():
    sdk = tomllib.loads((REPO / "sdk" / "pyproject.toml").read_text())["project"]
    stack = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]
    extra = requirement(sdk["optional-dependencies"]["images"], "opencv-python-headless")
    assert extra == requirement(stack["dependencies"], "opencv-python-headless")
    assert "<5" in extra
