"""Controller and observer kinds by name, as scenario files and the CLI refer to them.

Each kind is declared once, in a module of :mod:`controllers.kinds`: its parameters as a
pydantic model (names, units in the field descriptions, defaults and limits), its builder, and
its docs line (the builder's docstring), as an entry of a :class:`controllers.registries.Registry`.  ``twin
list``, the scenario's error lines and the docs site read :data:`CONTROLLERS` and
:data:`OBSERVERS` (through :mod:`twin.catalogue`); adding a kind is one decorated builder.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from pydantic import BaseModel, ConfigDict, ValidationError

from controllers.blocks import Controller, with_feedforward
from controllers.registries import Registry


@dataclass
class Context:
    """What a builder knows besides its parameters.

    Attributes
    ----------
    dt : float
        Control period (s).
    axes : tuple of str
        The axes the controller serves (one entry of ``[controllers.<axis>]``, or every axis
        for ``[controller]``).
    method : {"tustin", "zoh"}
        Discretization of continuous models.
    plants : dict of str to SisoTf
        The machine's nominal model per axis (m/V), for model-based blocks (observers).
    parts : list of Controller
        The already built parts of a ``sum``.
    delay_s : float
        The machine's drive delay (s), for model-based blocks.
    """

    dt: float
    axes: tuple[str, ...] = ("x",)
    method: str = "tustin"
    plants: dict = field(default_factory=dict)
    parts: list = field(default_factory=list)
    delay_s: float = 0.0


class Params(BaseModel):
    """The base of every kind's parameters: unknown names, non-finite numbers and values of the
    wrong type (a string for a number, a number for a flag) are errors."""

    model_config = ConfigDict(extra="forbid", strict=True, allow_inf_nan=False, frozen=True)


class NoParams(Params):
    """A kind without parameters."""


class ParameterError(ValueError):
    """A parameter a kind cannot use.

    Attributes
    ----------
    field : str
        The parameter's name (dotted below it for nested values, e.g. ``num.1``).
    value : object
        The value given.
    reason : str
        Why it cannot be used.
    """

    def __init__(self, field: str, value: Any, reason: str):
        super().__init__(f"{field} = {value!r}: {reason}")
        self.field, self.value, self.reason = field, value, reason


#: Controller kinds by name, in registration order (:mod:`controllers.kinds`): each entry's
#: settings are its :class:`Params`, its value the builder ``build(params, ctx) -> Controller``
#: and its summary the builder's docstring.
CONTROLLERS: Registry[Callable[[Any, Context], Controller]] = Registry("controller")
#: Observer add-on kinds by name, in registration order: each entry's value is the builder
#: ``build(params, ctx) -> list of blocks`` (every served axis's).
OBSERVERS: Registry[Callable[[Any, Context], list]] = Registry("observer")


def _registering(registry: Registry, name: str, params: type[Params]):
    """A decorator that adds its builder to ``registry`` as kind ``name`` (its docstring the
    kind's summary)."""

    def register(build):
        registry.add(name, build, summary=build.__doc__ or name, settings=params)
        return build

    return register


def controller_kind(name: str, params: type[Params] = NoParams):
    """Register the decorated ``build(params, ctx) -> Controller`` as controller kind ``name``."""
    return _registering(CONTROLLERS, name, params)


def observer_kind(name: str, params: type[Params] = NoParams):
    """Register the decorated ``build(params, ctx) -> list of blocks`` as observer kind ``name``."""
    return _registering(OBSERVERS, name, params)


def validate_params(name: str, model: type[BaseModel] | None, params: dict | None) -> Any:
    """``params`` checked against kind ``name``'s model (None: it takes none).

    Raises
    ------
    ParameterError
        The first parameter it cannot use, named.
    """
    model = model or NoParams
    try:
        return model.model_validate(dict(params or {}))
    except ValidationError as exc:
        error = exc.errors()[0]
        where = ".".join(str(p) for p in error["loc"])
        if error["type"] == "extra_forbidden":
            known = ", ".join(model.model_fields) or "none"
            raise ParameterError(
                where, error["input"], f"not a parameter of {name} (its parameters: {known})"
            ) from None
        if error["type"] == "missing":
            raise ParameterError(where, None, f"{name} needs it") from None
        raise ParameterError(where, error["input"], error["msg"]) from None


def make_controller(
    name: str,
    dt: float,
    params: dict | None = None,
    *,
    method: str = "tustin",
    velocity_ff=0.0,
    acceleration_ff=0.0,
    axes: tuple[str, ...] = ("x",),
    plants: dict | None = None,
    parts=(),
    delay_s: float = 0.0,
) -> Controller:
    """Build controller kind ``name`` for ``axes`` at period ``dt`` (s).

    ``velocity_ff``, ``acceleration_ff`` (V/(m/s), V/(m/s^2), one value or one per axis) add
    reference feedforward to u; ``plants`` are the machine's per-axis models (m/V) and
    ``delay_s`` its drive delay (s), for model-based designs; ``parts`` are the built
    controllers a ``sum`` adds up.  An observer is added with ``with_correction(ctrl,
    make_observers(...))``.

    Raises
    ------
    KeyError
        Unknown name.
    ParameterError
        A parameter the kind does not take, or of the wrong type or range.
    ValueError
        Values the design cannot use.
    """
    ctx = Context(dt, tuple(axes), method, dict(plants or {}), list(parts), delay_s)
    return build_controller(name, params, ctx, velocity_ff=velocity_ff, acceleration_ff=acceleration_ff)


def build_controller(
    name: str, params: dict | None, ctx: Context, *, velocity_ff=0.0, acceleration_ff=0.0
) -> Controller:
    """Build controller kind ``name`` in the build context ``ctx``: :func:`make_controller` for a
    caller that holds a context already (the same errors)."""
    kind = CONTROLLERS[name]
    ctrl = kind.value(validate_params(name, kind.settings, params), ctx)
    ctrl.name = name
    return with_feedforward(ctrl, velocity_ff, acceleration_ff)


def make_observers(name: str, params: dict | None, ctx: Context) -> list:
    """Observer blocks of kind ``name`` for every axis of ``ctx``.

    Raises
    ------
    KeyError
        Unknown name.
    ParameterError
        A parameter the kind does not take, or of the wrong type or range.
    ValueError
        Values the design cannot use.
    """
    kind = OBSERVERS[name]
    return kind.value(validate_params(name, kind.settings, params), ctx)


# Last, so the kinds (which import this module) find it whole: importing the registry gives every kind.
import controllers.kinds  # noqa: E402, F401
