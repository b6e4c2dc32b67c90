"""Machines described by a TOML file of datasheet values (the user's own machine).

A machine file names the axes, their archetype and their datasheet values, units in every key::

    [machine]
    name = "mid_size_xy"
    stacking = ["x", "y"]          # the first axis sits on the bed, each next one rides on it
    workpiece_mass_kg = 20.0

    [axes.x]
    type = "ball_screw"            # or "linear_motor"
    motor_inertia_kg_m2 = 1.8e-4
    ...
    [axes.x.limits]
    velocity_m_per_s = 0.5
    ...

From it :class:`DatasheetMachine` generates the MJCF with :class:`mujoco.MjSpec` (no XML per
machine) and derives the transfer-function model from the same values: a chain of masses in
table-travel units (motor side, screw, table) joined by the coupling's torsional spring and the
screw-nut-bearing axial spring, each rigid where its stiffness is infinite (the default).  Every
value is a parameter by the symbol ``<axis>_<key>`` (``x_table_mass_kg``) or ``<key>`` for the
machine's own (``workpiece_mass_kg``), which ``--set``, sweeps and calibration change.

The MJCF, per ball-screw axis ``a`` (hinges about the axis, the slide along it)::

    a_motor_rotor   hinge a_motor   rotor + gearbox inertia (+ half the coupling's where it is
                                    compliant); the drive's torque (actuator a_drive)
    a_screw         hinge a_screw   screw + coupling inertia (+ nut mass x lead^2 where the nut
                                    is compliant)
    a_table         slide a_table   table mass (+ a rigid nut's), guideway viscous damping,
                                    Coulomb friction, travel limits

linked by ``a_gear`` (motor = gear_ratio x screw) and ``a_nut`` (screw = travel / lead): a
joint equality where the stiffness is infinite (the hand-written models' gears), else a spring
tendon ``a_gear_spring`` (length motor / gear_ratio - screw, k_torsion, c_torsion) or
``a_nut_spring`` (length lead x screw - table, k_axial, c_axial). A linear-motor axis is its
carriage ``a_table`` on the slide ``a_table`` with the drive's force on it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, ClassVar, Literal

import mujoco
import numpy as np
from pydantic import Field, NonNegativeFloat, PositiveFloat, ValidationError, model_validator

from controllers.lti import SisoTf
from twin.errors import TwinInputError, input_file
from twin.machines.base import Axis, Machine, MotionLimits, Parameter, diagonal_plant
from twin.spec import StrictSpec, read_toml, validation_error

#: Density of screw steel (kg/m^3), for a screw inertia the file does not give.
STEEL_DENSITY_KG_PER_M3 = 7850.0
#: Young's modulus of screw steel (Pa), as THK's ball screw catalogue takes it (2.06e5 N/mm^2),
#: and its shear modulus (Pa): the shaft's stiffness from its root diameter.
STEEL_YOUNG_MODULUS_PA = 2.06e11
STEEL_SHEAR_MODULUS_PA = 7.93e10
#: The largest 2 pi f h (fastest mode f, physics step h) a machine file may be simulated at:
#: MuJoCo integrates its springs explicitly (semi-implicit Euler: 17 deg of phase a step at 0.3).
MAX_MODE_STEP_RAD = 0.3


def _geom(body, kind: str, size, rgba, **placement) -> None:
    """A massless geom (the bodies' inertials carry the masses): ``kind`` box or cylinder,
    ``size`` as MJCF, colour ``rgba`` (r, g, b), placed by ``pos`` or ``fromto``."""
    shape = {"box": mujoco.mjtGeom.mjGEOM_BOX, "cylinder": mujoco.mjtGeom.mjGEOM_CYLINDER}[kind]
    body.add_geom(type=shape, size=[*size, 0, 0][:3], rgba=[*rgba, 1.0], mass=0, **placement)


def _drive(spec, name: str, joint: str, gain: float) -> None:
    """The drive: torque (N m) or force (N) on ``joint`` = ``gain`` x the input (V)."""
    spec.add_actuator(name=name, target=joint, trntype=mujoco.mjtTrn.mjTRN_JOINT, gainprm=[gain] + [0.0] * 9)


def _link(spec, name: str, first: str, second: str, ratio: float, stiffness: float, damping: float) -> None:
    """Joint ``first`` = ``ratio`` x joint ``second``: a gear equality where ``stiffness`` is
    infinite, else a spring tendon whose length, ``first / ratio - second``, is the stretch."""
    if math.isinf(stiffness):
        eq = spec.add_equality(name=name, type=mujoco.mjtEq.mjEQ_JOINT, name1=first, name2=second)
        eq.data = np.r_[0.0, ratio, 0.0, 0.0, 0.0, np.zeros(len(eq.data) - 5)]
        eq.solref = list(EQUALITY_SOLREF)
        eq.solimp = list(EQUALITY_SOLIMP)
        return
    tendon = spec.add_tendon(name=f"{name}_spring")
    tendon.wrap_joint(first, 1.0 / ratio)
    tendon.wrap_joint(second, -1.0)
    tendon.stiffness = [stiffness, 0.0, 0.0]
    tendon.damping = [damping, 0.0, 0.0]


#: Time constant (s) and damping ratio of the gear equalities (as the hand-written models).
EQUALITY_SOLREF = (0.0002, 0.7)
EQUALITY_SOLIMP = (0.9999, 0.9999, 0.001, 0.5, 2.0)
#: Time constant (s) of the guideways' Coulomb friction (as the hand-written models).
FRICTION_SOLREF = (0.0002, 1.0)
DIRECTIONS = {"x": (1.0, 0.0, 0.0), "y": (0.0, 1.0, 0.0)}

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


def _unit(key: str) -> str:
    for suffix, unit in sorted(_UNITS.items(), key=lambda kv: -len(kv[0])):
        if key.endswith("_" + suffix):
            return unit
    return "-"


def screw_inertia_kg_m2(diameter_m: float, length_m: float) -> float:
    """Polar inertia (kg m^2) of a solid steel screw: pi rho d^4 L / 32."""
    return math.pi * STEEL_DENSITY_KG_PER_M3 * diameter_m**4 * length_m / 32.0


def screw_mass_kg(diameter_m: float, length_m: float) -> float:
    """Mass (kg) of a solid steel screw: rho pi d^2 L / 4."""
    return STEEL_DENSITY_KG_PER_M3 * math.pi * diameter_m**2 * length_m / 4.0


@dataclass(frozen=True)
class Chain:
    """One axis as masses in a row, in table-travel units (kg, N/m, N s/m).

    Attributes
    ----------
    masses_kg : tuple of float
        Motor side, screw side (nut included), table (with all it carries); merged where rigid.
    springs_N_per_m, dampers_N_s_per_m : tuple of float
        Between neighbouring masses (one fewer than masses).
    table_damping_N_s_per_m : float
        Guideway viscous friction, on the last mass.
    force_per_volt_N_per_V : float
        Drive force on the first mass per volt of input.
    """

    masses_kg: tuple[float, ...]
    springs_N_per_m: tuple[float, ...]
    dampers_N_s_per_m: tuple[float, ...]
    table_damping_N_s_per_m: float
    force_per_volt_N_per_V: float

    def transfer_function(self, output: Literal["table", "motor"] = "table") -> SisoTf:
        """Drive input (V) to table (or motor-side, in table travel) position (m), in exact
        polynomial arithmetic: with the dynamic stiffness Z(s) = M s^2 + C s + K (tridiagonal),
        X_j / F_0 = (-1)^j adj(Z)[j, 0] / det Z, the table's numerator the product of the
        springs' c s + k, the motor's the determinant of the chain without its first mass."""
        n = len(self.masses_kg)
        link = [np.array([c, k]) for k, c in zip(self.springs_N_per_m, self.dampers_N_s_per_m)]
        diagonal = []
        for i, m in enumerate(self.masses_kg):
            d = np.array([m, 0.0, 0.0])
            for j in (i - 1, i):
                if 0 <= j < n - 1:
                    d = np.polyadd(d, np.r_[0.0, link[j]])
            diagonal.append(np.polyadd(d, [self.table_damping_N_s_per_m, 0.0]) if i == n - 1 else d)

        def determinant(first: int) -> np.ndarray:
            """det of Z's lower-right block from mass ``first`` on (the continuant)."""
            before, current = np.array([1.0]), diagonal[first]
            for i in range(first + 1, n):
                before, current = (
                    current,
                    np.polysub(
                        np.polymul(diagonal[i], current), np.polymul(np.polymul(link[i - 1], link[i - 1]), before)
                    ),
                )
            return current

        if output == "table":
            num = np.array([1.0])
            for factor in link:
                num = np.polymul(num, factor)
        else:
            num = determinant(1) if n > 1 else np.array([1.0])
        den = determinant(0)
        den[-1] = 0.0  # det K = 0 exactly (no spring to the ground): the rigid-body pole at s = 0
        return SisoTf(self.force_per_volt_N_per_V * np.trim_zeros(num, "f"), den)


class DatasheetMachine(Machine):
    """A machine read from a machine file (see the module docstring)."""

    def __init__(self, path: Path, spec: MachineFile):
        self.path = path
        self.spec = spec
        m = spec.machine
        self.name = m.name
        self.summary = m.summary or f"machine file {path.name}"
        self.xml = ""
        self.feedback = "dual"
        self.axes = tuple(
            Axis(
                a,
                f"{a}_drive",
                f"{a}_table",
                *((f"{a}_motor", f"{a}_screw") if isinstance(ax, BallScrewSpec) else ()),
            )
            for a in m.stacking
            for ax in [spec.axes[a]]
        )
        self.motion_limits = {
            a: MotionLimits(
                spec.axes[a].limits.velocity_m_per_s,
                spec.axes[a].limits.acceleration_m_per_s2,
                spec.axes[a].limits.jerk_m_per_s3,
                spec.axes[a].limits.source,
            )
            for a in m.stacking
        }
        self.parameters = self._parameters()

    # -- parameters -------------------------------------------------------------------------

    def _parameters(self) -> dict[str, Parameter]:
        m = self.spec.machine
        out = {
            "workpiece_mass_kg": Parameter(m.workpiece_mass_kg, "kg", "workpiece mass"),
            "delay_s": Parameter(m.delay_s, "s", "drive transport delay", positive=False, nonnegative=True),
        }
        for a in m.stacking:
            ax = self.spec.axes[a]
            values = ax.model_dump(exclude={"type", "limits", "screw_support"})
            if isinstance(ax, BallScrewSpec):
                if ax.screw_inertia_kg_m2 is None:
                    values["screw_inertia_kg_m2"] = screw_inertia_kg_m2(ax.screw_diameter_m, ax.screw_length_m)
                if ax.screw_root_diameter_m is None:
                    del values["k_nut_N_per_m"], values["k_bearing_N_per_m"]  # the shaft's, not given
                else:
                    del values["k_axial_N_per_m"], values["k_screw_torsion_N_m_per_rad"]  # computed
                    if ax.nut_position_m is None:
                        values["nut_position_m"] = ax.screw_length_m / 2.0
            for key, value in values.items():
                if value is None:
                    continue
                field = type(ax).model_fields[key]
                positive = field.default != 0.0  # the keys that may be 0 default to 0 (friction, damping, ...)
                out[f"{a}_{key}"] = Parameter(
                    float(value),
                    _unit(key),
                    f"{a.upper()} axis ({ax.type}): {key}" + (f", {field.description}" if field.description else ""),
                    positive=positive,
                    nonnegative=not positive,
                    infinite=key.startswith(("k_axial", "k_torsion", "k_screw_torsion", "k_nut", "k_bearing")),
                )
        return out

    def _drive_gain(self, params, a: str) -> float:
        """Torque (N m/V) or force (N/V) per volt of drive input."""
        direct, constant, amplifier = self.spec.axes[a].drive_keys
        if f"{a}_{direct}" in params:
            return params[f"{a}_{direct}"]
        return params[f"{a}_{constant}"] * params[f"{a}_{amplifier}"]

    def _riding_mass_kg(self, params, a: str) -> float:
        """Mass (kg) of everything an axis's own moving parts carry: the axes above it and the workpiece."""
        stacking: list[str] = list(self.spec.machine.stacking)
        mass = params["workpiece_mass_kg"]
        for above in stacking[stacking.index(a) + 1 :]:
            mass += params[f"{above}_table_mass_kg"]
            if self.spec.axes[above].type == "ball_screw":
                mass += params[f"{above}_motor_mass_kg"] + params[f"{above}_nut_mass_kg"]
                mass += screw_mass_kg(params[f"{above}_screw_diameter_m"], params[f"{above}_screw_length_m"])
        return mass

    def chain(self, params, a: str) -> Chain:
        """Axis ``a`` as a :class:`Chain` (rigid links merged)."""
        table = params[f"{a}_table_mass_kg"] + self._riding_mass_kg(params, a)
        viscous = params[f"{a}_friction_viscous_N_s_per_m"]
        gain = self._drive_gain(params, a)
        if self.spec.axes[a].type == "linear_motor":
            return Chain((table,), (), (), viscous, gain)
        lead = params[f"{a}_screw_lead_m"] / (2.0 * math.pi)  # m/rad
        n = params[f"{a}_gear_ratio"]
        coupling = params[f"{a}_coupling_inertia_kg_m2"]
        k_t, k_a = self.torsion_N_m_per_rad(params, a), self.axial_N_per_m(params, a)
        motor = (
            (params[f"{a}_motor_inertia_kg_m2"] + params[f"{a}_gear_inertia_kg_m2"]) * n**2 + coupling / 2
        ) / lead**2
        screw = (params[f"{a}_screw_inertia_kg_m2"] + coupling / 2) / lead**2 + params[f"{a}_nut_mass_kg"]
        masses, springs, dampers = [motor, screw, table], [], []
        for k, c in (
            (k_t / lead**2, params[f"{a}_c_torsion_N_m_s_per_rad"] / lead**2),
            (k_a, params[f"{a}_c_axial_N_s_per_m"]),
        ):
            springs.append(k)
            dampers.append(c)
        # merge the rigid links, from the table down
        for i in (1, 0):
            if math.isinf(springs[i]):
                masses[i : i + 2] = [masses[i] + masses[i + 1]]
                del springs[i], dampers[i]
        return Chain(tuple(masses), tuple(springs), tuple(dampers), viscous, gain * n / lead)

    def plant(self, params, model):
        return diagonal_plant([self.chain(params, a).transfer_function() for a in self.spec.machine.stacking])

    def motor_plant(self, params, model):
        return tuple(self.chain(params, a).transfer_function("motor") for a in self.spec.machine.stacking)

    def motor_travel(self, params):
        return {
            a: params[f"{a}_screw_lead_m"] / (2.0 * math.pi) / params[f"{a}_gear_ratio"]
            for a in self.spec.machine.stacking
            if self.spec.axes[a].type == "ball_screw"
        }

    def delay(self, params):
        return params["delay_s"]

    def coulomb_symbols(self) -> tuple[str, ...]:
        return tuple(f"{a}_friction_coulomb_N" for a in self.spec.machine.stacking)

    def encoder_resolution(self, params) -> tuple[float, ...]:
        return tuple(params[f"{a}_encoder_resolution_m"] for a in self.spec.machine.stacking)

    def motor_encoder_resolution(self, params) -> tuple[float, ...]:
        travel = self.motor_travel(params)  # the ball-screw axes'
        counts = {a: params[f"{a}_motor_encoder_counts_per_rev"] for a in travel}
        return tuple(
            2.0 * math.pi * travel[a] / counts[a] if counts.get(a) else 0.0 for a in self.spec.machine.stacking
        )

    def couplings(self, params):
        pairs, leads = [], {}
        for a in self.spec.machine.stacking:
            if self.spec.axes[a].type != "ball_screw":
                continue
            lead = params[f"{a}_screw_lead_m"] / (2.0 * math.pi)
            if math.isinf(self.torsion_N_m_per_rad(params, a)):
                pairs.append((f"{a}_motor", f"{a}_screw", params[f"{a}_gear_ratio"]))
            if math.isinf(self.axial_N_per_m(params, a)):
                pairs.append((f"{a}_screw", f"{a}_table", 1.0 / lead))
            leads[a] = lead
        return pairs, leads

    # -- the MJCF ---------------------------------------------------------------------------

    def _screw_to_nut(self, params, a: str) -> tuple[float, float, float]:
        """The shaft's cross-section (m^2) and polar moment (m^4) from its root diameter, and
        the nut's distance from the drive end (m), where the file gives the root diameter."""
        d, position = params[f"{a}_screw_root_diameter_m"], params[f"{a}_nut_position_m"]
        if not position < params[f"{a}_screw_length_m"]:
            raise TwinInputError(
                f"{a}_nut_position_m", position, f"must be within the screw's {params[f'{a}_screw_length_m']} m"
            )
        return math.pi * d**2 / 4.0, math.pi * d**4 / 32.0, position

    def axial_N_per_m(self, params, a: str) -> float:
        """Axis ``a``'s axial stiffness (N/m): the file's ``k_axial_N_per_m``, or, with the
        shaft's root diameter, the nut, the bearings and the shaft up to the nut in series. The
        shaft at the nut's distance a from the drive end: E A / a held at the drive end only
        (fixed_free), E A L / (a (L - a)) held at both (fixed_fixed, the two lengths in parallel;
        THK's ball screw catalogue, "Axial rigidity of the feed screw system")."""
        if f"{a}_screw_root_diameter_m" not in params:
            return params[f"{a}_k_axial_N_per_m"]
        area, _, position = self._screw_to_nut(params, a)
        length = params[f"{a}_screw_length_m"]
        shaft = STEEL_YOUNG_MODULUS_PA * area / position
        axis = self.spec.axes[a]
        if isinstance(axis, BallScrewSpec) and axis.screw_support == "fixed_fixed":
            shaft *= length / (length - position)
        compliance = 1.0 / shaft + 1.0 / params[f"{a}_k_nut_N_per_m"] + 1.0 / params[f"{a}_k_bearing_N_per_m"]
        return 1.0 / compliance

    def torsion_N_m_per_rad(self, params, a: str) -> float:
        """The drive train's torsional stiffness of axis ``a`` (N m/rad): the coupling's and the
        screw's own in series (the file's ``k_screw_torsion_N_m_per_rad``, or with the root
        diameter G J / a up to the nut); infinite where both are rigid."""
        if f"{a}_screw_root_diameter_m" in params:
            _, polar, position = self._screw_to_nut(params, a)
            screw = STEEL_SHEAR_MODULUS_PA * polar / position
        else:
            screw = params[f"{a}_k_screw_torsion_N_m_per_rad"]
        compliance = 1.0 / params[f"{a}_k_torsion_N_m_per_rad"] + 1.0 / screw
        return math.inf if compliance == 0.0 else 1.0 / compliance

    def fastest_mode_hz(self, params) -> float:
        """The highest natural frequency (Hz) of the axes' chains (0 where every link is rigid)."""
        fastest = 0.0
        for a in self.spec.machine.stacking:
            den = self.chain(params, a).transfer_function().den
            if len(den) > 3:
                fastest = max(fastest, float(np.abs(np.roots(den)).max()) / (2.0 * math.pi))
        return fastest

    def make_spec(self, params, timestep_s: float | None = None) -> mujoco.MjSpec:
        """The machine's MJCF, generated (see the module docstring).

        Raises
        ------
        TwinInputError
            Where the physics step is too coarse for the fastest mode (``2 pi f h`` over
            :data:`MAX_MODE_STEP_RAD`), with the step that would do.
        """
        step = timestep_s if timestep_s is not None else self.spec.machine.timestep_s
        fastest = self.fastest_mode_hz(params)
        if 2.0 * math.pi * fastest * step > MAX_MODE_STEP_RAD:
            longest = MAX_MODE_STEP_RAD / (2.0 * math.pi * fastest)
            raise TwinInputError(
                "timestep_s",
                step,
                f"too coarse for the drive train's {fastest:.0f} Hz mode ({self.path.name}): "
                f"2 pi f h must be at most {MAX_MODE_STEP_RAD}, a step of at most {longest:.2g} s",
            )
        spec = mujoco.MjSpec()
        spec.modelname = self.name
        spec.compiler.autolimits = True
        spec.option.timestep = step
        spec.option.integrator = mujoco.mjtIntegrator.mjINT_EULER
        spec.option.disableflags |= mujoco.mjtDisableBit.mjDSBL_GRAVITY | mujoco.mjtDisableBit.mjDSBL_CONTACT
        parent = spec.worldbody
        z = 0.1
        for a in self.spec.machine.stacking:
            ax = self.spec.axes[a]
            if ax.type == "ball_screw":
                table = self._ball_screw(spec, parent, params, a, z)
            else:
                table = self._carriage(spec, parent, params, a, z)
            parent, z = table, 0.05
        work = self._body(parent, "workpiece", (0, 0, 0.05), params["workpiece_mass_kg"], (0.005,) * 3)
        _geom(work, "box", [0.05, 0.05, 0.02], (0.8, 0.6, 0.3))
        # the tool tip touches the workpiece's top face over its starting position (visual only)
        spindle = spec.worldbody.add_body(name="spindle", pos=[0, 0, 0.1 + 0.05 * len(self.axes) + 0.02])
        _geom(spindle, "cylinder", [0.005, 0.02], (0.85, 0.85, 0.9), name="tool", pos=[0, 0, 0.02])
        _geom(spindle, "cylinder", [0.04, 0.06], (0.25, 0.3, 0.35), name="spindle_housing", pos=[0, 0, 0.1])
        spindle.add_site(name="tool_tip", size=[0.002, 0, 0])
        return spec

    @staticmethod
    def _body(parent, name: str, pos, mass_kg: float, inertia):
        """A body with its mass (kg) and principal inertias (kg m^2) at its origin."""
        return parent.add_body(
            name=name, pos=list(pos), ipos=[0, 0, 0], mass=mass_kg, inertia=list(inertia), explicitinertial=True
        )

    def _slide(self, body, name: str, a: str, params):
        travel = params[f"{a}_travel_m"]
        return body.add_joint(
            name=name,
            type=mujoco.mjtJoint.mjJNT_SLIDE,
            axis=list(DIRECTIONS[a]),
            damping=[params[f"{a}_friction_viscous_N_s_per_m"], 0, 0],
            frictionloss=params[f"{a}_friction_coulomb_N"],
            solref_friction=list(FRICTION_SOLREF),
            range=[-travel / 2, travel / 2],
        )

    def _carriage(self, spec, parent, params, a: str, z: float):
        """A linear-motor axis: its carriage on a slide, the drive's force on it."""
        carriage = self._body(parent, f"{a}_table", (0, 0, z), params[f"{a}_table_mass_kg"], (1, 1, 1))
        self._slide(carriage, f"{a}_table", a, params)
        _geom(carriage, "box", [0.2, 0.2, 0.02], (0.4, 0.5, 0.6))
        _drive(spec, f"{a}_drive", f"{a}_table", self._drive_gain(params, a))
        return carriage

    def _ball_screw(self, spec, parent, params, a: str, z: float):
        """A ball-screw axis (see the module docstring); returns its table body."""
        e = np.array(DIRECTIONS[a])
        k = "xy".index(a)

        def about_axis(inertia: float, mass: float) -> list[float]:
            """Principal inertias with ``inertia`` about the axis, the others at least as large."""
            out = [max(inertia, 1e-3 * mass)] * 3
            out[k] = inertia
            return out

        length = params[f"{a}_screw_length_m"]
        radius = params[f"{a}_screw_diameter_m"] / 2
        n = params[f"{a}_gear_ratio"]
        lead = params[f"{a}_screw_lead_m"] / (2.0 * math.pi)
        coupling = params[f"{a}_coupling_inertia_kg_m2"]
        nut = params[f"{a}_nut_mass_kg"]
        k_torsion, k_axial = self.torsion_N_m_per_rad(params, a), self.axial_N_per_m(params, a)
        # half the coupling on each side of a compliant coupling; the nut on the screw's side of a
        # compliant nut (as inertia nut p^2), on the table where the nut is rigid
        motor_inertia = params[f"{a}_motor_inertia_kg_m2"] + params[f"{a}_gear_inertia_kg_m2"]
        screw_inertia = params[f"{a}_screw_inertia_kg_m2"] + coupling
        if math.isfinite(k_torsion):
            motor_inertia += coupling / 2 / n**2
            screw_inertia -= coupling / 2
        if math.isfinite(k_axial):
            screw_inertia += nut * lead**2

        motor_mass = params[f"{a}_motor_mass_kg"]
        rotor = self._body(
            parent,
            f"{a}_motor_rotor",
            -(length / 2 + 0.1) * e + [0, 0, z - 0.05],
            motor_mass,
            about_axis(motor_inertia, motor_mass),
        )
        rotor.add_joint(name=f"{a}_motor", type=mujoco.mjtJoint.mjJNT_HINGE, axis=list(e))
        _geom(rotor, "cylinder", [0.03], (0.2, 0.2, 0.25), fromto=list(np.r_[-0.06 * e, 0.06 * e]))
        marker = 0.061 * e + [0, 0, 0.018]
        _geom(rotor, "box", [0.004, 0.004, 0.0105], (1, 0.45, 0.1), name=f"{a}_motor_rotor_marker", pos=list(marker))
        # a compliant nut turns with the screw (its inertia above) and travels with the axes below
        # with it: its mass on the screw's body, so that each slide carries what the chain's table does
        mass = screw_mass_kg(2 * radius, length) + (nut if math.isfinite(k_axial) else 0.0)
        screw = self._body(parent, f"{a}_screw", (0, 0, z - 0.05), mass, about_axis(screw_inertia, mass))
        screw.add_joint(name=f"{a}_screw", type=mujoco.mjtJoint.mjJNT_HINGE, axis=list(e))
        _geom(screw, "cylinder", [radius], (0.7, 0.7, 0.7), fromto=list(np.r_[-length / 2 * e, length / 2 * e]))
        marker = -0.4 * length * e + [0, 0, radius]
        _geom(screw, "box", [0.006, 0.006, 0.006], (1, 0.45, 0.1), name=f"{a}_screw_marker", pos=list(marker))
        table_mass = params[f"{a}_table_mass_kg"] + (0.0 if math.isfinite(k_axial) else nut)
        table = self._body(parent, f"{a}_table", (0, 0, z), table_mass, (0.2 * table_mass / 12,) * 3)
        self._slide(table, f"{a}_table", a, params)
        half = 0.18 - 0.04 * k
        _geom(table, "box", [half, half, 0.015], (0.4 + 0.1 * k, 0.5 + 0.1 * k, 0.6 + 0.1 * k))
        nut_at = np.r_[-0.03 * e, 0.03 * e] + [0, 0, -0.05, 0, 0, -0.05]
        _geom(table, "cylinder", [radius * 1.8], (0.55, 0.45, 0.3), fromto=list(nut_at))
        coupling_damping = params[f"{a}_c_torsion_N_m_s_per_rad"]
        _link(spec, f"{a}_gear", f"{a}_motor", f"{a}_screw", n, k_torsion, coupling_damping)
        _link(spec, f"{a}_nut", f"{a}_screw", f"{a}_table", 1.0 / lead, k_axial, params[f"{a}_c_axial_N_s_per_m"])
        _drive(spec, f"{a}_drive", f"{a}_motor", self._drive_gain(params, a))
        return table


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


def load_machine_file(path: str | Path) -> DatasheetMachine:
    """The :class:`DatasheetMachine` of a machine file (see :func:`read_machine_file`)."""
    path = Path(path).resolve()
    return DatasheetMachine(path, read_machine_file(path))


def _toml_value(value) -> str:
    if isinstance(value, float):
        return "inf" if math.isinf(value) else repr(value)
    if isinstance(value, str):
        return '"' + value.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(value, list):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    return repr(value)


def machine_file_text(machine: DatasheetMachine, params: dict[str, float], note: str = "") -> str:
    """The machine file of ``machine`` with the parameter values ``params`` (a calibrated
    machine), as TOML text; ``note`` goes in a comment at the top."""
    spec = machine.spec.model_copy(deep=True)
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
