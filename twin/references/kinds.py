"""The registry of reference kinds: each kind's module registers its pydantic spec (the
scenario's ``[reference]`` table, ``type = "<name>"``) and the builder of its reference."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from controllers.registries import Entry, Registry
from twin.spec import KindSpec, register_kind

#: The base of every reference kind's spec.
ReferenceSpecBase = KindSpec
#: Reference kinds by name, in registration order: each builder is ``build(spec, ctx) -> reference``
#: (``ctx``: a :class:`ReferenceContext`; the reference has ``n_axes`` and ``sample(t) -> (len(t),
#: n_axes, 3)``), raising ``TwinInputError`` naming the field.
REFERENCES: Registry[Callable] = Registry("reference")


@dataclass(frozen=True)
class ReferenceContext:
    """What a reference builder knows besides its spec.

    Attributes
    ----------
    axis_names : list of str
        The machine's axes, in order.
    machine : object or None
        The built machine (its motion limits, for planned references); None where a reference
        is built without one.
    planner : object
        The scenario's ``[planner]`` table (:class:`twin.gcode.planner.PlannerSettings`, or a
        dict of its fields).
    tools : frozenset of int or None
        The T numbers of the scenario's ``[[tools]]`` (None: no list, any T word).
    stock : bool
        Whether the scenario cuts a stock (a program's plan is then held whole).
    saturation_V : float or None
        The drive's saturation (V; None: none), what a program's drive check compares with.
    tool_diameters_mm : dict of int to float
        The diameters of the scenario's ``[[tools]]`` by T number (mm; cutter compensation's).
    """

    axis_names: list[str]
    machine: Any = None
    planner: Any = field(default_factory=dict)
    tools: frozenset[int] | None = None
    stock: bool = False
    saturation_V: float | None = None
    tool_diameters_mm: dict[int, float] = field(default_factory=dict)


def register(name: str, spec: type[KindSpec], build: Callable) -> Entry:
    """Add a reference kind; its module calls this at import."""
    return register_kind(REFERENCES, name, spec, build)


def per_axis(signal: np.ndarray, n_axes: int, axes: tuple[int, ...] | None) -> np.ndarray:
    """A one-axis signal ``(n, 3)`` on the ``axes`` (indices; None: all) of ``n_axes``, zero
    on the others: ``(n, n_axes, 3)``."""
    out = np.zeros((signal.shape[0], n_axes, 3))
    for a in range(n_axes) if axes is None else axes:
        out[:, a, :] = signal
    return out


def two_axes(kind: str, axis_names: list[str]) -> None:
    """A 2-D path needs a machine of two axes."""
    from twin.errors import TwinInputError

    if len(axis_names) != 2:
        raise TwinInputError("reference.type", kind, f"a 2-D path needs two axes, the machine has {len(axis_names)}")
