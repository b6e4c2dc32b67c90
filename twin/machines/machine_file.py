"""The machine file's schema (pydantic: ``[machine]``, ``[axes.<a>]`` of a ball-screw or a
linear-motor archetype, ``[axes.<a>.limits]``), reading one and writing one back with new values
(a calibrated machine).  :mod:`twin.machines.datasheet` makes a machine of it."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated, ClassVar, Literal

from pydantic import Field, NonNegativeFloat, PositiveFloat, ValidationError, model_validator

from twin.errors import input_file
from twin.spec import StrictSpec, read_toml, validation_error

#: A stiffness: positive, infinite for a rigid link (the default).
Stiffness = Annotated[float, Field(gt=0, allow_inf_nan=True)]


class LimitsSpec(StrictSpec):
    """An axis's limits for the G-code interpolator."""

    velocity_m_per_s: PositiveFloat
    acceleration_m_per_s2: PositiveFloat
    jerk_m_per_s3: PositiveFloat
    source: str = "the machine file"


class AxisSpec(StrictSpec):
    """What every axis archetype has."""

    table_mass_kg: PositiveFloat = Field(
        description="the axis's own moving table or carriage (without what rides on it)"
    )
    friction_coulomb_N: NonNegativeFloat = 0.0
    friction_viscous_N_s_per_m: NonNegativeFloat = 0.0
    travel_m: PositiveFloat
    encoder_resolution_m: NonNegativeFloat = 0.0
    limits: LimitsSpec

    #: The drive's gain keys: (the drive's own V-to-torque/force gain, the motor's constant,
    #: the amplifier's gain); a file gives the first or the other two.
    drive_keys: ClassVar[tuple[str, str, str]]

    @model_validator(mode="after")
    def _one_drive_gain(self):
        direct, constant, amplifier = self.drive_keys
        given = [getattr(self, k) is not None for k in self.drive_keys]
        if given not in ([True, False, False], [False, True, True]):
            raise ValueError(f"give {direct}, or {constant} and {amplifier} (not both)")
        return self


class BallScrewSpec(AxisSpec):
    """A rotary servo motor, an optional gearbox or belt, a coupling, a ball screw and its nut."""

    type: Literal["ball_screw"]
    motor_inertia_kg_m2: PositiveFloat
    motor_mass_kg: PositiveFloat = Field(description="what an axis below carries of this axis's motor")
    torque_constant_N_m_per_A: PositiveFloat | None = None
    amplifier_gain_A_per_V: PositiveFloat | None = None
    drive_gain_N_m_per_V: PositiveFloat | None = Field(None, description="a torque-mode drive, instead of the two")
    gear_ratio: PositiveFloat = Field(1.0, description="motor revolutions per screw revolution")
    gear_inertia_kg_m2: NonNegativeFloat = Field(0.0, description="gearbox or pulleys, at the motor shaft")
    coupling_inertia_kg_m2: NonNegativeFloat = 0.0
    k_torsion_N_m_per_rad: Stiffness = Field(math.inf, description="the coupling's torsional stiffness")
    c_torsion_N_m_s_per_rad: NonNegativeFloat = 0.0
    k_screw_torsion_N_m_per_rad: Stiffness = Field(
        math.inf, description="the screw's own torsion up to the nut, G J / L (in series with the coupling's)"
    )
    screw_lead_m: PositiveFloat = Field(description="table travel per screw revolution")
    screw_diameter_m: PositiveFloat
    screw_length_m: PositiveFloat
    screw_inertia_kg_m2: PositiveFloat | None = Field(None, description="default: a steel cylinder")
    nut_mass_kg: NonNegativeFloat = 0.0
    screw_root_diameter_m: PositiveFloat | None = Field(
        None,
        description="the shaft's root diameter: with it the twin computes the axial stiffness (nut, bearings and "
        "the shaft up to the nut in series) and the screw's torsion from the nut's position",
    )
    screw_support: Literal["fixed_fixed", "fixed_free"] = Field(
        "fixed_fixed", description="the shaft's bearings: both ends fixed, or the drive end only"
    )
    nut_position_m: PositiveFloat | None = Field(
        None, description="the nut's distance from the drive end's bearing; default: half the screw's length"
    )
    k_nut_N_per_m: Stiffness = Field(
        math.inf, description="the preloaded nut's axial stiffness (with the root diameter)"
    )
    k_bearing_N_per_m: Stiffness = Field(
        math.inf, description="the fixed bearings' axial stiffness (with the root diameter)"
    )
    motor_encoder_counts_per_rev: NonNegativeFloat = Field(
        0.0, description="the motor encoder's counts per motor revolution (0: ideal)"
    )
    k_axial_N_per_m: Stiffness = math.inf
    c_axial_N_s_per_m: NonNegativeFloat = 0.0

    drive_keys: ClassVar = ("drive_gain_N_m_per_V", "torque_constant_N_m_per_A", "amplifier_gain_A_per_V")

    @model_validator(mode="after")
    def _one_stiffness_source(self):
        if self.screw_root_diameter_m is None:
            stray = [k for k in ("nut_position_m", "k_nut_N_per_m", "k_bearing_N_per_m") if k in self.model_fields_set]
            if stray:
                raise ValueError(f"{stray[0]} needs screw_root_diameter_m (the shaft the stiffness is computed from)")
            return self
        given = [k for k in ("k_axial_N_per_m", "k_screw_torsion_N_m_per_rad") if k in self.model_fields_set]
        if given:
            raise ValueError(f"give {given[0]} or screw_root_diameter_m (which computes it), not both")
        if self.screw_root_diameter_m >= self.screw_diameter_m:
            raise ValueError(f"screw_root_diameter_m = {self.screw_root_diameter_m} must be below screw_diameter_m")
        if self.nut_position_m is not None and self.nut_position_m >= self.screw_length_m:
            raise ValueError(f"nut_position_m = {self.nut_position_m} must be within screw_length_m")
        return self


