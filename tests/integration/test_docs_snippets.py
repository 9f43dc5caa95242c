"""The README's and docs/' shell and Python snippets, run as a reader would, against one
simulated secure graph (sim_iris_secure: signed MAVLink, the command lease, a TLS listener with
access control), so the docs cannot rot. What each snippet needs of this machine and which
lines cannot run here (hardware, fixed ports) is in tests/doc_snippets.py.

The flights run first (the paper's listing, then the asyncio one, as the same commander), then
the operator alice takes the lease over as the README shows, then the rest; the recording runs
last (its replay puts recorded telemetry on the bus).
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest
from doc_snippets import ASYNCIO, LISTING, PLAN, RECORDING, Run, adapt, snippets
from key_store import issued_store

from dronewrapper_compose.launcher import Launcher
from dronewrapper_compose.ports import private_links
from support import free_endpoint, free_port

pytestmark = pytest.mark.integration

FIRST = [LISTING, ASYNCIO]  # the flights, as one commander
LAST = [RECORDING]  # its replay publishes recorded telemetry
SNIPPET_TIMEOUT_S = 120


def _ordered() -> list:
    runs = [s for s in snippets() if isinstance(PLAN[s.key], Run) and not PLAN[s.key].same_as]
    rank = {key: i for i, key in enumerate(FIRST)}
    return sorted(
        runs, key=lambda s: (rank.get(s.key, len(FIRST)), s.key in LAST)
    )  # stable: document order otherwise


@pytest.fixture(scope="module")
def graph(tmp_path_factory):
    """sim_iris_secure on free ports with a TLS listener; the key store of alice (operator),
    bob (observer) and the drone."""
    root = tmp_path_factory.mktemp("docs")
    roles = {"drone1": "drone", "alice": "operator", "bob": "observer"}
    store = issued_store(root / "keys", roles)
    router, tls = free_endpoint(), f"tls/127.0.0.1:{free_port()}"
    variables = {
        **private_links(),
    }
    with open(root / "graph.log", "w") as log:
        launcher = Launcher.from_file(
            "sim_iris_secure",
            router=router,
            variables=variables,
            listen=[tls],
            identity="drone1",
            keys_dir=str(store.root),
            out=log,
        )
        with launcher:
            yield {"router": router, "tls": tls, "keys": str(store.root), "root": root}
    assert launcher.exit_code == 0, (root / "graph.log").read_text()[-3000:]


@pytest.mark.parametrize("snippet", _ordered(), ids=lambda s: s.where)
def test_snippet_runs(graph, snippet, tmp_path):
    plan = PLAN[snippet.key]
    bin_dir = str(Path(sys.executable).parent)
    text, left_out = adapt(
        snippet, plan, router=graph["router"], tls=graph["tls"], bin_dir=bin_dir,
        scratch=str(tmp_path),
    )  # fmt: skip
    env = {
        **os.environ,
        "PATH": f"{bin_dir}{os.pathsep}{os.environ.get('PATH', '')}",
        "DRONEWRAPPER_CONNECT": graph["router"],
        "DRONEWRAPPER_KEYS": graph["keys"],
        "PYTHONUNBUFFERED": "1",
    }
    if "dronewrapper keys" in text:  # a key store of its own: the snippet makes one
        env["DRONEWRAPPER_KEYS"] = str(tmp_path / "keys")
    if snippet.language == "python":
        argv = [sys.executable, "-c", text]
    else:
        argv = ["bash", "-e", "-o", "pipefail", "-c", text]
    done = subprocess.run(
        argv, cwd=tmp_path, env=env, capture_output=True, text=True, timeout=SNIPPET_TIMEOUT_S
    )
    said = f"{snippet.where} as run:\n{text}\nleft out: {left_out}\n{done.stdout}\n{done.stderr}"
    assert done.returncode == 0, said
    assert "Traceback" not in done.stderr, said
