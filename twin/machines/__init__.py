"""Machine registry: ``build(name, overrides)`` returns a compiled :class:`BuiltMachine`.

Each machine is one module here whose class registers itself (:func:`register_machine`): its
parameters with units, sources and limits, its MJCF file, its docs line; every module of this
package is imported below, so a new machine is one module, its MJCF folder and its tests.
"""

from __future__ import annotations

import importlib
import pkgutil
from functools import lru_cache

from twin.errors import TwinInputError, input_file
from twin.machines.base import MACHINES, Axis, BuiltMachine, Machine, Parameter, mjcf_dir, register_machine
from twin.machines.datasheet import load_machine_file

for _module in pkgutil.iter_modules(__path__):
    importlib.import_module(f"{__name__}.{_module.name}")


def is_machine_file(name: str) -> bool:
    """Whether ``name`` names a machine file (ends in ``.toml``) rather than a bundled machine."""
    return str(name).endswith(".toml")


@lru_cache(maxsize=32)
def _machine_file(path: str, modified_ns: int) -> Machine:
    return load_machine_file(path)


def get_machine(name: str) -> Machine:
    """Look a machine up by name, or read a machine file (a path ending in ``.toml``).

    Raises
    ------
    TwinInputError
        If no machine has that name, or the machine file is missing or invalid.
    """
    if is_machine_file(name):
        path = input_file(name, "machine", "no such machine file").resolve()
        return _machine_file(str(path), path.stat().st_mtime_ns)
    return MACHINES.lookup(
        name, field="machine", alternative="or a machine file, FILE.toml", error=TwinInputError
    ).value


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
    "is_machine_file",
    "mjcf_dir",
    "register_machine",
]
