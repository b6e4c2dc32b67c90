"""A machine file's drive trains: each axis's values resolved (:class:`AxisValues`), where its
masses sit (:func:`mass_budget`, the one split both the MJCF's bodies and the transfer function's
chain use), its stiffnesses, its drive gain, and the chain of masses in table-travel units whose
transfer function is the axis's model (:class:`Chain`)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np

from controllers.lti import SisoTf
from twin.machines.machine_file import BallScrewSpec, LinearMotorSpec

#: Density of screw steel (kg/m^3), for a screw inertia the file does not give.
STEEL_DENSITY_KG_PER_M3 = 7850.0
#: Young's modulus of screw steel (Pa), as THK's ball screw catalogue takes it (2.06e5 N/mm^2),
#: and its shear modulus (Pa): the shaft's stiffness from its root diameter.
STEEL_YOUNG_MODULUS_PA = 2.06e11
STEEL_SHEAR_MODULUS_PA = 7.93e10


@dataclass(frozen=True)
class AxisValues:
    """One axis of a machine file with every parameter resolved (overrides applied).

    Attributes
    ----------
    name : str
        The axis (``x``, ``y``).
    values : BallScrewSpec or LinearMotorSpec
        The axis's table of the file, its values replaced by the resolved ones (SI, the file's
        units): ``values.table_mass_kg``, ``values.screw_lead_m``...
    carried_kg : float
        The mass its own moving parts carry: the axes above it and the workpiece (kg).
    """

    name: str
    values: BallScrewSpec | LinearMotorSpec
    carried_kg: float

    @property
    def lead_m_per_rad(self) -> float:
        """A ball screw's table travel per screw radian (m/rad)."""
        assert isinstance(self.values, BallScrewSpec)
        return self.values.screw_lead_m / (2.0 * math.pi)


def moving_mass_kg(values: BallScrewSpec | LinearMotorSpec) -> float:
    """What an axis below carries of this axis (kg): its table, and a ball screw's motor, nut and
    screw."""
    mass = values.table_mass_kg
    if isinstance(values, BallScrewSpec):
        mass += values.motor_mass_kg + values.nut_mass_kg
        mass += screw_mass_kg(values.screw_diameter_m, values.screw_length_m)
    return mass


def drive_gain(values: BallScrewSpec | LinearMotorSpec) -> float:
    """Torque (N m/V) or force (N/V) per volt of drive input: the drive's own gain, or the
    motor's constant times the amplifier's gain."""
    direct, constant, amplifier = values.drive_keys
    gain = getattr(values, direct)
    return gain if gain is not None else getattr(values, constant) * getattr(values, amplifier)


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


def _screw_to_nut(axis: AxisValues) -> tuple[float, float, float]:
    """The shaft's cross-section (m^2) and polar moment (m^4) from its root diameter, and the
    nut's distance from the drive end (m), where the file gives the root diameter."""
    values = axis.values
    assert isinstance(values, BallScrewSpec) and values.screw_root_diameter_m is not None
    assert values.nut_position_m is not None  # the parameters default it to half the screw
    d, position = values.screw_root_diameter_m, values.nut_position_m  # within the screw: the schema's check
    return math.pi * d**2 / 4.0, math.pi * d**4 / 32.0, position


def axial_N_per_m(axis: AxisValues) -> float:
    """The axial stiffness (N/m): the file's ``k_axial_N_per_m``, or, with the shaft's root
    diameter, the nut, the bearings and the shaft up to the nut in series. The shaft at the
    nut's distance a from the drive end: E A / a held axially at the drive end only (fixed_free,
    and fixed_supported, whose far bearing holds the shaft radially only), E A L / (a (L - a))
    held at both (fixed_fixed, the two lengths in parallel; THK's ball screw catalogue, "Axial
    rigidity of the feed screw system")."""
    values = axis.values
    assert isinstance(values, BallScrewSpec)
    if values.screw_root_diameter_m is None:
        return values.k_axial_N_per_m
    area, _, position = _screw_to_nut(axis)
    length = values.screw_length_m
    shaft = STEEL_YOUNG_MODULUS_PA * area / position
    if values.screw_support == "fixed_fixed":
        shaft *= length / (length - position)
    compliance = 1.0 / shaft + 1.0 / values.k_nut_N_per_m + 1.0 / values.k_bearing_N_per_m
    return 1.0 / compliance


