"""What a planned program may ask of a machine's axes: each table's travel (the slide's range in
the model, a machine file's ``travel_m`` centred on machine zero) and each axis's drive as a rigid
body, the drive input its motion needs.

The drive input (V) that moves an axis along ``x(t)`` is, at low frequency, the plant's inverse
``1/G(s) = q0 + q1 s + q2 s^2 + ...`` (``G``: drive input V to table position m, the model the
twin checks its MuJoCo model against): ``u = q0 x + q1 v + q2 a``, and the guideway's Coulomb
friction ``F_c sign(v)`` over the drive's force per volt on top.  On a rigid axis ``G = K / (M s^2
+ B s)``, so ``K u = M a + B v + F_c sign(v)``: the moving mass, the viscous friction and the
Coulomb friction, as a force (N) at the table.  A compliant drive train's springs and dampers drop
out of ``q1`` and ``q2`` exactly (its masses add up), and the amplifier's own velocity or position
feedback (an affine bias, Yadav 2020's tachogenerator, the Googol drive) enters ``q1`` or ``q0``.
"""

from __future__ import annotations

from typing import NamedTuple

import mujoco
import numpy as np

from controllers.lti import SisoTf
from twin.machines.base import Axis, BuiltMachine


class RigidDrive(NamedTuple):
    """One axis's drive input for a motion, at low frequency (see the module's docstring).

    Attributes
    ----------
    axis : str
        The axis (``x``, ``y``).
    volts_per_m, volts_per_m_per_s, volts_per_m_per_s2 : float
        ``q0``, ``q1``, ``q2``: drive input (V) per metre of position (an amplifier's position
        feedback; 0 for most), per m/s of velocity and per m/s^2 of acceleration.
    force_per_volt_N_per_V : float
        The drive's force on the table per volt of input (N/V): a linear motor's gain, a rotary
        drive's torque per volt over the table travel per motor radian.
    coulomb_N : float
        The guideway's Coulomb friction (N), the table slide's ``frictionloss``.
    """

    axis: str
    volts_per_m: float
    volts_per_m_per_s: float
    volts_per_m_per_s2: float
    force_per_volt_N_per_V: float
    coulomb_N: float

    @property
    def moving_mass_kg(self) -> float:
        """The mass the drive accelerates, in table travel (kg): ``K q2``."""
        return self.force_per_volt_N_per_V * self.volts_per_m_per_s2

    @property
    def viscous_N_s_per_m(self) -> float:
        """The viscous friction the drive overcomes, in table travel (N s/m): ``K q1``."""
        return self.force_per_volt_N_per_V * self.volts_per_m_per_s


def inverse_series(g: SisoTf, terms: int = 3) -> tuple[float, ...]:
    """The first ``terms`` Taylor coefficients of ``1 / g(s)`` at ``s = 0`` (lowest power first).

    Raises
    ------
    ValueError
        A plant with no gain at low frequency (``g``'s numerator vanishes at ``s = 0``).
    """
    num = np.asarray(g.num, float)[::-1]
    den = np.asarray(g.den, float)[::-1]
    if num[0] == 0.0:
        raise ValueError("the plant has no gain at s = 0: its inverse has no series there")
    n = np.zeros(terms)
    d = np.zeros(terms)
    n[: min(terms, num.size)] = num[:terms]
    d[: min(terms, den.size)] = den[:terms]
    q = np.zeros(terms)
    for k in range(terms):  # den = q num, term by term
        q[k] = (d[k] - float(np.dot(q[:k], n[k:0:-1]))) / n[0]
    return tuple(float(c) for c in q)


def _force_per_volt(machine: BuiltMachine, axis: Axis) -> float:
    """The drive's force on the table per volt (N/V) of ``axis``."""
    model = machine.model
    act = model.actuator(axis.actuator).id
    gain = float(model.actuator_gainprm[act, 0] * model.actuator_gear[act, 0])
    target = int(model.actuator_trnid[act, 0])
    table = model.joint(axis.table_joint).id
    if model.actuator_trntype[act] == mujoco.mjtTrn.mjTRN_TENDON:
        first, count = model.tendon_adr[target], model.tendon_num[target]
        coefficient = sum(float(model.wrap_prm[w]) for w in range(first, first + count) if model.wrap_objid[w] == table)
        return gain * coefficient
    if model.jnt_type[target] == mujoco.mjtJoint.mjJNT_HINGE:
        return gain / machine.motor_travel_m_per_rad[axis.name]
    return gain


def rigid_drives(machine: BuiltMachine) -> dict[str, RigidDrive]:
    """Each axis's :class:`RigidDrive`, from the diagonal of the machine's plant (a cross-coupled
    machine's coupling is left out) and its model's actuators and slides."""
    out = {}
    for i, axis in enumerate(machine.axes):
        q0, q1, q2 = inverse_series(machine.plant[i][i])
        coulomb = float(machine.model.dof_frictionloss[machine.joint_dof_index(axis.table_joint)])
        out[axis.name] = RigidDrive(axis.name, q0, q1, q2, _force_per_volt(machine, axis), coulomb)
    return out


def table_travel_m(machine: BuiltMachine) -> dict[str, tuple[float, float]]:
    """Each axis's travel in machine coordinates (m): its table slide's range in the model, where
    the slide has one (a machine file's ``travel_m``, centred on machine zero); the papers'
    machines have none."""
    model = machine.model
    out = {}
    for axis in machine.axes:
        joint = model.joint(axis.table_joint).id
        if model.jnt_limited[joint]:
            low, high = model.jnt_range[joint]
            out[axis.name] = (float(low), float(high))
    return out
