"""Only authorised commanders fly the drone, across a real network (network namespaces, root).

The drone's namespace runs a TLS router with access control, the simulated autopilot with a
MAVLink signing key, the bridge with that key and the command lease, and a ground-truth monitor
on loopback. From the laptop's namespace, clients with no certificate, a certificate of another
CA, an observer's, an expired one and a revoked one try every command path, a parameter write,
a setpoint stream and telemetry forgery: none is obeyed and no forged message is delivered.
Then an operator flies; a second operator is refused until she takes the lease over.

The same attack on a TLS listener on the drone's loopback and through a forwarded port (as
``ssh -L`` or a reverse proxy ending on the drone) gets no more than the certificates allow:
only plain local links are trusted without one. Alice claiming to be carol is refused while
carol holds the lease. Each attacker's error is the one docs/security.md quotes.
"""

from __future__ import annotations

import datetime as dt
import json
import subprocess
import sys

import pytest
from netns import Host, is_root, two_hosts

from dronewrapper.security.keystore import KeyStore
from support import REPO, wait_for

pytestmark = pytest.mark.integration

ROUTER_LOCAL = "tcp/127.0.0.1:7447"
TLS_PORT = 7448
FORWARDED_PORT = 7449
CLIENT = str(REPO / "tests" / "data" / "security_client.py")
MONITOR = str(REPO / "tests" / "data" / "security_monitor.py")
FORWARD = str(REPO / "tests" / "data" / "tcp_forward.py")
SECURITY_DOC = REPO / "docs" / "security.md"

# What each attacker is told (docs/security.md quotes each; the tests hold both)
SAYS_NO_IDENTITY = "refused by this client: the router's certificate is not trusted"
SAYS_OTHER_CA = "refused by this client: the router's certificate does not verify with the CA in"
SAYS_EXPIRED = "refused by the router: this client's certificate has expired (identity='old')"
SAYS_PLAIN = "speaks TLS on that port: connect with tls/"
SAYS_OBSERVER = "not permitted for role observer (identity 'olga', as its certificate says)"
SAYS_REVOKED = "this identity was refused (revoked or unknown)"
SAYS_LEASE = "'carol' holds the command lease; 'alice' must take it over explicitly"


def _keys(tmp_path, drone_address: str) -> tuple[KeyStore, KeyStore]:
    store = KeyStore(tmp_path / "keys")
    store.init()
    store.issue("drone1", "drone", hosts=[drone_address])
    for name in ("alice", "carol", "rex"):
        store.issue(name, "operator")
    store.issue("olga", "observer")
    past = dt.datetime.now(dt.timezone.utc) - dt.timedelta(days=3)
    store.issue("old", "operator", days=1, now=past)
    store.revoke("rex")
    store.new_mavlink_key()
    other = KeyStore(tmp_path / "other_ca")
    other.init()
    other.issue("mallory", "operator")
    return store, other


def _client(host, *args: str, timeout: float) -> dict:
    return _clients(host, [args], timeout=timeout)[0]


def _clients(host, runs: list[tuple[str, ...]], timeout: float) -> list[dict]:
    """Run the client on ``host`` once per argument tuple, all at the same time (see
    :func:`_clients_on`); each one's JSON line in the order of ``runs``."""
    return _clients_on([(host, args) for args in runs], timeout)


def _clients_on(runs: list[tuple[Host, tuple[str, ...]]], timeout: float) -> list[dict]:
    """Run the client once per (host, argument tuple), all at the same time, and return each
    one's JSON line in the order of ``runs``. An attacker spends its time waiting for replies
    that never come (1 s per call) and for sessions that are never opened, so running them side
    by side changes no verdict: every call still gets its full timeout."""
    procs = [
        subprocess.Popen(
            host.argv(sys.executable, CLIENT, *args),
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            cwd=REPO,
        )
        for host, args in runs
    ]
    results = []
    try:
        for proc in procs:
            out, err = proc.communicate(timeout=timeout)
            assert proc.returncode == 0, out + err
            results.append(json.loads(out.strip().splitlines()[-1]))
    finally:
        for proc in procs:
            if proc.poll() is None:
                proc.kill()
                proc.wait(5)
    return results


