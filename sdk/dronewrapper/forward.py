"""A facade's verbs, each the same method of a part it owns.

``get_position = forward("getters", Getters.get_position)`` in a class body makes
``facade.get_position()`` call ``facade.getters.get_position()``, with the part's name,
signature and docstring (what ``help()`` and an editor show), and its types for the checker.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from typing import Any, Concatenate, ParamSpec, TypeVar

P = ParamSpec("P")
R = TypeVar("R")


def forward(
    part: str, method: Callable[Concatenate[Any, P], R]
) -> Callable[Concatenate[Any, P], R]:
    """``method`` called on the facade's attribute ``part`` (see the module doc)."""

    @functools.wraps(method)
    def forwarded(self: Any, *args: P.args, **kwargs: P.kwargs) -> R:
        return method(getattr(self, part), *args, **kwargs)

    return forwarded
