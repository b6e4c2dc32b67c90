"""The machine file's schema (pydantic: ``[machine]``, ``[axes.<a>]`` of a ball-screw or a
linear-motor archetype, ``[axes.<a>.limits]``), reading one and writing one back with new values
(a calibrated machine).  :mod:`twin.machines.datasheet` makes a machine of it."""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, ClassVar, Literal

from pydantic import BaseModel, Field, ValidationError, model_validator
from pydantic_core import core_schema

from twin.errors import input_file
from twin.spec import StrictSpec, read_toml, validation_error


@dataclass(frozen=True)
class PhysicalRange:
    """The physical range of a machine-file value: generous bounds around what feed drives are
    built of, from a miniature stage to a large gantry, so that any value inside gives a model
    every command computes with (a 1e12 m screw overflowed the transfer function's
    coefficients, a 1 s delay left the fidelity check's 1 s test input without a response).

    Attributes
    ----------
    low, high : float
        The bounds, inclusive (in the key's unit).
    why : str
        What the bounds stand for (the error line says it).
    rigid : bool
        Whether inf is allowed too (a stiffness: a rigid link).
    zero : bool
        Whether 0 is allowed too (an ideal encoder).
    """

    low: float
    high: float
    why: str
    rigid: bool = False
    zero: bool = False

    def check(self, value: float) -> float:
        """``value`` if it lies within the range (or is inf where rigid), else a ValueError."""
        if self.contains(value):
            return value
        raise ValueError(f"must be {self.describe()}: {self.why}")

    def contains(self, value: float) -> bool:
        """Whether ``value`` lies within the range (or is inf where rigid, 0 where zero)."""
        return self.low <= value <= self.high or (self.rigid and value == math.inf) or (self.zero and value == 0)

    def describe(self) -> str:
        """``within [low, high]``, with ``or inf (rigid)`` or ``or 0``."""
        return (
            f"within [{self.low:g}, {self.high:g}]"
            + (" or inf (rigid)" if self.rigid else "")
            + (" or 0" if self.zero else "")
        )

    def __get_pydantic_core_schema__(self, source, handler):
        """Pydantic's hook: the range checked after the field's own type."""
        return core_schema.no_info_after_validator_function(self.check, handler(source))


def physical_range(model: type[BaseModel], key: str) -> PhysicalRange | None:
    """The :class:`PhysicalRange` of ``model``'s field ``key`` (None: no range)."""
    return next((m for m in model.model_fields[key].metadata if isinstance(m, PhysicalRange)), None)