def print_summary(results: list[dict], seen: dict) -> None:
    """The counts, for the record (pytest -s shows them): attempts made by the attackers that
    got a session; the others never got one and made none."""
    print("\nidentity   session  attempts  obeyed  refused  no reply (router denied)")
    for r in results:
        print(f"{r['identity']:10} {r['connected']!s:7}  {r['attempts']:8}  {r['obeyed']:6}  "
              f"{r['refused']:7}  {r['no_reply']:8}")  # fmt: skip
    without = sum(not r["connected"] for r in results)
    print(f"{without} of {len(results)} attackers never got a session")
    print(f"drone side: {seen}")


def start_drone(spawn, drone, tmp_path, *, router_listen, bridge_set, sim_args) -> list:
    """Router, simulated autopilot, bridge and the ground-truth monitor in the drone's netns."""
    py = sys.executable
    bridge = [arg for item in bridge_set for arg in ("--set", item)]
    procs = [
        spawn(drone.argv(py, "-m", "dronewrapper", "router", "--listen", ROUTER_LOCAL,
                         *router_listen, "--namespace", "drone"), "router"),
        spawn(drone.argv(py, "-m", "dronewrapper_sim", "--scenario", "empty", "--no-cameras",
                         "--connect", ROUTER_LOCAL, "--udp-onboard", "14540:0", "--udp-gcs",
                         "off", *sim_args), "sim"),
        spawn(drone.argv(py, "-m", "dronewrapper_bridge_mavlink", "--connect", ROUTER_LOCAL,
                         "--connection", "udpin:127.0.0.1:14540", *bridge), "bridge"),
    ]  # fmt: skip
    truth = tmp_path / "truth.json"
    monitor = spawn(drone.argv(py, MONITOR, ROUTER_LOCAL, str(truth)), "monitor")
    ready = tmp_path / "truth.json.ready"
    wait_for(lambda: ready.exists() or not monitor.alive(), 90, interval=0.2, what="monitor")
    assert ready.exists(), monitor.output()[-2000:]
    return [*procs, monitor]


def start_secured_drone(spawn, drone, tmp_path, store: KeyStore, listen: str) -> list:
    """:func:`start_drone` with every protection on: the router's TLS listener at ``listen``
    (the drone's certificate from ``store``), the command lease, and signed MAVLink."""
    mavkey = str(store.mavlink_key)
    return start_drone(
        spawn,
        drone,
        tmp_path,
        router_listen=["--listen", listen, "--identity", "drone1", "--keys", str(store.root)],
        bridge_set=["command_lease=true", f"signing_key_file={mavkey}"],
        sim_args=["--signing-key", mavkey],
    )


