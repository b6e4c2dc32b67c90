"""The base of every scenario table's pydantic model."""

from __future__ import annotations

import math
import tomllib
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Union, overload

from pydantic import AfterValidator, BaseModel, ConfigDict, Field, ValidationError, field_validator

from controllers.registries import Entry, Registry

if TYPE_CHECKING:
    from twin.errors import TwinInputError


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


#: The largest magnitude of any number in a scenario, machine, stock or tool table.  No
#: physical value of the twin comes near it (the stiffest spring of the catalogue machines is
#: 1.6e8 N/m); with every input under it, no product or power of a few inputs overflows (a
#: gear ratio of 1e308 did, squared).
MAX_MAGNITUDE = 1e12
#: The smallest magnitude of a number that is not zero: its inverse and square inverse stay
#: finite (a screw lead of 5e-324 divided by zero).
MIN_MAGNITUDE = 1e-15


#: Coordinates and sizes at most (mm) of a stock, a tool, a work offset or an inspected
#: feature: a metre-sized machine's travel, ten times.
MAX_MM = 1e4
#: A coordinate or size (mm) within +-MAX_MM.
Millimetres = Annotated[float, Field(ge=-MAX_MM, le=MAX_MM)]


def _one_line(text: str) -> str:
    """``text`` where every character prints (a newline would split a report's line)."""
    if not text.isprintable():
        raise ValueError("must be one line of printable characters (no newline, tab or control character)")
    return text


#: A name a report prints: 1 to 200 printable characters on one line.
ReportName = Annotated[str, Field(min_length=1, max_length=200), AfterValidator(_one_line)]


def _out_of_range(value, path: str = "") -> tuple[str, float] | None:
    """The path (``key.0``; empty for ``value`` itself) and value of the first finite number
    in ``value`` (a number, or lists, tuples and dicts of them) whose magnitude is over
    :data:`MAX_MAGNITUDE` or, not zero, under :data:`MIN_MAGNITUDE`; None if there is none."""
    if isinstance(value, bool):
        return None
    if isinstance(value, int | float):
        size = abs(value)
        return (path, value) if math.isfinite(value) and (size > MAX_MAGNITUDE or 0 < size < MIN_MAGNITUDE) else None
    items = value.items() if isinstance(value, dict) else enumerate(value) if isinstance(value, list | tuple) else ()
    for key, item in items:
        found = _out_of_range(item, f"{path}.{key}" if path else str(key))
        if found is not None:
            return found
    return None


class StrictSpec(BaseModel):
    """Unknown fields and non-finite numbers (nan, inf) are errors, and so is a number of
    magnitude over :data:`MAX_MAGNITUDE` or, not zero, under :data:`MIN_MAGNITUDE` (fields may
    bound themselves more tightly)."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)

    @field_validator("*", mode="after")
    @classmethod
    def _bounded(cls, value):
        found = _out_of_range(value)
        if found is not None:
            path, number = found
            big = abs(number) > MAX_MAGNITUDE
            bound = f"beyond +-{MAX_MAGNITUDE:g}" if big else f"not zero and under +-{MIN_MAGNITUDE:g}"
            raise ValueError(f"{path + ' = ' if path else ''}{number:g} is {bound}, out of any physical range")
        return value


def validation_error(err: ValidationError, data, prefix: str = "", whole: str = "scenario") -> TwinInputError:
    """The error of pydantic's ``err`` for the user's ``data`` (the dict validated) as the
    twin's error line: the field path as the user wrote it (after ``prefix``; ``whole`` for an
    error of the whole table), the value and the reason (without pydantic's "Value error, ").

    Pydantic's path holds the union members it tried (``constrained-float``,
    ``list[constrained-float]``, a tagged table's tag): a step of its path that the data does not
    hold is such a member and is left out (the last step of a missing field excepted).  Of the
    union members' errors for one field, the deepest is reported: ``[-1]`` for a number or a list
    of numbers is refused for its item ``0``, not as "not a number".
    """
    from twin.errors import TwinInputError

    errors = [(_written_path(e, data), e) for e in err.errors()]
    stem = errors[0][0]
    path, e = max((pe for pe in errors if pe[0][: len(stem)] == stem), key=lambda pe: len(pe[0]))
    value = e.get("input")
    reason = e["msg"].removeprefix("Value error, ")
    field = ".".join(str(step) for step in path)
    return TwinInputError(prefix + (field or whole), "{...}" if isinstance(value, dict) else value, reason)


def _written_path(error, data) -> list:
    """The steps of pydantic's ``error["loc"]`` that ``data`` holds (a missing field's name last)."""
    loc, path, node = error["loc"], [], data
    for i, step in enumerate(loc):
        in_table = isinstance(node, dict) and step in node
        if in_table or (isinstance(node, list) and isinstance(step, int) and 0 <= step < len(node)):
            path.append(step)
            node = node[step]
        elif i == len(loc) - 1 and error["type"] == "missing":
            path.append(step)
    return path


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
    names its kind (:func:`register_kind`)."""

    type: str


def register_kind(registry: Registry, name: str, spec: type[StrictSpec], build: Callable) -> Entry:
    """Add a kind to ``registry`` (:data:`twin.references.REFERENCES`,
    :data:`twin.disturbances.DISTURBANCES`, :data:`twin.machining.inspection.FEATURES`): its
    settings the pydantic ``spec`` (with ``type: Literal[name]``), its value the builder of its
    model from its spec or what uses it (the registry says the arguments), its summary the first
    line of the spec's docstring (less a leading ``<name>: ``); each kind's module calls this at
    import."""
    summary = (spec.__doc__ or name).strip().splitlines()[0].removeprefix(f"{name}: ")
    return registry.add(name, build, summary=summary, settings=spec)


def tagged_union(registry: Registry):
    """The pydantic type of a table that is any of ``registry``'s kinds, told apart by ``type``
    (a union built at run time from the registered specs)."""
    specs = tuple(kind.settings for kind in registry.values())
    return Annotated[Union[specs], Field(discriminator="type")]  # noqa: UP007 (a union built at run time)
