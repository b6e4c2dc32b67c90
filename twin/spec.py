"""The base of every scenario table's pydantic model."""

from __future__ import annotations

from pydantic import BaseModel, ConfigDict


class StrictSpec(BaseModel):
    """Unknown fields and non-finite numbers (nan, inf) are errors."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)


def axes_indices(names: list[str] | None, axis_names: list[str], field: str) -> tuple[int, ...] | None:
    """Indices of the axes ``names`` among the machine's ``axis_names`` (None stays None: all
    axes).

    Raises
    ------
    TwinInputError
        A name that is not one of the machine's axes, under ``field``.
    """
    from twin.errors import TwinInputError

    if names is None:
        return None
    for a in names:
        if a not in axis_names:
            raise TwinInputError(field, a, f"machine axes are {axis_names}")
    return tuple(axis_names.index(a) for a in names)
