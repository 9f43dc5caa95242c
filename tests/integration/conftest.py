"""Fixtures of the integration tier: compose/sim_iris.yaml run once for a whole test module."""

from __future__ import annotations

from collections.abc import Iterator

import pytest
from sdk_sim_graph import sim_graph


@pytest.fixture(scope="module")
def sim_iris(tmp_path_factory, request) -> Iterator[str]:
    """The router endpoint of the simulated Iris and its bridge (compose/sim_iris.yaml, see
    :func:`sdk_sim_graph.sim_graph`), one graph for the module's tests."""
    with sim_graph(tmp_path_factory.mktemp(request.module.__name__)) as (endpoint, _):
        yield endpoint
