"""Machine registry: ``build(name, overrides)`` returns a compiled :class:`BuiltMachine`."""

from __future__ import annotations

from twin.errors import TwinInputError
from twin.machines.base import Axis, BuiltMachine, Machine, Parameter, mjcf_dir
from twin.machines.cncmt import CNCMT, CNCMTXY
from twin.machines.googol import GoogolXY
from twin.machines.linear_motor import LinearMotorXY
from twin.machines.sabau import SabauXY

MACHINES: dict[str, Machine] = {m.name: m for m in (CNCMT(), CNCMTXY(), GoogolXY(), LinearMotorXY(), SabauXY())}


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


__all__ = ["MACHINES", "Axis", "BuiltMachine", "Machine", "Parameter", "build", "get_machine", "mjcf_dir"]
