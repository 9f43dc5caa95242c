"""``make setup``'s installs print no setuptools warning block: one distribution installed
editable, and the root distribution as it is, into a fresh virtual environment, as the
Makefile does (build isolation, this interpreter's pip)."""

from __future__ import annotations

import subprocess
import sys

import pytest

from support import REPO

pytestmark = pytest.mark.integration

WARNING_SIGNS = ("BuildBackendWarning", "Editable installation", "!!", "********")


@pytest.mark.parametrize(
    "requirement", [["-e", "services/controller"], ["."]], ids=["a service, editable", "the root"]
)
def test_an_install_as_make_setup_does_it_prints_no_warning_block(tmp_path, requirement):
    venv = tmp_path / "venv"
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(venv)], check=True)
    pip = [sys.executable, "-m", "pip", "--python", str(venv / "bin" / "python")]
    done = subprocess.run(
        [*pip, "install", "-q", "--no-deps", "--no-compile", *requirement],
        capture_output=True,
        text=True,
        timeout=240,
        cwd=REPO,
    )
    said = done.stdout + done.stderr
    assert done.returncode == 0, said
    assert not any(sign in said for sign in WARNING_SIGNS), said
