"""The registry of disturbance kinds (the scenario's ``[[disturbances]]`` entries): each kind's
module registers its pydantic spec (``type = "<name>"``) and the builder of its model."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from twin.spec import StrictSpec


class DisturbanceSpecBase(StrictSpec):
    """What every disturbance kind's spec has: the ``type`` that names its kind."""

    type: str


@dataclass(frozen=True)
class DisturbanceKind:
    """One disturbance kind.

    Attributes
    ----------
    name : str
        The scenario's ``type``.
    spec : type
        Its pydantic model (a :class:`DisturbanceSpecBase` with ``type: Literal[name]``); its
        docstring's first line is the kind's docs line (``twin list``).
    build : callable
        ``build(spec, axis_names, seed, field) -> model``: the force model on the workpiece
        (``kernel_arrays``) or the drive-input disturbance (``input_V``) for a machine with those
        axes, ``seed`` the entry's (or the scenario's), ``field`` the entry's path for errors.
    """

    name: str
    spec: type[DisturbanceSpecBase]
    build: Callable

    @property
    def doc(self) -> str:
        """The first line of the spec's docstring."""
        return (self.spec.__doc__ or self.name).strip().splitlines()[0]


#: Disturbance kinds by name, in registration order.
DISTURBANCES: dict[str, DisturbanceKind] = {}


def register(name: str, spec: type[DisturbanceSpecBase], build: Callable) -> DisturbanceKind:
    """Add a disturbance kind; its module calls this at import."""
    if name in DISTURBANCES:
        raise ValueError(f"disturbance kind {name!r} is registered twice")
    DISTURBANCES[name] = DisturbanceKind(name, spec, build)
    return DISTURBANCES[name]
