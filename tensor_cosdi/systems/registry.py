"""The registry of imagers: ``name → System subclass`` (:data:`REGISTRY`).

It imports no imager: :mod:`tensor_cosdi.systems` registers the built-in ones,
and ``REGISTRY.register_class`` adds yours.  The :class:`System` base class
the registry checks against is set by :mod:`tensor_cosdi.systems._base` when it
defines it.
"""

from __future__ import annotations

from .._registry import Registry

__all__ = ["SystemRegistry", "REGISTRY"]


class SystemRegistry(Registry):
    """:class:`~tensor_cosdi._registry.Registry` of system classes, keyed by their ``name``."""

    #: The class every entry must subclass (:class:`tensor_cosdi.systems.System`, set once by
    #: the module that defines it).
    base: type | None = None

    def register_class(self, cls, *, replace: bool = False, builtin: bool = False) -> None:
        """Register a :class:`System` subclass under its ``name`` class attribute."""
        base = self.base
        if base is None or not (isinstance(cls, type) and issubclass(cls, base)) or not cls.name:
            raise ValueError(
                f"a registered system must be a System subclass with a non-empty name, got {cls!r}"
            )
        self.register(cls.name, cls, replace=replace, builtin=builtin)

    def name_of_class(self, class_name: str) -> str:
        """The registry name of a class name (older bundles store the class name only)."""
        for name, cls in self.items():
            if cls.__name__ == class_name:
                return name
        raise ValueError(
            f"unknown system class {class_name!r}; registered: "
            f"{[c.__name__ for c in self.values()]}"
        )


REGISTRY = SystemRegistry("system")
"""``name → System subclass``, read-only: every imager the library knows (``register_class`` adds
yours)."""