#: Masses (kg): a miniature stage's 1 g carriage to a 100 t table.
Mass = Annotated[float, PhysicalRange(1e-3, 1e5, "from a miniature stage's 1 g carriage to a 100 t table")]
#: Masses that may be 0 (a nut: part of the table).
MassOrZero = Annotated[float, PhysicalRange(0.0, 1e5, "up to a 100 t table")]
#: Rotary inertias (kg m^2): a miniature motor's rotor (Maxon EC 4: 1e-9 kg m^2) to a 100 kW
#: servo's or a large screw's.
Inertia = Annotated[float, PhysicalRange(1e-9, 10.0, "a miniature motor's rotor to a 100 kW servo's")]
InertiaOrZero = Annotated[float, PhysicalRange(0.0, 10.0, "up to a 100 kW servo's rotor")]
#: A rotary stiffness (N m/rad; inf: rigid) and damping (N m s/rad).
Torsion = Annotated[
    float, Field(allow_inf_nan=True), PhysicalRange(1.0, 1e9, "a miniature coupling's to a spindle's", rigid=True)
]
TorsionDamping = Annotated[float, PhysicalRange(0.0, 1e4, "up to 1e4 N m s/rad")]
#: An axial stiffness (N/m; inf: rigid) and damping (N s/m).
Axial = Annotated[
    float, Field(allow_inf_nan=True), PhysicalRange(1e3, 1e12, "a belt's to a hydrostatic screw's", rigid=True)
]
AxialDamping = Annotated[float, PhysicalRange(0.0, 1e8, "up to 1e8 N s/m")]
#: Lengths and travels (m).
Length = Annotated[float, PhysicalRange(1e-3, 30.0, "from 1 mm to a 30 m gantry")]
#: Screw diameters (m).
Diameter = Annotated[float, PhysicalRange(1e-3, 0.5, "from a 1 mm miniature screw to a 0.5 m press screw")]
#: Drive gains: a motor's constant (N m/A, N/A), an amplifier's gain (A/V), their product.
MotorConstant = Annotated[float, PhysicalRange(1e-4, 1e4, "a miniature motor's to a linear motor's")]
AmplifierGain = Annotated[float, PhysicalRange(1e-4, 100.0, "a +-10 V command of 1 mA to one of 1 kA")]
DriveGain = Annotated[float, PhysicalRange(1e-8, 1e6, "a motor's constant times an amplifier's gain")]
#: The interpolator's limits: velocity (m/s), acceleration (m/s^2), jerk (m/s^3).
Velocity = Annotated[float, PhysicalRange(1e-6, 100.0, "from 1 um/s to 100 m/s")]
Acceleration = Annotated[float, PhysicalRange(1e-6, 1e4, "from 1 um/s^2 to 1000 g")]
Jerk = Annotated[float, PhysicalRange(1e-6, 1e8, "from 1 um/s^3 to 1e8 m/s^3")]
#: Coulomb friction (N).
Force = Annotated[float, PhysicalRange(0.0, 1e6, "up to 1 MN")]
#: An encoder's resolution (m; 0: ideal) and a motor encoder's counts per revolution (0: ideal).
Resolution = Annotated[float, PhysicalRange(1e-12, 1e-3, "0 (ideal), an interferometer's 1 pm to 1 mm", zero=True)]
Counts = Annotated[float, PhysicalRange(1.0, 2.0**32, "0 (ideal), one count to 32 bits", zero=True)]
#: Motor revolutions per screw revolution, and table travel per screw revolution (m).
GearRatio = Annotated[float, PhysicalRange(1e-2, 1e3, "a 1:100 step-up belt to a 1000:1 gearbox")]
Lead = Annotated[float, PhysicalRange(1e-4, 1.0, "a 0.1 mm screw to a belt pulley's 1 m circumference")]
#: A drive's transport delay (s): current loop and bus cycles are 0.1-2 ms.
Delay = Annotated[float, PhysicalRange(0.0, 0.01, "a drive's current loop and bus cycles, a slow field bus's 10 ms")]


class LimitsSpec(StrictSpec):
    """An axis's limits for the G-code interpolator."""

    velocity_m_per_s: Velocity
    acceleration_m_per_s2: Acceleration
    jerk_m_per_s3: Jerk
    source: str = "the machine file"


