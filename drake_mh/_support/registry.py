"""One idiom for "one entry point, many methods": a table of named methods, each loaded on first use.

IK (:data:`drake_mh.ik.solve.METHODS`), motion planning (:data:`drake_mh.planning.methods.METHODS`)
and the optimizers (:data:`drake_mh.optim.METHODS`) each keep one explicit :class:`Registry`:
a name, what it stands for (the object itself, or where to import it from on first use) and a
one-line description. An optional peer's method names the modules it needs (``requires``): where
one of them cannot be imported, the method is absent (not listed, unknown), not an error.

Example::

    METHODS = Registry("motion planning method")
    METHODS.add("straight", load="drake_mh.planning.straight:plan", description="the straight line")
    METHODS.add("ompl_rrtconnect", load="drake_mh.planning.ompl_peer:plan_rrtconnect",
                description="OMPL's RRT-Connect", requires=("ompl.base", "ompl.geometric"))
    METHODS.available()     # {name: description} of the methods present here
    METHODS.get("straight")  # the plan function (imported now); UnknownMethod lists the names
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import Any

from drake_mh.errors import UnknownMethod

__all__ = ["Registry"]

_IMPORTABLE: dict[str, bool] = {}
"""Whether each module a method requires could be imported (tried once per process)."""


def _importable(module: str) -> bool:
    if module not in _IMPORTABLE:
        try:
            importlib.import_module(module)
        except ImportError:  # an optional peer that is not installed, or whose import fails
            _IMPORTABLE[module] = False
        else:
            _IMPORTABLE[module] = True
    return _IMPORTABLE[module]


@dataclass
class _Entry:
    description: str
    value: Any = None
    load: str | Callable[[], Any] | None = None
    args: tuple | None = None
    requires: tuple[str, ...] = ()

    def resolve(self) -> Any:
        if self.load is not None:
            if callable(self.load):
                self.value = self.load()
            else:
                module, _, attribute = self.load.partition(":")
                self.value = getattr(importlib.import_module(module), attribute)
                if self.args is not None:
                    self.value = self.value(*self.args)
            self.load = None
        return self.value


class Registry:
    """Named methods of one entry point, in the order they were added.

    Args:
        what: what a method is, for messages (``"IK method"``: "unknown IK method 'x'; available: ...").
        case_sensitive: with ``False``, :meth:`get` and ``in`` take a name in any case (the
            table's names are lower case).
        extend: called once with the registry before its first read, to add the entries that
            need an import to be known (e.g. one per optimizer), so that importing the table
            costs nothing.
    """

    def __init__(self, what: str, *, case_sensitive: bool = True,
                 extend: Callable[[Registry], None] | None = None):
        self.what = what
        self._case_sensitive = case_sensitive
        self._extend = extend
        self._entries: dict[str, _Entry] = {}

    def add(self, name: str, value: Any = None, *, load: str | Callable[[], Any] | None = None,
            args: tuple | None = None, description: str = "", requires: tuple[str, ...] = ()) -> None:
        """Adds method ``name``: ``value`` itself, or ``load``, where to get it on first use:
        ``"module:attribute"`` (with ``args``: what that attribute returns when called with them),
        or a function of no arguments that returns it. A string keeps the table free of import
        statements, so a method's module may import the entry point that reads the table.
        ``requires``: modules that must import for the method to be present (an optional peer)."""
        if (value is None) == (load is None):
            raise TypeError(f"{self.what} {name!r}: give either the value or where to load it from")
        self._entries[name] = _Entry(description, value, load, None if args is None else tuple(args),
                                     tuple(requires))

    def remove(self, name: str) -> None:
        """Removes method ``name`` (one you added; nothing if there is none)."""
        self._entries.pop(name, None)

    def register(self, name: str, description: str = "", requires: tuple[str, ...] = ()):
        """Decorator form of :meth:`add`: ``@METHODS.register("name", "what it does")``."""

        def wrap(function):
            self.add(name, function, description=description, requires=requires)
            return function

        return wrap

    def _present(self) -> dict[str, _Entry]:
        if self._extend is not None:
            extend, self._extend = self._extend, None
            extend(self)
        return {name: entry for name, entry in self._entries.items()
                if all(_importable(module) for module in entry.requires)}

    def available(self) -> dict[str, str]:
        """``{name: one-line description}`` of the methods present here, in table order."""
        return {name: entry.description for name, entry in self._present().items()}

    def names(self) -> list[str]:
        """The names of the methods present here, in table order."""
        return list(self._present())

    def _key(self, name) -> Any:
        return name if self._case_sensitive or not isinstance(name, str) else name.lower()

    def get(self, name: str) -> Any:
        """The method ``name`` (imported on first use).

        Raises:
            UnknownMethod: no such method here (the message lists the names).
        """
        present = self._present()
        entry = present.get(self._key(name)) if isinstance(name, str) else None
        if entry is None:
            raise UnknownMethod(name, present, what=self.what)
        return entry.resolve()

    __getitem__ = get

    def __contains__(self, name: object) -> bool:
        return isinstance(name, str) and self._key(name) in self._present()

    def __iter__(self) -> Iterator[str]:
        return iter(self.names())

    def __len__(self) -> int:
        return len(self._present())

    def __repr__(self) -> str:
        return f"Registry({self.what!r}: {', '.join(self.names())})"
