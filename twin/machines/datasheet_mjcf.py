"""The MJCF of a machine file, generated with :class:`mujoco.MjSpec` (no XML per machine): per
ball-screw axis its motor rotor, screw and table bodies linked by gear equalities or spring
tendons, per linear-motor axis its carriage, the workpiece and a spindle (see
:mod:`twin.machines.datasheet` for the layout)."""

from __future__ import annotations

import math

import mujoco
import numpy as np

from twin.machines.drive_train import (
    AxisValues,
    axial_N_per_m,
    drive_gain,
    mass_budget,
    torsion_N_m_per_rad,
)
from twin.machines.machine_file import BallScrewSpec


def _geom(body, kind: str, size, rgba, **placement) -> None:
    """A massless geom (the bodies' inertials carry the masses): ``kind`` box or cylinder,
    ``size`` as MJCF, colour ``rgba`` (r, g, b), placed by ``pos`` or ``fromto``."""
    shape = {"box": mujoco.mjtGeom.mjGEOM_BOX, "cylinder": mujoco.mjtGeom.mjGEOM_CYLINDER}[kind]
    body.add_geom(type=shape, size=[*size, 0, 0][:3], rgba=[*rgba, 1.0], mass=0, **placement)


def _drive(spec, name: str, joint: str, gain: float) -> None:
    """The drive: torque (N m) or force (N) on ``joint`` = ``gain`` x the input (V)."""
    spec.add_actuator(name=name, target=joint, trntype=mujoco.mjtTrn.mjTRN_JOINT, gainprm=[gain] + [0.0] * 9)


def _link(spec, name: str, *, first: str, second: str, ratio: float, stiffness: float, damping: float) -> None:
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


def machine_spec(name: str, axes: list[AxisValues], workpiece_mass_kg: float, timestep_s: float) -> mujoco.MjSpec:
    """The machine's MJCF: ``axes`` stacked in order (the first on the bed), the workpiece on the
    last one, a spindle above it; physics step ``timestep_s`` (s)."""
    spec = mujoco.MjSpec()
    spec.modelname = name
    spec.compiler.autolimits = True
    spec.option.timestep = timestep_s
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_EULER
    spec.option.disableflags |= mujoco.mjtDisableBit.mjDSBL_GRAVITY | mujoco.mjtDisableBit.mjDSBL_CONTACT
    parent = spec.worldbody
    z = 0.1
    for axis in axes:
        if isinstance(axis.values, BallScrewSpec):
            table = _ball_screw(spec, parent, axis, z)
        else:
            table = _carriage(spec, parent, axis, z)
        parent, z = table, 0.05
    work = _body(parent, "workpiece", pos=(0, 0, 0.05), mass_kg=workpiece_mass_kg, inertia=(0.005,) * 3)
    _geom(work, "box", [0.05, 0.05, 0.02], (0.8, 0.6, 0.3))
    # the tool tip touches the workpiece's top face over its starting position (visual only)
    spindle = spec.worldbody.add_body(name="spindle", pos=[0, 0, 0.1 + 0.05 * len(axes) + 0.02])
    _geom(spindle, "cylinder", [0.005, 0.02], (0.85, 0.85, 0.9), name="tool", pos=[0, 0, 0.02])
    _geom(spindle, "cylinder", [0.04, 0.06], (0.25, 0.3, 0.35), name="spindle_housing", pos=[0, 0, 0.1])
    spindle.add_site(name="tool_tip", size=[0.002, 0, 0])
    return spec


def _body(parent, name: str, *, pos, mass_kg: float, inertia):
    """A body with its mass (kg) and principal inertias (kg m^2) at its origin."""
    return parent.add_body(
        name=name, pos=list(pos), ipos=[0, 0, 0], mass=mass_kg, inertia=list(inertia), explicitinertial=True
    )


def _slide(body, name: str, axis: AxisValues):
    """The table's slide: travel limits, guideway viscous damping and Coulomb friction."""
    values = axis.values
    travel = values.travel_m
    return body.add_joint(
        name=name,
        type=mujoco.mjtJoint.mjJNT_SLIDE,
        axis=list(DIRECTIONS[axis.name]),
        damping=[values.friction_viscous_N_s_per_m, 0, 0],
        frictionloss=values.friction_coulomb_N,
        solref_friction=list(FRICTION_SOLREF),
        range=[-travel / 2, travel / 2],
    )


