"""Services sharing a process: a fleet's ``per_process``, and a process ``beside`` another.

With ``per_process`` = N > 1 the ``each_drone`` processes of N drones (their sims and bridges)
run in one process, :mod:`dronewrapper.runtime.host`, each on a Node of its own over one Zenoh
session. ``per_process=1`` (the default) keeps a process per drone and per program: a crash
then takes down one program of one drone; a host costs less memory (one interpreter and one
copy of the imported modules for N drones) and a process that dies takes its N drones' sims
and bridges with it (see the host's docstring for what one member's exception takes down).

A process with ``beside: NAME`` runs in the process of the earlier process ``NAME``: a ROS 2
gateway beside its drone's bridge (``compose/sim_iris_ros2_hosted.yaml``), on the bridge's
Zenoh session, so the bridge's telemetry reaches it on the putting thread. Both stay services
of their own (``run(node, config)`` each, their own configs and liveliness tokens); neither
imports the other.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import NamedTuple

from dronewrapper_compose.graph import GraphError, ProcessSpec

HOST_MODULE = "dronewrapper.runtime.host"


class Instance(NamedTuple):
    """One process to start: a spec under a namespace, with its variables; ``label`` names it
    in the output (``sim``, or ``drone2/sim`` for a fleet's). A host process (``per_process``)
    lists the instances it runs in ``members``."""

    spec: ProcessSpec
    label: str
    ns: str
    values: Mapping[str, str]
    members: tuple = ()

    def tokens(self) -> list[tuple[str, str]]:
        """The liveliness tokens (namespace, name) that say it is ready."""
        hosted = self.members or (self,)
        return [(m.ns, m.spec.name) for m in hosted if m.spec.ready == "alive"]


def per_process(values: Mapping[str, str], where: Path) -> int:
    """The graph variable ``per_process``: drones whose processes share one process (1: a
    process each).

    Raises:
        GraphError: it is not a whole number >= 1.
    """
    text = str(values.get("per_process", "1")).strip()
    if not text.isdigit() or int(text) < 1:
        raise GraphError(f"{where}: per_process={text!r} must be a whole number >= 1")
    return int(text)


def host_instances(instances: list[Instance], drones: list[str], size: int) -> list[Instance]:
    """The ``each_drone`` instances of ``drones`` packed ``size`` drones to a host process, each
    host's members in the graph's order (every sim, then every bridge)."""
    hosts = []
    for at in range(0, len(drones), size):
        chunk = drones[at : at + size]
        members = tuple(inst for inst in instances if inst.ns in chunk)
        if not members:
            continue
        if any(m.spec.module is None for m in members):
            raise GraphError("per_process hosts modules only (python -m), not commands")
        label = chunk[0] if len(chunk) == 1 else f"{chunk[0]}-{chunk[-1]}"
        hosts.append(Instance(host_spec(members), f"{label}/host", "", {}, members))
    return hosts


def host_spec(members: tuple[Instance, ...]) -> ProcessSpec:
    """The spec of the one process that runs ``members`` (:data:`HOST_MODULE`)."""
    return ProcessSpec(
        name="host",
        module=HOST_MODULE,
        zenoh_args=False,
        ready_timeout_s=max(m.spec.ready_timeout_s for m in members) + 2.0 * len(members),
        stop_timeout_s=max(m.spec.stop_timeout_s for m in members) + 5.0,
    )


def join_beside(groups: list[list[Instance]]) -> list[list[Instance]]:
    """``groups`` with each ``beside`` process moved into the process of the one it names: one
    host process, started where that one was, its members in the graph's order (the graph
    file checked that the name is an earlier process's, run once)."""
    joined: list[list[Instance]] = []
    where: dict[str, tuple[int, int]] = {}  # process name -> (group, place) in joined
    for group in groups:
        beside = group[0].spec.beside
        if beside is None:
            where.update({inst.spec.name: (len(joined), j) for j, inst in enumerate(group)})
            joined.append(list(group))
            continue
        g, j = where[beside]
        members = (*(joined[g][j].members or (joined[g][j],)), *group)
        label = "+".join(m.label for m in members)
        joined[g][j] = Instance(host_spec(members), label, members[0].ns, {}, members)
    return joined
