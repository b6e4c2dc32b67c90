"""One registry type for every catalogue of the twin: controller and observer kinds, reference
and disturbance kinds, machines, materials, inspection features and reproductions.

An :class:`Entry` is a name, its one-line summary (``twin list`` and the docs print it), the
pydantic model of its settings (where it takes any) and the registered value (a builder, a
machine, a material, a measurement).  A :class:`Registry` holds entries by name in registration
order and answers an unknown name with one error line naming the field, the value and the known
names.

This package sits below both :mod:`controllers` and :mod:`twin` and imports neither (the
controllers may not import the twin, and the twin's registries and the controllers' must be one
type).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Generic, TypeVar

if TYPE_CHECKING:
    from pydantic import BaseModel

T = TypeVar("T")


@dataclass(frozen=True)
class Entry(Generic[T]):
    """One name of a registry.

    Attributes
    ----------
    name : str
        What a scenario, a machine file or the command line calls it (``type = "<name>"``).
    summary : str
        Its one line for ``twin list`` and the docs.
    settings : type or None
        The pydantic model of its settings (names, defaults, limits; units in the field
        descriptions); None where it takes none.
    value : object
        What is registered: a builder, a machine, a material's coefficients, a measurement.
    """

    name: str
    summary: str
    settings: type[BaseModel] | None
    value: T


class UnknownName(ValueError):
    """A name a registry does not hold.

    Attributes
    ----------
    field : str
        Where the name was given (``controller.type``).
    value : str
        The name given.
    reason : str
        ``unknown <what> (known: <names>)``.
    """

    def __init__(self, field: str, value: str, reason: str):
        super().__init__(f"{field} = {value!r}: {reason}")
        self.field, self.value, self.reason = field, value, reason


class Registry(dict[str, Entry[T]]):
    """Entries by name, in registration order (a dict: a test may set an entry for its own run).

    Parameters
    ----------
    what : str
        What one entry is, for error lines (``"controller"``).
    """

    def __init__(self, what: str):
        super().__init__()
        self.what = what

    def add(self, name: str, value: T, *, summary: str, settings: type[BaseModel] | None = None) -> Entry[T]:
        """Register ``value`` as ``name``; each entry's module calls this at import.

        Raises
        ------
        ValueError
            An empty name, or a name registered already.
        """
        if not name or name in self:
            raise ValueError(f"{self.what} {name!r} has no name or is registered twice")
        self[name] = Entry(name, " ".join(summary.split()), settings, value)
        return self[name]

    def unknown(self, name: str, *, alternative: str = "") -> str:
        """Why ``name`` cannot be used: ``unknown <what> (known: <names>[; <alternative>])``."""
        return f"unknown {self.what} (known: {', '.join(self)}{'; ' + alternative if alternative else ''})"

    def lookup(
        self,
        name: str,
        *,
        field: str,
        alternative: str = "",
        error: Callable[[str, Any, str], Exception] = UnknownName,
    ) -> Entry[T]:
        """The entry ``name``.

        Parameters
        ----------
        name : str
            The name given.
        field : str
            Where it was given, for the error line.
        alternative : str
            What else the field takes, appended to the known names (``or a machine file``).
        error : callable
            ``error(field, value, reason)``: the exception raised for an unknown name (the twin
            passes its own input error).

        Raises
        ------
        UnknownName
            (or what ``error`` makes) A name the registry does not hold.
        """
        if name not in self:
            raise error(field, name, self.unknown(name, alternative=alternative))
        return self[name]
