"""The node contract on a real router: Node keeps every promise FakeNode keeps (the same checks
run on the fake bus in tests/unit/test_node_contract.py)."""

from __future__ import annotations

import pytest
from node_contract import PORTS, check_node, check_ports

from support import client_node, wait_for

pytestmark = pytest.mark.integration


def settled(predicate, what: str) -> None:
    wait_for(predicate, 10.0, what=what)


def test_node_keeps_the_node_contract(router):
    with (
        client_node(router, "a", mode="client") as a,
        client_node(router, "b", mode="client") as b,
    ):
        check_node(a, b, settled)


def test_a_node_with_ports_refuses_what_they_do_not_declare(router):
    with (
        client_node(router, "limited", mode="client", ports=PORTS) as limited,
        client_node(router, "free", mode="client") as free,
    ):
        check_ports(limited, free, settled)
