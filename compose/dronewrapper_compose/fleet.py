"""The drones of a fleet graph: how many, of which kind, under which namespaces (pure).

A fleet graph (``compose/sim_fleet.yaml``) declares the variables ``drones`` (a count) and
``kind`` (``iris``, ``tello``, or a comma-separated list cycled over the drones:
``iris,tello`` makes drone1 an Iris, drone2 a Tello, drone3 an Iris ...). A process marked
``each_drone: KIND`` runs once per drone of that kind (``any``: every drone), under the
drone's namespace, with these variables of its own:

=============  ==========================================================================
``i``          the drone's number, 1..N
``ns``         its namespace, ``{prefix}{i}`` (``drone1`` ...; ``prefix`` is the graph's
               ``ns_prefix`` variable, ``drone`` by default)
``kind``       its kind
``drone_port`` a UDP port free on this machine, one per drone (its autopilot link; outside
               the ephemeral range, see ``ports.free_fixed_port``)
``address``    the drone's own address, from the ``addresses`` list ("" without one)
``local``      this machine's address for that drone, from ``local_addresses`` (else
               ``0.0.0.0``: every address, enough for one Tello)
=============  ==========================================================================

A classroom graph (``compose/classroom_tello.yaml``) lists its aircraft instead of counting
them: ``addresses`` (comma-separated: one per Tello, in station mode on one access point) sets
the number of drones, and ``local_addresses`` (as many, or empty) the address on this machine
each drone's bridge binds, since a Tello sends its state and video to the address that
commanded it.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

KINDS = ("iris", "tello")
"""The simulated aircraft a fleet can hold."""
ANY = "any"
"""``each_drone: any`` runs a process for every drone, whatever its kind."""
ANY_ADDRESS = "0.0.0.0"
"""A bridge's local address when none is listed: every address of this machine."""
MAX_DRONES = 200
"""More drones than this is a typo, not a fleet (each is a few processes)."""
SIM_MODULE = "dronewrapper_sim"
"""The module of a simulated aircraft's process (one per drone)."""
CORE_SHARE_PER_DRONE = 0.065
"""The share of one core a simulated drone takes while flying: its sim (3.3 %), its bridge
(2.7 %) and its part of the router (0.5 %), measured by ``bench.fleet`` (docs/fleet.md)."""
BUSY_LIMIT = 0.9
"""The share of the machine's cores a fleet may take before poses arrive late (``bench.fleet``
calls 90 % busy the knee)."""


class FleetError(ValueError):
    """The fleet's variables are wrong; the message names the variable."""


@dataclass(frozen=True)
class FleetDrone:
    """One drone of a fleet graph and the variables its processes see."""

    i: int
    ns: str
    kind: str
    values: dict[str, str] = field(default_factory=dict, compare=False)


def split_list(text: str) -> list[str]:
    """``a, b,c`` -> ``["a", "b", "c"]`` (empty parts dropped)."""
    return [part.strip() for part in str(text).split(",") if part.strip()]


def parse_kinds(text: str) -> list[str]:
    """``iris`` / ``tello`` / ``iris,tello,...`` -> the list of kinds, checked."""
    kinds = split_list(text)
    if not kinds:
        raise FleetError("kind: give iris, tello, or a list such as iris,tello")
    for kind in kinds:
        if kind not in KINDS:
            raise FleetError(f"kind: unknown aircraft {kind!r} (known: {', '.join(KINDS)})")
    return kinds


def plan_fleet(values: Mapping[str, str], free_udp_port: Callable[[], int]) -> list[FleetDrone]:
    """The drones that the variables ``drones`` (or ``addresses``), ``kind``,
    ``local_addresses`` and ``ns_prefix`` describe.

    Raises:
        FleetError: ``drones`` is not a whole number 1..MAX_DRONES, ``kind`` names an
            aircraft that is not simulated, an address is listed twice, or
            ``local_addresses`` does not give one per address.
    """
    addresses = split_list(values.get("addresses", ""))
    locals_ = split_list(values.get("local_addresses", ""))
    if locals_ and len(locals_) != len(addresses):
        raise FleetError(
            f"local_addresses: {len(locals_)} given for {len(addresses)} addresses (one each)"
        )
    if len(set(addresses)) != len(addresses):
        raise FleetError(f"addresses: listed twice: {', '.join(addresses)}")
    count_text = str(len(addresses)) if addresses else str(values.get("drones", "")).strip()
    if not count_text.isdigit() or not 1 <= int(count_text) <= MAX_DRONES:
        raise FleetError(f"drones={count_text!r} must be a whole number 1..{MAX_DRONES}")
    kinds = parse_kinds(str(values.get("kind", KINDS[0])))
    prefix = str(values.get("ns_prefix", "drone"))
    drones = []
    for i in range(1, int(count_text) + 1):
        ns, kind = f"{prefix}{i}", kinds[(i - 1) % len(kinds)]
        own = {
            "i": str(i),
            "ns": ns,
            "kind": kind,
            "drone_port": str(free_udp_port()),
            "address": addresses[i - 1] if addresses else "",
            "local": locals_[i - 1] if locals_ else ANY_ADDRESS,
        }
        drones.append(FleetDrone(i, ns, kind, own))
    return drones


def load_warning(drones: int, cores: int) -> str | None:
    """What to tell a user who asks for ``drones`` simulated drones on ``cores`` cores, or
    None when the cores carry them (:data:`CORE_SHARE_PER_DRONE`, :data:`BUSY_LIMIT`)."""
    carried = int(cores * BUSY_LIMIT / CORE_SHARE_PER_DRONE)
    if drones <= carried:
        return None
    return (
        f"{drones} simulated drones take about {drones * CORE_SHARE_PER_DRONE:.1f} cores "
        f"({CORE_SHARE_PER_DRONE:.1%} of one core each, docs/fleet.md); the {cores} cores of "
        f"this machine carry about {carried} before they are {BUSY_LIMIT:.0%} busy: expect "
        "late poses and slow or failed starts"
    )


def drones_of(drones: list[FleetDrone], kind: str) -> list[FleetDrone]:
    """The drones a process marked ``each_drone: kind`` runs for."""
    return [d for d in drones if kind in (ANY, d.kind)]
