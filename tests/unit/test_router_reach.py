"""Finding that no router listens, from the endpoints (pure; the connect is injected)."""

from __future__ import annotations

from dronewrapper.router_reach import NO_ROUTER_HINT, no_router, tcp_address


def test_tcp_and_tls_endpoints_give_an_address_and_others_none():
    assert tcp_address("tcp/127.0.0.1:7447") == ("127.0.0.1", 7447)
    assert tcp_address("tls/192.168.1.50:7448") == ("192.168.1.50", 7448)
    assert tcp_address("tcp/[::1]:7447#iface=lo") == ("::1", 7447)
    assert tcp_address("udp/127.0.0.1:7447") is None
    assert tcp_address("unixsock-stream/tmp/z.sock") is None
    assert tcp_address("tcp/localhost") is None


def test_no_router_only_when_every_endpoint_refused():
    refused = {("127.0.0.1", 7447), ("127.0.0.1", 7448)}
    sentence = no_router(["tcp/127.0.0.1:7447"], refused=lambda a: a in refused)
    assert sentence == f"no router at tcp/127.0.0.1:7447 (connection refused): {NO_ROUTER_HINT}"
    both = ["tcp/127.0.0.1:7447", "tcp/127.0.0.1:9"]
    assert no_router(both, refused=lambda a: a in refused) is None  # one may answer
    assert no_router(["udp/127.0.0.1:7447"], refused=lambda a: True) is None  # not ours to say
    assert no_router([], refused=lambda a: True) is None
    assert "dronewrapper up compose/GRAPH.yaml" in NO_ROUTER_HINT
