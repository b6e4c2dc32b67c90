"""The registry of disturbance kinds (the scenario's ``[[disturbances]]`` entries): each kind's
module registers its pydantic spec (``type = "<name>"``) and the builder of its model."""

from __future__ import annotations

from collections.abc import Callable

from controllers.registries import Entry, Registry
from twin.spec import KindSpec, register_kind

#: The base of every disturbance kind's spec.
DisturbanceSpecBase = KindSpec
#: Disturbance kinds by name, in registration order: each builder is ``build(spec, axis_names,
#: seed, field) -> model``, the force model on the workpiece (``kernel_arrays``) or the
#: drive-input disturbance (``input_V``) for a machine with those axes, ``seed`` the entry's (or
#: the scenario's), ``field`` the entry's path for errors.
DISTURBANCES: Registry[Callable] = Registry("disturbance")


def register(name: str, spec: type[KindSpec], build: Callable) -> Entry:
    """Add a disturbance kind; its module calls this at import."""
    return register_kind(DISTURBANCES, name, spec, build)
