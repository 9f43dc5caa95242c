"""The launcher: ``dronewrapper up compose/GRAPH.yaml`` runs a process graph on this machine.

It starts a Zenoh router (a router-mode session in this process) on ``--router``, then each
process in order, waiting for its liveliness token ``{ns}/alive/{name}`` before starting the next.
Every line a process prints is prefixed with its name. A fleet graph's ``each_drone`` process
runs once per drone (``drone1/sim``, ``drone2/sim`` ...), all of them started together and
waited for together (:mod:`dronewrapper_compose.fleet`); with the graph variable
``per_process`` = N > 1 the ``each_drone`` processes of N drones share one process
(:mod:`dronewrapper.runtime.host`: ``drone1-drone5/host`` holds their sims and bridges),
which costs less memory than a process each and isolates less. On Ctrl-C, SIGTERM or after
``--duration`` it stops the processes in reverse order (SIGINT, then SIGKILL after a grace
period) and closes the router. Exit status: 0 when every process started and stopped cleanly,
1 when a process died or failed to become ready, 2 for a bad graph file or bad flags.

A process's whole life in a graph (start in order, readiness, ordered stop, exit status) is
here; one running process and its prefixed output is ``child.py``, the graph file's schema
``graph.py``, its ports ``ports.py``.
"""

from __future__ import annotations

import signal
import sys
import threading
import time
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TextIO

import zenoh

from dronewrapper.msgs.registry import ALIVE
from dronewrapper.router import router_options
from dronewrapper.router_reach import open_client_session
from dronewrapper.runtime.host import SEPARATOR
from dronewrapper.runtime.node import open_session
from dronewrapper.runtime.options import DEFAULT_ROUTER, ZenohOptions
from dronewrapper.runtime.shm import remove_stale_segments
from dronewrapper.security.keystore import default_keys_dir
from dronewrapper_compose import fleet, hosting
from dronewrapper_compose.child import Child
from dronewrapper_compose.graph import (
    REPO,
    Graph,
    GraphError,
    ProcessSpec,
    assets_dir,
    check_value,
    load_graph,
    resolve_graph_path,
    substitute,
)
from dronewrapper_compose.hosting import HOST_MODULE, Instance, host_instances, per_process
from dronewrapper_compose.ports import (
    PortInUse,
    check_ports_free,
    choose_ports,
    free_fixed_port,
    router_port_in_use,
)


class LaunchError(RuntimeError):
    """A process failed to start or become ready."""


def build_argv(
    spec: ProcessSpec, values: Mapping[str, str], graph_path: Path, ns: str, router: str
) -> tuple[list[str], dict[str, str]]:
    """The argv and extra environment of one process, with variables substituted."""
    where = f"{graph_path}: process {spec.name!r}"
    if spec.module is not None:
        argv = [sys.executable, "-m", substitute(spec.module, values, where)]
    else:
        argv = [substitute(part, values, where) for part in spec.command or []]
    if spec.config is not None:
        config = Path(substitute(spec.config, values, where))
        if not config.is_absolute():
            config = (graph_path.parent / config).resolve()
        if not config.exists():
            raise GraphError(f"{where}: config file {config} does not exist")
        argv += ["--config", str(config)]
    for key, value in spec.set.items():
        argv += ["--set", f"{key}={substitute(str(value), values, where)}"]
    argv += [substitute(arg, values, where) for arg in spec.args]
    if spec.zenoh_args:
        argv += ["--connect", router, "--namespace", ns, "--name", spec.name, "--mode", "peer"]
    env = {key: substitute(value, values, where) for key, value in spec.env.items()}
    return argv, env


