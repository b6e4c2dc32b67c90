"""The registry of reference kinds: each kind's module registers its pydantic spec (the
scenario's ``[reference]`` table, ``type = "<name>"``) and the builder of its reference."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from twin.spec import StrictSpec


class ReferenceSpecBase(StrictSpec):
    """What every reference kind's spec has: the ``type`` that names its kind."""

    type: str


@dataclass(frozen=True)
class ReferenceKind:
    """One reference kind.

    Attributes
    ----------
    name : str
        The scenario's ``type``.
    spec : type
        Its pydantic model (a :class:`ReferenceSpecBase` with ``type: Literal[name]``); its
        docstring's first line is the kind's docs line (``twin list``).
    build : callable
        ``build(spec, axis_names) -> reference``: the reference for a machine with those axes
        (``sample(t) -> (len(t), n_axes, 3)``); raises ``TwinInputError`` naming the field.
    """

    name: str
    spec: type[ReferenceSpecBase]
    build: Callable

    @property
    def doc(self) -> str:
        """The first line of the spec's docstring."""
        return (self.spec.__doc__ or self.name).strip().splitlines()[0]


#: Reference kinds by name, in registration order.
REFERENCES: dict[str, ReferenceKind] = {}


def register(name: str, spec: type[ReferenceSpecBase], build: Callable) -> ReferenceKind:
    """Add a reference kind; its module calls this at import."""
    if name in REFERENCES:
        raise ValueError(f"reference kind {name!r} is registered twice")
    REFERENCES[name] = ReferenceKind(name, spec, build)
    return REFERENCES[name]


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
