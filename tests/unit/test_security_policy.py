"""Router refusals, the registry-generated access control, the command lease, the caller."""

from __future__ import annotations

import pytest

from dronewrapper.msgs import registry
from dronewrapper.router import InsecureEndpoint, check_endpoints, is_loopback, router_options
from dronewrapper.runtime import caller
from dronewrapper.security.acl import access_control, acl_rules
from dronewrapper_bridge_base.commander_lease import CommanderLease


@pytest.mark.parametrize(
    ("endpoint", "loopback"),
    [
        ("tcp/127.0.0.1:7447", True),
        ("tcp/localhost:7447", True),
        ("tcp/[::1]:7447", True),
        ("tcp/0.0.0.0:7447", False),
        ("tcp/192.168.1.50:7447", False),
        ("tcp/drone.local:7447", False),
    ],
)
def test_loopback(endpoint, loopback):
    assert is_loopback(endpoint) is loopback


def test_plain_tcp_off_loopback_is_refused_and_says_why():
    with pytest.raises(InsecureEndpoint, match=r"tls/.*--insecure"):
        router_options(["tcp/0.0.0.0:7447"])
    check_endpoints(["tcp/0.0.0.0:7447"], identity="", insecure=True)
    check_endpoints(["tcp/127.0.0.1:7447"], identity="", insecure=False)
    with pytest.raises(InsecureEndpoint, match="identity"):
        check_endpoints(["tls/0.0.0.0:7447"], identity="", insecure=False)


def _allowed(rules, message, flow):
    keys = set()
    for rule in rules:
        if message in rule["messages"] and flow in rule["flows"]:
            keys.update(rule["key_exprs"])
    return keys


def test_rules_follow_the_registry():
    rules = acl_rules(["drone"])
    setpoint = registry.SETPOINT_RAW_LOCAL.key("drone")
    state = registry.STATE.key("drone")
    arming = registry.ARMING.key("drone")
    assert setpoint in _allowed(rules["operator"], "put", "ingress")
    # a client publisher sends only while it sees a subscriber: the operator must see them
    assert setpoint in _allowed(rules["operator"], "declare_subscriber", "egress")
    assert state not in _allowed(rules["operator"], "put", "ingress")
    assert arming in _allowed(rules["operator"], "query", "ingress")
    assert state in _allowed(rules["drone"], "put", "ingress")
    assert arming in _allowed(rules["drone"], "declare_queryable", "ingress")
    assert arming not in _allowed(rules["operator"], "declare_queryable", "ingress")
    # observers only watch: no put, no query, no queryable, no token
    for message in ("put", "delete", "query", "declare_queryable", "liveliness_token"):
        assert not _allowed(rules["observer"], message, "ingress"), message
    assert state in _allowed(rules["observer"], "declare_subscriber", "ingress")
    every_service = {s.key("drone") for s in registry.SERVICES.values()}
    assert every_service <= _allowed(rules["operator"], "query", "ingress")


def test_a_relay_forwards_what_the_drone_and_the_operator_may_send():
    """A router between the field and the ground carries telemetry one way and setpoints and
    calls the other: its rules are the drone's and the operator's, and nothing more."""
    rules = acl_rules(["drone"])
    ids = lambda role: {r["id"] for r in rules[role]}  # noqa: E731
    assert ids("relay") == ids("drone") | ids("operator")
    for message, flow in (
        ("put", "ingress"),
        ("query", "ingress"),
        ("declare_queryable", "ingress"),
    ):
        assert _allowed(rules["relay"], message, flow) == (
            _allowed(rules["drone"], message, flow) | _allowed(rules["operator"], message, flow)
        )
    acl = access_control({"drone": ["field"], "operator": ["ground"], "relay": ["link"]})
    policies = {p["id"]: p for p in acl["policies"]}
    assert set(policies["role_relay"]["rules"]) == {f"relay_{i}" for i in ids("relay")}


def test_policy_is_deny_by_default_and_binds_names():
    acl = access_control({"drone": ["drone1"], "operator": ["alice", "carol"], "observer": []})
    assert acl["enabled"] and acl["default_permission"] == "deny"
    subjects = {s["id"]: s for s in acl["subjects"]}
    assert subjects["role_operator"]["cert_common_names"] == ["alice", "carol"]
    assert "role_observer" not in subjects  # an empty name list is not a valid subject
    rule_ids = {r["id"] for r in acl["rules"]}
    for policy in acl["policies"]:
        assert set(policy["rules"]) <= rule_ids and policy["subjects"]


def test_lease_one_commander_at_a_time():
    lease = CommanderLease(ttl_s=5.0)
    assert lease.admit("alice", 0.0).event == "acquired"
    assert lease.admit("alice", 1.0).accepted
    refused = lease.admit("carol", 2.0)
    assert not refused.accepted and refused.holder == "alice"
    assert "take it over" in refused.reason("carol")
    taken = lease.take_over("carol", 3.0)
    assert (taken.event, taken.previous) == ("taken_over", "alice")
    assert not lease.admit("alice", 3.5).accepted
    assert lease.admit("carol", 4.0).accepted
    # silent for ttl: the lease lapses and the next commander gets it
    assert lease.current(9.1) == ""
    lapsed = lease.admit("alice", 9.1)
    assert lapsed.accepted and lapsed.event == "expired" and lapsed.previous == "carol"
    assert not lease.release("carol", 9.2).accepted
    assert lease.release("alice", 9.3).event == "released"
    assert lease.current(9.4) == ""
    with pytest.raises(ValueError):
        CommanderLease(ttl_s=0)


def test_caller_attachment_round_trip():
    assert caller.commander_of(caller.commander_attachment("alice")) == "alice"
    assert caller.commander_of(None) == "" and caller.commander_of(b"other") == ""
    with caller.handling(caller.commander_attachment("carol")):
        assert caller.current_commander() == "carol"
    assert caller.current_commander() == ""
