"""The command lines a compose graph resolves to, and the config arguments in one of them.

:func:`graph_argvs` resolves ``compose/NAME.yaml`` as the launcher would, without starting
anything; :func:`config_args` reads back what a process's ``--config``/``--set`` flags say.
"""

from __future__ import annotations

import itertools
from collections.abc import Mapping

from dronewrapper.runtime.options import DEFAULT_ROUTER
from dronewrapper_compose.graph import REPO, ProcessSpec, load_graph
from dronewrapper_compose.launcher import Launcher, build_argv


def graph_argvs(
    name: str, *, router: str = DEFAULT_ROUTER, variables: Mapping[str, str] | None = None
) -> list[tuple[ProcessSpec, list[str]]]:
    """Each process of graph ``name`` (under ``compose/``) with its resolved argv, in order."""
    path = REPO / "compose" / f"{name}.yaml"
    launcher = Launcher(load_graph(path), path, router=router, variables=variables)
    return [
        (spec, build_argv(spec, launcher.values, path, launcher.ns, launcher.router)[0])
        for spec in launcher.graph.processes
    ]


def config_args(argv: list[str]) -> tuple[str | None, list[str]]:
    """The ``--config`` file (None without one) and every ``--set KEY=VALUE`` of ``argv``."""
    config, sets = None, []
    for flag, value in itertools.pairwise(argv):
        if flag == "--config":
            config = value
        elif flag == "--set":
            sets.append(value)
    return config, sets