class LinearMotorSpec(AxisSpec):
    """A linear motor driving its carriage directly."""

    type: Literal["linear_motor"]
    force_constant_N_per_A: PositiveFloat | None = None
    amplifier_gain_A_per_V: PositiveFloat | None = None
    drive_gain_N_per_V: PositiveFloat | None = Field(None, description="a force-mode drive, instead of the two")

    drive_keys: ClassVar = ("drive_gain_N_per_V", "force_constant_N_per_A", "amplifier_gain_A_per_V")


class MachineSpec(StrictSpec):
    """The ``[machine]`` table."""

    name: str = Field(pattern=r"^[A-Za-z0-9_.-]{1,64}$")
    summary: str = ""
    sources: str = Field("", description="where the values come from")
    stacking: list[Literal["x", "y"]] = Field(min_length=1, max_length=2)
    workpiece_mass_kg: PositiveFloat
    delay_s: NonNegativeFloat = Field(0.0, le=1.0)
    timestep_s: float = Field(1e-4, ge=1e-7, le=1e-2)
    planner_mode: Literal["jerk_limited", "linuxcnc"] | None = Field(
        None, description="how a program is planned for this machine unless a scenario's [planner] mode says"
    )


class MachineFile(StrictSpec):
    """A whole machine file."""

    machine: MachineSpec
    axes: dict[str, Annotated[BallScrewSpec | LinearMotorSpec, Field(discriminator="type")]]

    @model_validator(mode="after")
    def _axes_match_stacking(self):
        if sorted(self.axes) != sorted(self.machine.stacking) or len(set(self.machine.stacking)) != len(self.axes):
            raise ValueError(f"[axes.*] tables {sorted(self.axes)} must be the stacking's axes {self.machine.stacking}")
        return self


#: Parameter metadata by file key: unit and whether the value may be infinite or zero.
_UNITS = {
    "kg_m2": "kg m^2",
    "kg": "kg",
    "N_m_per_A": "N m/A",
    "A_per_V": "A/V",
    "N_m_per_V": "N m/V",
    "N_per_A": "N/A",
    "N_per_V": "N/V",
    "N_m_per_rad": "N m/rad",
    "N_m_s_per_rad": "N m s/rad",
    "N_per_m": "N/m",
    "N_s_per_m": "N s/m",
    "N": "N",
    "m": "m",
    "s": "s",
    "counts_per_rev": "1/rev",
}


def unit_of(key: str) -> str:
    """The unit of a file key, read from its suffix (``table_mass_kg``: kg; ``-`` for none)."""
    for suffix, unit in sorted(_UNITS.items(), key=lambda kv: -len(kv[0])):
        if key.endswith("_" + suffix):
            return unit
    return "-"


def read_machine_file(path: str | Path) -> MachineFile:
    """Read and validate a machine file.

    Raises
    ------
    TwinInputError
        A missing or unreadable file, malformed TOML, or a value the schema refuses (named by
        its table and key: ``mill.toml: axes.x.table_mass_kg = -3: ...``).
    """
    path = input_file(path, "machine", "no such machine file")
    data = read_toml(path, "machine file")
    try:
        return MachineFile.model_validate(data)
    except ValidationError as exc:
        raise validation_error(exc, f"{path.name}: ", ("ball_screw", "linear_motor"), "machine file") from None


def _toml_value(value) -> str:
    if isinstance(value, float):
        return "inf" if math.isinf(value) else repr(value)
    if isinstance(value, str):
        return '"' + value.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(value, list):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    return repr(value)


def machine_file_text(machine_file: MachineFile, params: dict[str, float], note: str = "") -> str:
    """``machine_file`` with the parameter values ``params`` (a calibrated machine), as TOML
    text; ``note`` goes in a comment at the top."""
    spec = machine_file.model_copy(deep=True)
    for key, value in params.items():
        if key in ("workpiece_mass_kg", "delay_s"):
            setattr(spec.machine, key, value)
            continue
        axis, _, field = key.partition("_")
        setattr(spec.axes[axis], field, value)
    lines = [f"# {line}" for line in note.splitlines()] + ["", "[machine]"]
    for key, value in spec.machine.model_dump().items():
        lines.append(f"{key} = {_toml_value(value)}")
    for a, ax in spec.axes.items():
        lines += ["", f"[axes.{a}]"]
        for key, value in ax.model_dump(exclude={"limits"}, exclude_none=True, exclude_unset=True).items():
            lines.append(f"{key} = {_toml_value(value)}")
        lines += ["", f"[axes.{a}.limits]"]
        for key, value in ax.limits.model_dump().items():
            lines.append(f"{key} = {_toml_value(value)}")
    return "\n".join(lines).lstrip("\n") + "\n"
