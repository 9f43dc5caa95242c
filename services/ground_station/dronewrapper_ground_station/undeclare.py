"""Undeclaring a node's subscriptions and publishers, whatever became of its session."""

from __future__ import annotations

import logging
from typing import Any

log = logging.getLogger("station")


def undeclare(entities: list[Any]) -> None:
    """Undeclare each of ``entities`` (newest first), whatever became of the session."""
    for entity in reversed(entities):
        try:
            entity.undeclare()
        except Exception as exc:  # the session is already closed
            log.debug("undeclare: %s", exc)
    entities.clear()
