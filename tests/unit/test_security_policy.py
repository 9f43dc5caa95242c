"""Router refusals, the registry-generated access control, the command lease, the caller."""

from __future__ import annotations

import pytest

from dronewrapper.msgs import registry
from dronewrapper.router import InsecureEndpoint, check_endpoints, is_loopback, router_options
from dronewrapper.runtime import caller
from dronewrapper.security.acl import access_control, acl_rules, command_rule
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
    # a certificate's commands travel on keys bound to its name only (command_rule)
    assert setpoint not in _allowed(rules["operator"], "put", "ingress")
    assert arming not in _allowed(rules["operator"], "query", "ingress")
    alice = [command_rule(["drone"], "alice")]
    assert _allowed(alice, "put", "ingress") >= {f"{setpoint}/@by/alice"}
    assert f"{arming}/@by/alice" in _allowed(alice, "query", "ingress")
    assert not any("carol" in k or k.endswith("/*") for k in _allowed(alice, "query", "ingress"))
    assert state not in {k.split("/@by/")[0] for k in _allowed(alice, "put", "ingress")}
    # a client publisher sends only while it sees a subscriber: the operator must see them
    assert setpoint in _allowed(rules["operator"], "declare_subscriber", "egress")
    assert f"{setpoint}/@by/*" in _allowed(rules["operator"], "declare_subscriber", "egress")
    assert state in _allowed(rules["drone"], "put", "ingress")
    assert arming in _allowed(rules["drone"], "declare_queryable", "ingress")
    assert f"{arming}/@by/*" in _allowed(rules["drone"], "declare_queryable", "ingress")
    assert arming not in _allowed(rules["operator"], "declare_queryable", "ingress")
    # observers only watch: no put, no query, no queryable, no token
    for message in ("put", "delete", "query", "declare_queryable", "liveliness_token"):
        assert not _allowed(rules["observer"], message, "ingress"), message
    assert state in _allowed(rules["observer"], "declare_subscriber", "ingress")
    every_service = {s.key("drone") for s in registry.SERVICES.values()}
    assert {f"{k}/@by/alice" for k in every_service} <= _allowed(alice, "query", "ingress")
    # the drone's own local processes command on plain keys (named by their attachment)
    assert every_service <= _allowed(rules["local"], "query", "ingress")
    assert setpoint in _allowed(rules["local"], "put", "ingress")


def test_only_plain_loopback_links_are_trusted_without_a_certificate():
    """A TLS link on loopback (a listener on 127.0.0.1, an ssh -L tunnel, a reverse proxy)
    gets its certificate's role: the local subject is interface lo *and* a plain protocol."""
    acl = access_control({"operator": ["alice"], "observer": ["olga"]})
    local = next(s for s in acl["subjects"] if s["id"] == "local")
    assert local["interfaces"] == ["lo"]
    assert local["link_protocols"] == ["tcp", "udp"]
    assert "tls" not in local["link_protocols"] and "quic" not in local["link_protocols"]
    # every subject that is not the local one names certificates
    for subject in acl["subjects"]:
        assert subject["id"] == "local" or set(subject) == {"id", "cert_common_names"}, subject


def test_each_operator_commands_in_its_own_name_only():
    acl = access_control({"operator": ["alice", "carol"], "observer": ["olga"], "relay": []})
    policies = {p["id"]: p for p in acl["policies"]}
    rules = {r["id"]: r for r in acl["rules"]}
    subjects = {s["id"]: s for s in acl["subjects"]}
    for name in ("alice", "carol"):
        policy = policies[f"cert_{name}"]
        assert subjects[policy["subjects"][0]]["cert_common_names"] == [name]
        (rule,) = (rules[r] for r in policy["rules"])
        assert all(k.endswith(f"/@by/{name}") for k in rule["key_exprs"]), rule
    assert "cert_olga" not in policies  # an observer commands in no name


def test_a_relay_forwards_what_the_drone_and_the_operator_may_send():
    """A router between the field and the ground carries telemetry one way and setpoints and
    calls the other, bound to any commander's name (each end's router checked them)."""
    rules = acl_rules(["drone"])
    ids = lambda role: {r["id"] for r in rules[role]}  # noqa: E731
    assert ids("relay") >= ids("drone") | ids("operator")
    arming = registry.ARMING.key("drone")
    assert f"{arming}/@by/*" in _allowed(rules["relay"], "query", "ingress")
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


def test_a_bound_key_names_the_commander_whatever_the_attachment_says():
    key = caller.bound_key("drone/mavros/cmd/arming", "alice")
    assert key == "drone/mavros/cmd/arming/@by/alice"
    assert caller.split_bound(key) == ("drone/mavros/cmd/arming", "alice")
    assert caller.split_bound("drone/mavros/state") == ("drone/mavros/state", "")
    assert caller.bound_key("drone/x", "") == "drone/x"
    claim = caller.commander_attachment("carol", sent=5.0)
    assert caller.origin_of(claim, key) == ("alice", 5.0)
    assert caller.origin_of(claim, "drone/mavros/cmd/arming") == ("carol", 5.0)
    with caller.handling(claim, key):
        assert caller.current_commander() == "alice"
    with caller.handling(None, key):
        assert caller.current_commander() == "alice"
    assert caller.current_commander() == ""