class AxisSpec(StrictSpec):
    """What every axis archetype has."""

    table_mass_kg: Mass = Field(description="the axis's own moving table or carriage (without what rides on it)")
    friction_coulomb_N: Force = 0.0
    friction_viscous_N_s_per_m: AxialDamping = 0.0
    travel_m: Length
    encoder_resolution_m: Resolution = 0.0
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
    motor_inertia_kg_m2: Inertia
    motor_mass_kg: Mass = Field(description="what an axis below carries of this axis's motor")
    torque_constant_N_m_per_A: MotorConstant | None = None
    amplifier_gain_A_per_V: AmplifierGain | None = None
    drive_gain_N_m_per_V: DriveGain | None = Field(None, description="a torque-mode drive, instead of the two")
    gear_ratio: GearRatio = Field(1.0, description="motor revolutions per screw revolution")
    gear_inertia_kg_m2: InertiaOrZero = Field(0.0, description="gearbox or pulleys, at the motor shaft")
    coupling_inertia_kg_m2: InertiaOrZero = 0.0
    k_torsion_N_m_per_rad: Torsion = Field(math.inf, description="the coupling's torsional stiffness")
    c_torsion_N_m_s_per_rad: TorsionDamping = 0.0
    k_screw_torsion_N_m_per_rad: Torsion = Field(
        math.inf, description="the screw's own torsion up to the nut, G J / L (in series with the coupling's)"
    )
    screw_lead_m: Lead = Field(description="table travel per screw revolution")
    screw_diameter_m: Diameter
    screw_length_m: Length
    screw_inertia_kg_m2: Inertia | None = Field(None, description="default: a steel cylinder")
    nut_mass_kg: MassOrZero = 0.0
    screw_root_diameter_m: Diameter | None = Field(
        None,
        description="the shaft's root diameter: with it the twin computes the axial stiffness (nut, bearings and "
        "the shaft up to the nut in series) and the screw's torsion from the nut's position",
    )
    screw_support: Literal["fixed_fixed", "fixed_supported", "fixed_free"] = Field(
        "fixed_fixed",
        description="the shaft's bearings: both ends fixed; the drive end fixed and the far end supported "
        "(radially only: axially as fixed_free); or the drive end only",
    )
    nut_position_m: Length | None = Field(
        None, description="the nut's distance from the drive end's bearing; default: half the screw's length"
    )
    k_nut_N_per_m: Axial = Field(math.inf, description="the preloaded nut's axial stiffness (with the root diameter)")
    k_bearing_N_per_m: Axial = Field(
        math.inf, description="the fixed bearings' axial stiffness (with the root diameter)"
    )
    motor_encoder_counts_per_rev: Counts = Field(
        0.0, description="the motor encoder's counts per motor revolution (0: ideal)"
    )
    k_axial_N_per_m: Axial = math.inf
    c_axial_N_s_per_m: AxialDamping = 0.0

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
            raise ValueError(
                f"nut_position_m = {self.nut_position_m} must be within the screw's {self.screw_length_m} m"
            )
        return self


class LinearMotorSpec(AxisSpec):
    """A linear motor driving its carriage directly."""

    type: Literal["linear_motor"]
    force_constant_N_per_A: MotorConstant | None = None
    amplifier_gain_A_per_V: AmplifierGain | None = None
    drive_gain_N_per_V: DriveGain | None = Field(None, description="a force-mode drive, instead of the two")

    drive_keys: ClassVar = ("drive_gain_N_per_V", "force_constant_N_per_A", "amplifier_gain_A_per_V")


class MachineSpec(StrictSpec):
    """The ``[machine]`` table."""

    name: str = Field(pattern=r"^[A-Za-z0-9_.-]{1,64}$")
    summary: str = ""
    sources: str = Field("", description="where the values come from")
    stacking: list[Literal["x", "y"]] = Field(min_length=1, max_length=2)
    workpiece_mass_kg: Mass
    delay_s: Delay = 0.0
    #: the physics step (s): 1 us (a fidelity check then simulates 6e7 steps, minutes) to 10 ms
    timestep_s: float = Field(1e-4, ge=1e-6, le=1e-2)
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
        raise validation_error(exc, data, f"{path.name}: ", "machine file") from None


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
    for key, value in spec.machine.model_dump(exclude_none=True).items():
        lines.append(f"{key} = {_toml_value(value)}")
    for a, ax in spec.axes.items():
        lines += ["", f"[axes.{a}]"]
        for key, value in ax.model_dump(exclude={"limits"}, exclude_none=True, exclude_unset=True).items():
            lines.append(f"{key} = {_toml_value(value)}")
        lines += ["", f"[axes.{a}.limits]"]
        for key, value in ax.limits.model_dump().items():
            lines.append(f"{key} = {_toml_value(value)}")
    return "\n".join(lines).lstrip("\n") + "\n"
