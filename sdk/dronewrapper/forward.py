"""A facade's verbs, each the same method of a part it owns.

``get_position = forward("getters", Getters.get_position)`` in a class body makes
``facade.get_position`` the bound method ``facade.getters.get_position``: the call goes straight
to the part (no wrapper in between), and the class shows the part's function, with its name,
signature and docstring (what ``help()`` and an editor show), and its types for the checker.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, Concatenate, Generic, ParamSpec, TypeVar, overload

P = ParamSpec("P")
R = TypeVar("R")


class forward(Generic[P, R]):  # lower case: it is written like a function in a class body
    """``method`` of the part in the facade's attribute ``part`` (see the module doc)."""

    def __init__(self, part: str, method: Callable[Concatenate[Any, P], R]) -> None:
        self.part = part
        self.method = method
        self.name = method.__name__
        self.__doc__ = method.__doc__

    @overload
    def __get__(self, facade: None, owner: type) -> Callable[Concatenate[Any, P], R]: ...
    @overload
    def __get__(self, facade: object, owner: type | None = None) -> Callable[P, R]: ...
    def __get__(self, facade: object | None, owner: type | None = None) -> Callable[..., Any]:
        if facade is None:
            return self.method
        bound: Callable[P, R] = getattr(getattr(facade, self.part), self.name)
        return bound
