"""Zenoh access control for a drone's router, generated from the message registry.

Nobody writes the policy by hand: each registry topic names the processes that publish it and
each service the process that serves it (``Topic.publishers``, ``Service.server``), and
:data:`PROCESS_ROLES` says which security role each process runs as. Roles are bound to
certificate common names from the key store (``index.json``: valid, not revoked, not expired).

What each role may do, per namespace, everything else denied (``default_permission: deny``):

- every role (``drone``, ``operator``, ``observer``, ``relay``): subscribe to every registry
  topic and see who is alive (liveliness queries and subscribers);
- ``drone``: publish the topics its processes publish (telemetry, images, detections), declare
  the services' queryables and answer them, hold ``{ns}/alive/*`` tokens;
- ``operator``: publish the topics an SDK app publishes (setpoints, world teleop) and call
  every service (arm, take off, land, modes, parameters, the command lease), each **only on
  keys bound to its own certificate name** (``KEY/@by/NAME``, see
  :mod:`dronewrapper.runtime.caller`): the bridge takes the commander from that key, so an
  operator cannot command in another's name;
- ``observer``: nothing more;
- ``relay``: a router between the field and the ground (a radio's base station, a cloud
  relay) forwards what both ends may send, so it gets the ``drone`` and the ``operator`` rules
  for any name; each end's router checks the certificates of the processes that connect to it.

Only **plain** links on loopback (``tcp``/``udp`` on interface ``lo``: the drone's own
processes) get the drone's and the operator's rules without a certificate. A link that carries
a certificate (``tls``, ``quic``) gets its certificate's role whatever the interface, so a TLS
listener on 127.0.0.1, an ``ssh -L`` tunnel, a VPN or a reverse proxy ending on the drone gives
no more than the certificate does. Zenoh combines a subject's properties with *and*: the local
subject is ``interfaces: [lo]`` and ``link_protocols: [tcp, udp]``.
"""

from __future__ import annotations

from typing import Any

from dronewrapper.msgs import registry
from dronewrapper.runtime import caller

LOOPBACK_INTERFACES = ("lo",)
LOCAL_PROTOCOLS = ("tcp", "udp")
"""Link protocols trusted on loopback: plain ones, which carry no certificate."""

# registry process name -> security role (a process not listed runs on the drone); the ROS 2
# gateway commands for the ROS 2 programs it presents the drone to: an operator's part
PROCESS_ROLES = {
    "sdk": "operator",
    "teleop": "operator",
    "tests": "operator",
    "gcs": "operator",
    "ros2_gateway": "operator",
}

SUBSCRIBE = ["declare_subscriber"]
LIVELINESS_WATCH = ["liveliness_query", "declare_liveliness_subscriber"]


def role_of(process: str) -> str:
    """The security role a registry process (``bridge``, ``sdk`` ...) runs as."""
    return PROCESS_ROLES.get(process, "drone")


def _keys(templates: list[Any], namespaces: list[str]) -> list[str]:
    out: list[str] = []
    for template in templates:
        for ns in namespaces:
            key = template.wildcard(ns) if "{ns}" in template.template else template.wildcard()
            if key not in out:
                out.append(key)
    return out


def _rule(rule_id: str, messages: list[str], flows: list[str], keys: list[str]) -> dict[str, Any]:
    return {
        "id": rule_id,
        "messages": messages,
        "flows": flows,
        "permission": "allow",
        "key_exprs": keys,
    }


def published_by(role: str) -> list[registry.Topic[Any]]:
    """Registry topics some process of ``role`` publishes."""
    return [t for t in registry.TOPICS.values() if any(role_of(p) == role for p in t.publishers)]


def is_commanded(topic: registry.Topic[Any]) -> bool:
    """True if an operator's process publishes ``topic`` (a setpoint, world teleop): a topic
    its sender commands with, bound to its certificate's name on a secure router."""
    return any(role_of(p) == "operator" for p in topic.publishers)


def commanding_key(topic: registry.Topic[Any], key: str, name: str) -> str:
    """``key`` bound to ``name`` when ``topic`` is one an operator commands with, else ``key``."""
    return caller.bound_key(key, name) if name and is_commanded(topic) else key


def _bound(keys: list[str], name: str = "") -> list[str]:
    """``keys`` bound to commander ``name`` (any commander when ``name`` is empty)."""
    return [caller.bound_key(k, name) if name else caller.any_bound(k) for k in keys]


def command_rule(namespaces: list[str], name: str) -> dict[str, Any]:
    """The rule letting certificate ``name`` put the commanding topics and query the services,
    only on keys bound to ``name`` (``KEY/@by/NAME``)."""
    keys = _keys(published_by("operator"), namespaces) + _keys(
        list(registry.SERVICES.values()), namespaces
    )
    return _rule(f"command_as_{name}", ["put", "delete", "query"], ["ingress"], _bound(keys, name))


