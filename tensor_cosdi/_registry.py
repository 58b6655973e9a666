"""One registry pattern for every named extension point of the library.

Methods (:data:`tensor_cosdi.solvers.METHODS`), denoisers, systems
(:data:`tensor_cosdi.systems.REGISTRY`), glasses and scenes are each a
:class:`Registry`: a read-only mapping from a validated name to an entry.
Looking up an unknown name raises :class:`UnknownNameError` (a ``KeyError``
and a ``ValueError``) that lists the valid names; registering a name that
exists needs ``replace=True``, and built-in entries cannot be replaced at
all (register yours under another name).
"""

from __future__ import annotations

import re
from collections.abc import Iterator, Mapping
from typing import Any

__all__ = ["Registry", "UnknownNameError"]

_NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.+\-]*$")


class UnknownNameError(KeyError, ValueError):
    """A name that is not in a registry; the message lists the valid names."""

    def __str__(self):  # KeyError would quote the whole message
        return str(self.args[0]) if self.args else ""


class Registry(Mapping):
    """A read-only ``name → entry`` mapping with validated, non-clobbering registration.

    Parameters
    ----------
    kind : str
        What the entries are ("method", "denoiser", "system", …), used in messages.

    Examples
    --------
    >>> r = Registry("colour")
    >>> r.register("red", 1, builtin=True)
    >>> r["red"]
    1
    >>> r["blue"]
    Traceback (most recent call last):
    ...
    tensor_cosdi._registry.UnknownNameError: unknown colour 'blue'; valid names: ['red']
    """

    def __init__(self, kind: str):
        self.kind = kind
        self._items: dict[str, Any] = {}
        self._builtin: set[str] = set()

    def register(self, name: str, entry, *, replace: bool = False, builtin: bool = False) -> None:
        """Add ``entry`` under ``name``.

        Raises ``ValueError`` for a malformed name, for an existing name
        without ``replace=True``, and for any attempt to replace a built-in.
        """
        if not isinstance(name, str) or not _NAME.match(name):
            raise ValueError(
                f"a {self.kind} name must be a non-empty string of letters, digits and _ . + -, "
                f"got {name!r}"
            )
        if name in self._builtin:
            raise ValueError(
                f"{name!r} is a built-in {self.kind} and cannot be replaced; register yours under "
                "another name"
            )
        if name in self._items and not replace:
            raise ValueError(
                f"a {self.kind} named {name!r} is already registered; pass replace=True to replace "
                f"it"
            )
        self._items[name] = entry
        if builtin:
            self._builtin.add(name)

    def unregister(self, name: str) -> None:
        """Remove a user entry (built-ins stay)."""
        if name in self._builtin:
            raise ValueError(f"{name!r} is a built-in {self.kind} and cannot be removed")
        self[name]  # noqa: B018 - raises the listing error for unknown names
        del self._items[name]

    def names(self) -> tuple[str, ...]:
        """The registered names, sorted."""
        return tuple(sorted(self._items))

    def __getitem__(self, name):
        try:
            return self._items[name]
        except (KeyError, TypeError):
            raise UnknownNameError(
                f"unknown {self.kind} {name!r}; valid names: {list(self.names())}"
            ) from None

    def __iter__(self) -> Iterator[str]:
        return iter(self.names())

    def __len__(self) -> int:
        return len(self._items)

    def __contains__(self, name) -> bool:
        try:
            return name in self._items
        except TypeError:
            return False

    def __repr__(self):
        return f"Registry({self.kind!r}, {list(self.names())})"