def test_only_authorised_commanders_fly(tmp_path, spawn):
    if not is_root():
        pytest.fail("needs root: it creates network namespaces (CI runs as root)")
    with two_hosts() as (drone, laptop):
        store, other = _keys(tmp_path, drone.address)
        keys = str(store.root)
        tls = f"tls/{drone.address}:{TLS_PORT}"
        procs = start_secured_drone(spawn, drone, tmp_path, store, tls)
        truth = tmp_path / "truth.json"

        attackers = [
            ("", keys, tls),  # no certificate
            ("", keys, f"tcp/{drone.address}:7447"),  # plain tcp: nothing listens off loopback
            ("mallory", str(other.root), tls),  # another CA
            ("olga", keys, tls),  # an observer
            ("old", keys, tls),  # expired
            ("rex", keys, tls),  # revoked
        ]
        runs = [("attack", ep, who, k) for who, k, ep in attackers]
        results = _clients(laptop, runs, timeout=120)
        procs[-1].stop()  # the monitor writes what it saw
        seen = json.loads(truth.read_text())

        report = {f"{r['identity']}@{i}": r for i, r in enumerate(results)}
        assert sum(r["obeyed"] for r in results) == 0, report
        connected = {f"{r['identity']}@{i}": r["connected"] for i, r in enumerate(results)}
        assert connected == {"none@0": False, "none@1": False, "mallory@2": False, "olga@3": True,
                             "old@4": False, "rex@5": True}, report  # fmt: skip
        made = [r for r in results if r["connected"]]
        assert len(made) == 2 and all(r["attempts"] == r["planned"] for r in made), report
        for r in made:  # the router denied every call: no reply, not even a refusal
            assert r["no_reply"] == r["calls"] and r["refused"] == 0, json.dumps(r)
        for r in results:
            if not r["connected"]:  # never got a session: no attempt was made at all
                assert r["attempts"] == 0 and r["no_reply"] == r["refused"] == 0, r
        # what the SDK tells each of them
        by_name = {r["identity"]: r for r in made}
        assert "not permitted for role observer" in by_name["olga"]["sdk_error"], by_name["olga"]
        assert by_name["olga"]["sdk_error"].startswith("CommandRefused"), by_name["olga"]
        refused = "this identity was refused (revoked or unknown)"
        assert refused in by_name["rex"]["sdk_error"], by_name["rex"]
        assert seen["states"] > 0 and seen["poses"] > 0, seen  # the monitor did watch
        assert seen["truths"] > 0, seen  # ... the ground truth too: max_z below is measured
        watched = {r["identity"]: r["states_received"] for r in results if r["connected"]}
        assert watched["olga"] > 0 and watched["rex"] == 0, watched  # observers watch; revoked not
        assert seen["forged_states"] == 0 and seen["forged_poses"] == 0, seen
        assert seen["setpoints"] == 0, seen  # no intruder setpoint reached the drone
        assert not seen["armed"] and seen["max_z"] < 0.3, seen
        assert seen["param_after"] == seen["param_before"], seen
        # no fake bridge answered a parameter read, no forged liveliness token was seen
        assert seen["param_replies"] > 0 and seen["forged_replies"] == 0, seen
        assert seen["forged_tokens"] == 0, seen
        print_summary(results, seen)

        flight = _client(laptop, "fly", tls, keys, timeout=240)
        assert flight["alice_flew_to"] > 1.3, flight
        assert flight["commander_after_takeoff"] == "alice", flight
        assert flight["carol_arm"].startswith("refused") and "alice" in flight["carol_arm"], flight
        assert flight["z_while_carol_refused"] < 1.8, flight  # carol's 2.5 m setpoints dropped
        assert flight["carol_took_over_from"] == "alice", flight
        assert flight["commander_after_take_over"] == "carol", flight
        assert flight["carol_flew_to"] > 2.2, flight
        assert flight["alice_land"].startswith("refused"), flight
        assert flight["landed"], flight
        for proc in reversed(procs):
            proc.stop()
        bridge_log = procs[2].output()
        assert "command lease taken_over: carol (was alice)" in bridge_log, bridge_log[-2000:]


def test_without_security_an_intruder_flies_the_drone(tmp_path, spawn):
    """The same attack on the unsecured setup (plain tcp, --insecure, no lease, no signing):
    the issue's measurement, and the proof that the detectors above do detect."""
    if not is_root():
        pytest.fail("needs root: it creates network namespaces (CI runs as root)")
    with two_hosts("u") as (drone, laptop):
        plain = f"tcp/{drone.address}:7447"
        procs = start_drone(spawn, drone, tmp_path, router_listen=["--listen", plain,
                            "--insecure"], bridge_set=[], sim_args=[])  # fmt: skip
        result = _client(laptop, "attack", plain, "", str(tmp_path), timeout=120)
        procs[-1].stop()
        seen = json.loads((tmp_path / "truth.json").read_text())
        print_summary([result], seen)
        print(result)
        for proc in reversed(procs):
            proc.stop()
    assert result["connected"] and result["obeyed"] >= 6, result  # param, arm, land, ...
    assert seen["param_after"] != seen["param_before"], seen
    assert seen["armed"] and seen["setpoints"] > 0, seen
    assert seen["forged_states"] > 0 and seen["forged_poses"] > 0, seen
    assert seen["forged_replies"] > 0 and seen["forged_tokens"] > 0, seen


def _judge(results: list[dict], seen: dict) -> None:
    """Nothing obeyed, nothing forged delivered, every call of a session denied by the router."""
    report = {f"{r['identity']}@{i}": r for i, r in enumerate(results)}
    assert sum(r["obeyed"] for r in results) == 0, report
    for r in results:
        if r["connected"]:
            assert r["attempts"] == r["planned"], r
            assert r["no_reply"] == r["calls"] and r["refused"] == 0, json.dumps(r)
        else:
            assert r["attempts"] == 0, r
    assert seen["states"] > 0 and seen["truths"] > 0, seen
    assert seen["forged_states"] == 0 and seen["forged_poses"] == 0, seen
    assert seen["setpoints"] == 0 and seen["forged_replies"] == 0, seen
    assert seen["forged_tokens"] == 0 and seen["param_replies"] > 0, seen
    assert not seen["armed"] and seen["max_z"] < 0.3, seen
    assert seen["param_after"] == seen["param_before"], seen