def torsion_N_m_per_rad(axis: AxisValues) -> float:
    """The drive train's torsional stiffness (N m/rad): the coupling's and the screw's own in
    series (the file's ``k_screw_torsion_N_m_per_rad``, or with the root diameter G J / a up to
    the nut); infinite where both are rigid."""
    values = axis.values
    assert isinstance(values, BallScrewSpec)
    if values.screw_root_diameter_m is not None:
        _, polar, position = _screw_to_nut(axis)
        screw = STEEL_SHEAR_MODULUS_PA * polar / position
    else:
        screw = values.k_screw_torsion_N_m_per_rad
    compliance = 1.0 / values.k_torsion_N_m_per_rad + 1.0 / screw
    return math.inf if compliance == 0.0 else 1.0 / compliance


@dataclass(frozen=True)
class MassBudget:
    """Where a ball-screw axis's masses sit: half a compliant coupling on each of its sides (all
    of a rigid one on the screw's), a compliant nut on the screw's side (as nut x lead^2), a rigid
    one on the table.

    Attributes
    ----------
    motor_kg_m2 : float
        The motor side's inertia at the motor shaft: rotor, gearbox, coupling share.
    screw_kg_m2 : float
        The screw side's inertia at the screw: screw, coupling share, a compliant nut.
    screw_body_kg : float
        The screw's mass, with a compliant nut (which turns with it).
    table_kg : float
        The table's own mass, with a rigid nut.
    """

    motor_kg_m2: float
    screw_kg_m2: float
    screw_body_kg: float
    table_kg: float


def mass_budget(axis: AxisValues) -> MassBudget:
    """The one split of a ball-screw axis's masses (:class:`MassBudget`): the MJCF's bodies carry
    it, and :func:`chain` turns it into table-travel masses."""
    values = axis.values
    assert isinstance(values, BallScrewSpec)
    assert values.screw_inertia_kg_m2 is not None  # the parameters default it to a steel cylinder
    n, lead, coupling, nut = values.gear_ratio, axis.lead_m_per_rad, values.coupling_inertia_kg_m2, values.nut_mass_kg
    motor = values.motor_inertia_kg_m2 + values.gear_inertia_kg_m2
    screw = values.screw_inertia_kg_m2 + coupling
    if math.isfinite(torsion_N_m_per_rad(axis)):
        motor += coupling / 2 / n**2
        screw -= coupling / 2
    compliant_nut = math.isfinite(axial_N_per_m(axis))
    if compliant_nut:
        screw += nut * lead**2
    return MassBudget(
        motor_kg_m2=motor,
        screw_kg_m2=screw,
        screw_body_kg=screw_mass_kg(values.screw_diameter_m, values.screw_length_m) + (nut if compliant_nut else 0.0),
        table_kg=values.table_mass_kg + (0.0 if compliant_nut else nut),
    )


def chain(axis: AxisValues) -> Chain:
    """The axis as a :class:`Chain` in table-travel units, from its :func:`mass_budget` (rigid
    links merged)."""
    values = axis.values
    gain = drive_gain(values)
    if isinstance(values, LinearMotorSpec):
        return Chain((values.table_mass_kg + axis.carried_kg,), (), (), values.friction_viscous_N_s_per_m, gain)
    lead, n = axis.lead_m_per_rad, values.gear_ratio
    budget = mass_budget(axis)
    masses = [budget.motor_kg_m2 * n**2 / lead**2, budget.screw_kg_m2 / lead**2, budget.table_kg + axis.carried_kg]
    springs = [torsion_N_m_per_rad(axis) / lead**2, axial_N_per_m(axis)]
    dampers = [values.c_torsion_N_m_s_per_rad / lead**2, values.c_axial_N_s_per_m]
    # merge the rigid links, from the table down
    for i in (1, 0):
        if math.isinf(springs[i]):
            masses[i : i + 2] = [masses[i] + masses[i + 1]]
            del springs[i], dampers[i]
    return Chain(tuple(masses), tuple(springs), tuple(dampers), values.friction_viscous_N_s_per_m, gain * n / lead)
