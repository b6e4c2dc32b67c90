"""The base of every scenario table's pydantic model."""

from __future__ import annotations

import tomllib
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Union, overload

from pydantic import BaseModel, ConfigDict, Field


def read_toml(path: Path, what: str) -> dict:
    """The TOML file ``path`` as a dict.

    Raises
    ------
    TwinInputError
        Under ``what`` (``"scenario file"``): not UTF-8 text, malformed TOML, or unreadable.
    """
    from twin.errors import TwinInputError

    try:
        return tomllib.loads(path.read_bytes().decode("utf-8"))
    except UnicodeDecodeError as exc:
        raise TwinInputError(what, str(path), f"not UTF-8 text (byte {exc.start})") from None
    except tomllib.TOMLDecodeError as exc:
        raise TwinInputError(what, str(path), f"malformed TOML: {exc}") from None
    except OSError as exc:
        raise TwinInputError(what, str(path), f"cannot be read ({exc.strerror})") from None


class StrictSpec(BaseModel):
    """Unknown fields and non-finite numbers (nan, inf) are errors."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)


@overload
def axes_indices(names: list[str], axis_names: list[str], field: str) -> tuple[int, ...]: ...


@overload
def axes_indices(names: None, axis_names: list[str], field: str) -> None: ...


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


class KindSpec(StrictSpec):
    """What the spec of every registered kind (reference, disturbance) has: the ``type`` that
    names its kind."""

    type: str


@dataclass(frozen=True)
class Kind:
    """One kind of a registry (:data:`twin.references.REFERENCES`, :data:`twin.process.DISTURBANCES`).

    Attributes
    ----------
    name : str
        The scenario's ``type``.
    spec : type
        Its pydantic model (a :class:`KindSpec` with ``type: Literal[name]``); its docstring's
        first line is the kind's docs line (``twin list``).
    build : callable
        The builder of the kind's model from its spec (its registry says the arguments).
    """

    name: str
    spec: type[KindSpec]
    build: Callable

    @property
    def doc(self) -> str:
        """The first line of the spec's docstring."""
        return (self.spec.__doc__ or self.name).strip().splitlines()[0]


def register_kind(registry: dict[str, Kind], name: str, spec: type[KindSpec], build: Callable) -> Kind:
    """Add a kind to ``registry``; each kind's module calls this at import."""
    if name in registry:
        raise ValueError(f"kind {name!r} is registered twice")
    registry[name] = Kind(name, spec, build)
    return registry[name]


def tagged_union(registry: dict[str, Kind]):
    """The pydantic type of a table that is any of ``registry``'s kinds, told apart by ``type``
    (a union built at run time from the registered specs)."""
    specs = tuple(kind.spec for kind in registry.values())
    return Annotated[Union[specs], Field(discriminator="type")]  # noqa: UP007 (a union built at run time)