def test_roles_hold_on_a_tls_listener_on_loopback_and_a_forwarded_port(tmp_path, spawn):
    """The router listens with TLS on the drone's loopback only; attackers connect there from
    the drone itself and from the laptop through a port forwarded to it: every link arrives on
    ``lo``, and each gets exactly its certificate's role."""
    if not is_root():
        pytest.fail("needs root: it creates network namespaces (CI runs as root)")
    with two_hosts("f") as (drone, laptop):
        store, other = _keys(tmp_path, drone.address)
        keys = str(store.root)
        local_tls = f"tls/127.0.0.1:{TLS_PORT}"
        procs = start_secured_drone(spawn, drone, tmp_path, store, local_tls)
        forward = spawn(drone.argv(sys.executable, FORWARD, f"{drone.address}:{FORWARDED_PORT}",
                                   f"127.0.0.1:{TLS_PORT}"), "forward")  # fmt: skip
        wait_for(lambda: "forwarding" in forward.output() or not forward.alive(), 30,
                 what="forwarder")  # fmt: skip
        tunnel = f"tls/{drone.address}:{FORWARDED_PORT}"
        on_drone = [("attack", local_tls, who, keys) for who in ("olga", "rex", "old")]
        on_drone += [
            ("attack", local_tls, "", keys),
            ("attack", local_tls, "mallory", str(other.root)),
        ]
        on_drone.append(("attack", f"tcp/127.0.0.1:{TLS_PORT}", "", keys))  # plain on the TLS port
        through = [("attack", tunnel, who, keys) for who in ("olga", "rex")]
        everyone = [(drone, args) for args in on_drone] + [(laptop, args) for args in through]
        results = _clients_on(everyone, timeout=120)  # on the drone and through the tunnel
        local_results, tunnel_results = results[: len(on_drone)], results[len(on_drone) :]
        procs[-1].stop()  # the monitor writes what it saw
        seen = json.loads((tmp_path / "truth.json").read_text())
        print_summary(results, seen)
        _judge(results, seen)
        olga, rex, old, nobody, mallory, plain = local_results
        assert olga["connected"] and rex["connected"], results  # TLS passes; roles decide
        assert olga["states_received"] > 0 and rex["states_received"] == 0, results
        assert not (old["connected"] or nobody["connected"] or mallory["connected"]), results
        assert SAYS_EXPIRED in old["why"], old
        assert SAYS_NO_IDENTITY in nobody["why"], nobody
        assert SAYS_OTHER_CA in mallory["why"], mallory
        assert not plain["connected"] and SAYS_PLAIN in plain["why"], plain
        for r in (olga, tunnel_results[0]):
            assert r["sdk_error"].startswith("CommandRefused") and SAYS_OBSERVER in r["sdk_error"]
        for r in (rex, tunnel_results[1]):
            assert SAYS_REVOKED in r["sdk_error"], r
        assert all(r["connected"] for r in tunnel_results), tunnel_results

        spoofed = _client(drone, "spoof", local_tls, keys, timeout=120)
        assert spoofed["alice_commander"] == "alice", spoofed  # the certificate's name
        assert spoofed["sdk"].startswith("refused") and SAYS_LEASE in spoofed["sdk"], spoofed
        said = spoofed["sdk"].removeprefix("refused: ")  # the CommandRefused's own text
        assert said.startswith(f"param_set MPC_XY_VEL_MAX refused: {SAYS_LEASE}"), spoofed
        assert spoofed["raw_plain"] == "no_reply", spoofed  # plain keys: local processes only
        assert spoofed["raw_carol"] == "no_reply", spoofed  # carol's key: carol's certificate
        assert SAYS_LEASE in spoofed["raw_alice"], spoofed  # her own: she is alice
        assert spoofed["holder"] == "carol", spoofed
        assert spoofed["param_after"] == spoofed["param_before"], spoofed
        for proc in reversed([*procs, forward]):
            proc.stop()
        router_log = procs[0].output()
        assert "rejected TLS handshake" in router_log, router_log[-3000:]
        assert "open file limit" not in router_log, router_log[-3000:]


def test_docs_quote_what_each_attacker_is_told():
    """docs/security.md quotes the errors the attack above holds."""
    text = " ".join(SECURITY_DOC.read_text().split())
    for said in (SAYS_NO_IDENTITY, SAYS_OTHER_CA, SAYS_EXPIRED, SAYS_PLAIN, SAYS_OBSERVER,
                 SAYS_REVOKED, SAYS_LEASE):  # fmt: skip
        assert said in text, said