class Launcher:
    """Runs one graph: ``start()`` brings it up, ``wait()`` supervises, ``stop()`` tears down.

    Use as a context manager from Python (the demo and the scenario tests do)::

        with Launcher.from_file("compose/sim_iris.yaml", router=endpoint) as graph:
            graph.wait(duration=30)
        assert graph.exit_code == 0
    """

    def __init__(
        self,
        graph: Graph,
        graph_path: Path,
        *,
        router: str = DEFAULT_ROUTER,
        start_router: bool = True,
        variables: Mapping[str, str] | None = None,
        namespace: str | None = None,
        out: TextIO | None = None,
        listen: Sequence[str] = (),
        connect: Sequence[str] = (),
        identity: str = "",
        keys_dir: str = "",
        insecure: bool = False,
    ) -> None:
        self.graph = graph
        # the router's endpoints for other machines (tls/ with the drone's identity); the
        # graph's own processes always use ``router``
        self.listen = list(listen)
        self.connect = list(connect)  # other routers this one joins (a relay, another field)
        self.identity = identity
        self.keys_dir = keys_dir
        self.insecure = insecure
        self.graph_path = graph_path
        self.router = router
        self.start_router = start_router
        self.ns = namespace or graph.namespace
        self.out = out or sys.stdout
        self.values = {
            **graph.vars,
            **(variables or {}),
            "ns": self.ns,
            "router": router,
            "repo": str(REPO),
            "graph_dir": str(graph_path.parent.resolve()),
            "assets": str(assets_dir()),
            "python": sys.executable,
            "keys": keys_dir or str(default_keys_dir()),
        }
        try:
            self.values.update(choose_ports(graph.ports, self.values))
        except ValueError as exc:
            raise GraphError(f"{graph_path}: {exc}") from exc
        for name in graph.types:
            if why := check_value(graph, name, self.values[name]):
                raise GraphError(f"{graph_path}: {name}={self.values[name]!r} {why}")
        self.drones: list[fleet.FleetDrone] = []
        if any(spec.each_drone for spec in graph.processes):
            try:
                self.drones = fleet.plan_fleet(self.values, free_fixed_port)
            except fleet.FleetError as exc:
                raise GraphError(f"{graph_path}: {exc}") from exc
        self.groups = self.plan()
        self.namespaces = sorted(
            {ns for group in self.groups for inst in group for ns, _ in inst.tokens()}
            | {inst.ns for group in self.groups for inst in group if inst.ns}
        )
        self.children: list[Child] = []
        self._started: list[list[Child]] = []  # the children, in the groups they started in
        self.failures: list[str] = []
        self.exit_code: int | None = None
        self._alive: set[tuple[str, str]] = set()  # (namespace, service)
        self._alive_cond = threading.Condition()
        self._out_lock = threading.Lock()
        self._session: zenoh.Session | None = None
        self._token_sub: zenoh.Subscriber[None] | None = None
        self._width = max(len(inst.label) for group in self.groups for inst in group)

    def plan(self) -> list[list[Instance]]:
        """The processes to start, in groups started together: a group per spec, of one
        instance, or one per drone (``each_drone``); ``per_process`` > 1 and ``beside`` make
        host processes in their place (:mod:`~dronewrapper_compose.hosting`)."""
        size = per_process(self.values, self.graph_path)
        groups: list[list[Instance]] = []
        hosted: list[Instance] = []
        hosts_at = None
        for spec in self.graph.processes:
            if spec.each_drone is None:
                groups.append([Instance(spec, spec.name, self.ns, self.values)])
                continue
            drones = fleet.drones_of(self.drones, spec.each_drone)
            group = [
                Instance(spec, f"{d.ns}/{spec.name}", d.ns, {**self.values, **d.values})
                for d in drones
            ]
            if size == 1:
                groups.append(group)
                continue
            if hosts_at is None:  # the hosts start where the first each_drone process did
                hosts_at = len(groups)
                groups.append([])
            hosted += group
        if hosts_at is not None:
            try:
                groups[hosts_at] = host_instances(hosted, [d.ns for d in self.drones], size)
            except GraphError as exc:
                raise GraphError(f"{self.graph_path}: {exc}") from exc
        return hosting.join_beside([group for group in groups if group])

    def argv_of(self, inst: Instance) -> tuple[list[str], dict[str, str]]:
        """The argv and extra environment of one instance (a host's: its members' argvs,
        without the interpreter, one after the other)."""
        if not inst.members:
            return build_argv(inst.spec, inst.values, self.graph_path, inst.ns, self.router)
        argv, env = [sys.executable, "-m", HOST_MODULE], {}
        for i, member in enumerate(inst.members):
            member_argv, member_env = self.argv_of(member)
            argv += ([SEPARATOR] if i else []) + member_argv[1:]
            env.update(member_env)
        return argv, env

    @classmethod
    def from_file(cls, path: str | Path, **kwargs) -> Launcher:
        """A launcher for the graph at ``path`` (or a bare name in compose/)."""
        resolved = resolve_graph_path(str(path))
        return cls(load_graph(resolved), resolved, **kwargs)

    # ---- bring-up ----

    def __enter__(self) -> Launcher:
        try:
            self.start()
        except BaseException:
            self.stop()
            raise
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop()

    def _say(self, text: str) -> None:
        with self._out_lock:
            self.out.write(f"{'launcher':>{self._width}} | {text}\n")
            self.out.flush()

    def _on_token(self, sample: zenoh.Sample) -> None:
        match = ALIVE.match(str(sample.key_expr))
        if match is None or match["ns"] not in self.namespaces:
            return
        with self._alive_cond:
            if sample.kind == zenoh.SampleKind.PUT:
                self._alive.add((match["ns"], match["service"]))
            else:
                self._alive.discard((match["ns"], match["service"]))
            self._alive_cond.notify_all()

    def start(self) -> None:
        """Start the router and every process in order, each ready before the next.

        Raises:
            LaunchError: a process exited or did not become ready in time.
            GraphError: a variable or config path in the graph is wrong.
        """
        try:
            check_ports_free(self.graph.ports, self.values)
        except PortInUse as exc:
            raise LaunchError(f"{self.graph_path.name}: {exc}") from exc
        if self.start_router and (taken := router_port_in_use(self.router)) is not None:
            raise LaunchError(
                f"router endpoint {self.router}: TCP port {taken} is already in use (another "
                f"graph's router?); pick another with --router tcp/127.0.0.1:N, or join the "
                f"running one with --use-router"
            )
        for var in self.graph.ports:
            self._say(f"{var} = {self.values[var]}")
        if self.start_router:
            options = router_options(
                [self.router, *self.listen],
                self.connect,
                identity=self.identity,
                keys_dir=self.keys_dir,
                insecure=self.insecure,
                acl_namespaces=self.namespaces,
            )
            options.namespace = self.ns
        else:
            options = ZenohOptions(mode="client", connect=[self.router], namespace=self.ns)
        self._session = (open_session if self.start_router else open_client_session)(options)
        where = ", ".join([self.router, *self.listen]) if self.start_router else self.router
        acl = " (access control on)" if options.access_control else ""
        if self.start_router and self.connect:
            where += f"; joining {', '.join(self.connect)}"
        self._say(f"{'router listening on' if self.start_router else 'using router'} {where}{acl}")
        watched = self.namespaces[0] if len(self.namespaces) == 1 else "*"
        self._token_sub = self._session.liveliness().declare_subscriber(
            ALIVE.wildcard(watched), self._on_token, history=True
        )
        plans = [[(inst, *self.argv_of(inst)) for inst in group] for group in self.groups]
        for group in plans:
            started: list[Child] = []
            self._started.append(started)
            for inst, argv, env in group:
                shown = " ".join(argv[1:] if inst.spec.module else argv)
                self._say(f"starting {inst.label}: {shown}")
                child = Child(
                    inst.spec,
                    argv,
                    env,
                    self.out,
                    self._out_lock,
                    self._width,
                    label=inst.label,
                    ns=inst.ns,
                    tokens=inst.tokens(),
                )
                self.children.append(child)
                started.append(child)
            for child in started:
                self._wait_ready(child)

    def _wait_ready(self, child: Child) -> None:
        if child.spec.ready == "none":
            return
        deadline = time.monotonic() + child.spec.ready_timeout_s
        started = time.monotonic()
        with self._alive_cond:
            while not set(child.tokens) <= self._alive:
                code = child.poll()
                if code is not None:
                    raise LaunchError(f"{child.name} exited with code {code} before it was ready")
                remaining = deadline - time.monotonic()
                if remaining <= 0:
                    missing = sorted(set(child.tokens) - self._alive)
                    keys = ", ".join(ALIVE.key(ns, service=name) for ns, name in missing)
                    raise LaunchError(
                        f"{child.name} not ready after {child.spec.ready_timeout_s:g} s "
                        f"(no liveliness token {keys})"
                    )
                self._alive_cond.wait(min(remaining, 0.2))
        self._say(f"{child.name} ready in {time.monotonic() - started:.1f} s")

    # ---- supervision and shutdown ----

    def wait(self, duration: float | None = None, stop: threading.Event | None = None) -> int:
        """Supervise until ``stop`` is set, ``duration`` seconds pass, or a process dies."""
        stop = stop or threading.Event()
        deadline = time.monotonic() + duration if duration else None
        while not stop.wait(0.2):
            for child in self.children:
                code = child.poll()
                if code is not None and not child.stopping:
                    self.failures.append(f"{child.name} exited unexpectedly with code {code}")
                    self._say(self.failures[-1])
                    return self.stop()
            if deadline is not None and time.monotonic() >= deadline:
                self._say(f"duration of {duration:g} s reached")
                break
        return self.stop()

    def _reap(self, child: Child) -> None:
        """Wait for an interrupted child (SIGKILL after its grace period); note failures."""
        if child.proc.returncode is None:
            grace = child.spec.stop_timeout_s
            code = child.wait(grace)
            if code is None:
                self.failures.append(f"{child.name} ignored SIGINT for {grace:g} s")
                self._say(self.failures[-1] + "; killing it")
                child.kill()
        code = child.proc.returncode
        if child.stopping and code not in (0, -signal.SIGINT):
            self.failures.append(f"{child.name} exited with code {code} when stopped")
        child.join_output()

    def stop(self) -> int:
        """Stop every process in reverse order, close the router; the graph's exit status."""
        if self.exit_code is not None:
            return self.exit_code
        for group in reversed(self._started):  # a group stops together, as it started
            for child in group:
                if child.poll() is None:
                    child.interrupt()
            for child in group:
                self._reap(child)
        if self._token_sub is not None:
            self._token_sub.undeclare()
        if self._session is not None:
            self._session.close()
        remove_stale_segments()
        self.exit_code = 1 if self.failures else 0
        self._say(
            "stopped" if not self.failures else "stopped with failures: " + "; ".join(self.failures)
        )
        return self.exit_code