def _carriage(spec, parent, axis: AxisValues, z: float):
    """A linear-motor axis: its carriage on a slide, the drive's force on it."""
    a = axis.name
    carriage = _body(parent, f"{a}_table", pos=(0, 0, z), mass_kg=axis.values.table_mass_kg, inertia=(1, 1, 1))
    _slide(carriage, f"{a}_table", axis)
    _geom(carriage, "box", [0.2, 0.2, 0.02], (0.4, 0.5, 0.6))
    _drive(spec, f"{a}_drive", f"{a}_table", drive_gain(axis.values))
    return carriage


def _ball_screw(spec, parent, axis: AxisValues, z: float):
    """A ball-screw axis (see :mod:`twin.machines.datasheet`); returns its table body."""
    a, values = axis.name, axis.values
    assert isinstance(values, BallScrewSpec)
    e = np.array(DIRECTIONS[a])
    k = "xy".index(a)

    def about_axis(inertia: float, mass: float) -> list[float]:
        """Principal inertias with ``inertia`` about the axis, the others at least as large."""
        out = [max(inertia, 1e-3 * mass)] * 3
        out[k] = inertia
        return out

    length = values.screw_length_m
    radius = values.screw_diameter_m / 2
    k_torsion, k_axial = torsion_N_m_per_rad(axis), axial_N_per_m(axis)
    budget = mass_budget(axis)
    motor_mass = values.motor_mass_kg
    rotor = _body(
        parent,
        f"{a}_motor_rotor",
        pos=-(length / 2 + 0.1) * e + [0, 0, z - 0.05],
        mass_kg=motor_mass,
        inertia=about_axis(budget.motor_kg_m2, motor_mass),
    )
    rotor.add_joint(name=f"{a}_motor", type=mujoco.mjtJoint.mjJNT_HINGE, axis=list(e))
    _geom(rotor, "cylinder", [0.03], (0.2, 0.2, 0.25), fromto=list(np.r_[-0.06 * e, 0.06 * e]))
    marker = 0.061 * e + [0, 0, 0.018]
    _geom(rotor, "box", [0.004, 0.004, 0.0105], (1, 0.45, 0.1), name=f"{a}_motor_rotor_marker", pos=list(marker))
    # a compliant nut turns with the screw (its inertia in the budget) and travels with the axes
    # below with it: its mass on the screw's body, so that each slide carries what the chain's table does
    mass = budget.screw_body_kg
    screw = _body(
        parent, f"{a}_screw", pos=(0, 0, z - 0.05), mass_kg=mass, inertia=about_axis(budget.screw_kg_m2, mass)
    )
    screw.add_joint(name=f"{a}_screw", type=mujoco.mjtJoint.mjJNT_HINGE, axis=list(e))
    _geom(screw, "cylinder", [radius], (0.7, 0.7, 0.7), fromto=list(np.r_[-length / 2 * e, length / 2 * e]))
    marker = -0.4 * length * e + [0, 0, radius]
    _geom(screw, "box", [0.006, 0.006, 0.006], (1, 0.45, 0.1), name=f"{a}_screw_marker", pos=list(marker))
    table_mass = budget.table_kg
    table = _body(parent, f"{a}_table", pos=(0, 0, z), mass_kg=table_mass, inertia=(0.2 * table_mass / 12,) * 3)
    _slide(table, f"{a}_table", axis)
    half = 0.18 - 0.04 * k
    _geom(table, "box", [half, half, 0.015], (0.4 + 0.1 * k, 0.5 + 0.1 * k, 0.6 + 0.1 * k))
    nut_at = np.r_[-0.03 * e, 0.03 * e] + [0, 0, -0.05, 0, 0, -0.05]
    _geom(table, "cylinder", [radius * 1.8], (0.55, 0.45, 0.3), fromto=list(nut_at))
    _link(
        spec,
        f"{a}_gear",
        first=f"{a}_motor",
        second=f"{a}_screw",
        ratio=values.gear_ratio,
        stiffness=k_torsion,
        damping=values.c_torsion_N_m_s_per_rad,
    )
    _link(
        spec,
        f"{a}_nut",
        first=f"{a}_screw",
        second=f"{a}_table",
        ratio=1.0 / axis.lead_m_per_rad,
        stiffness=k_axial,
        damping=values.c_axial_N_s_per_m,
    )
    _drive(spec, f"{a}_drive", f"{a}_motor", drive_gain(values))
    return table
