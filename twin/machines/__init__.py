"""Machine registry: ``build(name, overrides)`` returns a compiled :class:`BuiltMachine`.

Each machine is one module here whose class registers itself (:func:`register_machine`): its
parameters with units, sources and limits, its MJCF file, its docs line; every module of this
package is imported below, so a new machine is one module, its MJCF folder and its tests.
"""

from __future__ import annotations

import importlib
import pkgutil

from twin.errors import TwinInputError
from twin.machines.base import MACHINES, Axis, BuiltMachine, Machine, Parameter, mjcf_dir, register_machine

for _module in pkgutil.iter_modules(__path__):
    importlib.import_module(f"{__name__}.{_module.name}")


def get_machine(name: str) -> Machine:
    """Look a machine up by name.

    Raises
    ------
    TwinInputError
        If no machine has that name.
    """
    try:
        return MACHINES[name]
    except KeyError:
        raise TwinInputError("machine", name, f"unknown machine (known: {', '.join(MACHINES)})") from None


def build(name: str, overrides: dict[str, float] | None = None, timestep_s: float | None = None) -> BuiltMachine:
    """Build machine ``name`` with parameter ``overrides`` (source symbols)."""
    return get_machine(name).build(overrides, timestep_s)


__all__ = [
    "MACHINES",
    "Axis",
    "BuiltMachine",
    "Machine",
    "Parameter",
    "build",
    "get_machine",
    "mjcf_dir",
    "register_machine",
]