def acl_rules(namespaces: list[str]) -> dict[str, list[dict[str, Any]]]:
    """Role -> the allow rules it gets, for vehicles in ``namespaces`` (``["*"]``: all); the
    pseudo-role ``local`` is what plain loopback links get. An operator's own commands are
    allowed by :func:`command_rule`, one per certificate name."""
    topics = _keys(list(registry.TOPICS.values()), namespaces)
    services = _keys(list(registry.SERVICES.values()), namespaces)
    alive = _keys(list(registry.LIVELINESS.values()), namespaces)
    watch = [
        _rule("watch_topics", SUBSCRIBE, ["ingress"], topics),
        _rule("receive_topics", ["put", "delete"], ["egress"], topics),
        _rule("watch_alive", LIVELINESS_WATCH, ["ingress"], alive),
        _rule("receive_alive", ["liveliness_token", "reply"], ["egress"], alive),
    ]
    drone_pub = _keys(published_by("drone"), namespaces)
    operator_pub = _keys(published_by("operator"), namespaces)
    commands = _bound(operator_pub)  # the commanding topics, bound to any commander
    calls = services + _bound(services)
    drone = [
        _rule("drone_publish", ["put", "delete"], ["ingress"], drone_pub),
        _rule("drone_serve", ["declare_queryable", "reply"], ["ingress"], calls),
        _rule("drone_queried", ["query"], ["egress"], calls),
        _rule("drone_alive", ["liveliness_token"], ["ingress"], alive),
        _rule("drone_subscribed", SUBSCRIBE, ["egress"], drone_pub),
        _rule("drone_commanded", SUBSCRIBE, ["ingress"], commands),
        _rule("drone_receives_commands", ["put", "delete"], ["egress"], commands),
    ]
    operator = [
        # a client publisher sends only while it knows of a subscriber: let it see them
        _rule("operator_subscribed", SUBSCRIBE, ["egress"], operator_pub + commands),
        _rule("operator_replies", ["reply"], ["egress"], calls),
        _rule("operator_servers", ["declare_queryable"], ["egress"], calls),
    ]
    unbound = [  # commands on plain keys (the commander named by the attachment)
        _rule("command_unbound", ["put", "delete"], ["ingress"], operator_pub),
        _rule("call_unbound", ["query"], ["ingress"], services),
    ]
    forward = [  # commands bound to any name
        _rule("command_bound", ["put", "delete"], ["ingress"], commands),
        _rule("call_bound", ["query"], ["ingress"], _bound(services)),
    ]
    return {
        "observer": watch,
        "operator": watch + operator,
        "drone": watch + drone,
        "relay": watch + drone + operator + unbound + forward,
        "local": watch + drone + operator + unbound + forward,
    }


def access_control(
    names_by_role: dict[str, list[str]], namespaces: list[str] | None = None
) -> dict[str, Any]:
    """The Zenoh ``access_control`` config: deny by default, the registry's rules per role,
    each operator's commands bound to its name, and the local subject (plain loopback links).

    Args:
        names_by_role: role -> certificate common names (``KeyStore.names_by_role()``).
        namespaces: vehicle namespaces the policy covers (default every one: ``*``).
    """
    spaces = list(namespaces or ["*"])
    by_role = acl_rules(spaces)
    rules: list[dict[str, Any]] = []
    for role, role_rules in by_role.items():
        for rule in role_rules:
            rules.append({**rule, "id": f"{role}_{rule['id']}"})
    local = {
        "id": "local",
        "interfaces": list(LOOPBACK_INTERFACES),
        "link_protocols": list(LOCAL_PROTOCOLS),
    }
    subjects: list[dict[str, Any]] = [local]
    policies: list[dict[str, Any]] = [
        {
            "id": "local",
            "rules": [f"local_{r['id']}" for r in by_role["local"]],
            "subjects": ["local"],
        }
    ]
    for role, names in names_by_role.items():
        if role not in by_role or role == "local":
            raise ValueError(f"unknown role {role!r}")
        if not names:  # an empty list is not a valid subject property
            continue
        subjects.append({"id": f"role_{role}", "cert_common_names": sorted(names)})
        policies.append(
            {
                "id": f"role_{role}",
                "rules": [f"{role}_{r['id']}" for r in by_role[role]],
                "subjects": [f"role_{role}"],
            }
        )
        if role != "operator":
            continue
        for name in sorted(names):  # each operator commands in its own name only
            rule = command_rule(spaces, name)
            rules.append(rule)
            subjects.append({"id": f"cert_{name}", "cert_common_names": [name]})
            policies.append(
                {"id": f"cert_{name}", "rules": [rule["id"]], "subjects": [f"cert_{name}"]}
            )
    return {
        "enabled": True,
        "default_permission": "deny",
        "rules": rules,
        "subjects": subjects,
        "policies": policies,
    }
