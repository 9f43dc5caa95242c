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
  every service (arm, take off, land, modes, parameters, the command lease);
- ``observer``: nothing more;
- ``relay``: a router between the field and the ground (a radio's base station, a cloud
  relay) forwards what both ends may send, so it gets the ``drone`` and the ``operator`` rules;
  each end's router checks the certificates of the processes that connect to it.

Processes on the drone itself connect on loopback (``lo``); loopback links get the drone and
operator rules (the machine is trusted as a whole; remote links must show a certificate).
"""

from __future__ import annotations

from typing import Any

from dronewrapper.msgs import registry

LOOPBACK_INTERFACES = ("lo",)

# registry process name -> security role (a process not listed runs on the drone)
PROCESS_ROLES = {"sdk": "operator", "teleop": "operator", "tests": "operator", "gcs": "operator"}

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


def acl_rules(namespaces: list[str]) -> dict[str, list[dict[str, Any]]]:
    """Role -> the allow rules it gets, for vehicles in ``namespaces`` (``["*"]``: all)."""
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
    drone = [
        _rule("drone_publish", ["put", "delete"], ["ingress"], drone_pub),
        _rule("drone_serve", ["declare_queryable", "reply"], ["ingress"], services),
        _rule("drone_queried", ["query"], ["egress"], services),
        _rule("drone_alive", ["liveliness_token"], ["ingress"], alive),
        _rule("drone_subscribed", SUBSCRIBE, ["egress"], drone_pub),
    ]
    operator = [
        _rule("operator_publish", ["put", "delete"], ["ingress"], operator_pub),
        # a client publisher sends only while it knows of a subscriber: let it see them
        _rule("operator_subscribed", SUBSCRIBE, ["egress"], operator_pub),
        _rule("operator_call", ["query"], ["ingress"], services),
        _rule("operator_replies", ["reply"], ["egress"], services),
        _rule("operator_servers", ["declare_queryable"], ["egress"], services),
    ]
    return {
        "observer": watch,
        "operator": watch + operator,
        "drone": watch + drone,
        "relay": watch + drone + operator,
    }


def access_control(
    names_by_role: dict[str, list[str]], namespaces: list[str] | None = None
) -> dict[str, Any]:
    """The Zenoh ``access_control`` config: deny by default, the registry's rules per role.

    Args:
        names_by_role: role -> certificate common names (``KeyStore.names_by_role()``).
        namespaces: vehicle namespaces the policy covers (default every one: ``*``).
    """
    by_role = acl_rules(list(namespaces or ["*"]))
    rules: list[dict[str, Any]] = []
    for role, role_rules in by_role.items():
        for rule in role_rules:
            rules.append({**rule, "id": f"{role}_{rule['id']}"})
    subjects: list[dict[str, Any]] = [{"id": "loopback", "interfaces": list(LOOPBACK_INTERFACES)}]
    policies: list[dict[str, Any]] = [
        {
            "id": "loopback",
            "rules": sorted({f"{r}_{x['id']}" for r in ("drone", "operator") for x in by_role[r]}),
            "subjects": ["loopback"],
        }
    ]
    for role, names in names_by_role.items():
        if role not in by_role:
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
    return {
        "enabled": True,
        "default_permission": "deny",
        "rules": rules,
        "subjects": subjects,
        "policies": policies,
    }
