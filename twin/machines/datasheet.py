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
machine, :mod:`twin.machines.datasheet_mjcf`) and derives the transfer-function model from the
same values (:mod:`twin.machines.drive_train`; the schema is :mod:`twin.machines.machine_file`): a chain of masses in
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
from pathlib import Path

import mujoco
import numpy as np
from pydantic import ValidationError

from twin.errors import TwinInputError
from twin.machines.base import Axis, Coupling, Machine, MotionLimits, Parameter, diagonal_plant
from twin.machines.datasheet_mjcf import machine_spec
from twin.machines.drive_train import (
    AxisValues,
    Chain,
    axial_N_per_m,
    chain,
    moving_mass_kg,
    screw_inertia_kg_m2,
    torsion_N_m_per_rad,
)
from twin.machines.machine_file import (
    BallScrewSpec,
    MachineFile,
    MachineSpec,
    physical_range,
    read_machine_file,
    unit_of,
)

#: The largest 2 pi f h (fastest mode f, physics step h) a machine file may be simulated at:
#: MuJoCo integrates its springs explicitly (semi-implicit Euler: 17 deg of phase a step at 0.3).
MAX_MODE_STEP_RAD = 0.3


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
        self.planner_mode = m.planner_mode
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
            "workpiece_mass_kg": Parameter(
                m.workpiece_mass_kg, "kg", "workpiece mass", bounds=physical_range(MachineSpec, "workpiece_mass_kg")
            ),
            "delay_s": Parameter(
                m.delay_s,
                "s",
                "drive transport delay",
                positive=False,
                nonnegative=True,
                bounds=physical_range(MachineSpec, "delay_s"),
            ),
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
                    unit_of(key),
                    f"{a.upper()} axis ({ax.type}): {key}" + (f", {field.description}" if field.description else ""),
                    positive=positive,
                    nonnegative=not positive,
                    infinite=key.startswith(("k_axial", "k_torsion", "k_screw_torsion", "k_nut", "k_bearing")),
                    bounds=physical_range(type(ax), key),
                )
        return out

    def check(self, params) -> None:
        """The overridden values of each axis through the machine file's own schema (a root
        diameter over the screw's, a nut beyond its end, a drive gain given twice).

        Raises
        ------
        TwinInputError
            Under the first overridden symbol of the axis the schema refuses.
        """
        for a in self.spec.machine.stacking:
            ax = self.spec.axes[a]
            changed = {
                key.removeprefix(f"{a}_"): value
                for key, value in params.items()
                if key.startswith(f"{a}_") and value != self.parameters[key].value
            }
            if not changed:
                continue
            try:
                type(ax).model_validate({**ax.model_dump(exclude_unset=True), **changed})
            except ValidationError as exc:
                error = exc.errors()[0]
                key = str(error["loc"][0]) if error["loc"] else next(iter(changed))
                reason = error["msg"].removeprefix("Value error, ")
                raise TwinInputError(f"overrides.{a}_{key}", params.get(f"{a}_{key}"), reason) from None

    def axis_values(self, params) -> list[AxisValues]:
        """Every axis's values resolved from ``params`` (by the symbols ``<axis>_<key>``), in
        stacking order, each with the mass it carries: the one per-axis view the model and the
        MJCF read."""
        stacking = self.spec.machine.stacking
        files = []
        for a in stacking:
            prefix = f"{a}_"
            resolved = {key.removeprefix(prefix): v for key, v in params.items() if key.startswith(prefix)}
            files.append(self.spec.axes[a].model_copy(update=resolved))
        return [
            AxisValues(a, files[i], params["workpiece_mass_kg"] + sum(moving_mass_kg(f) for f in files[i + 1 :]))
            for i, a in enumerate(stacking)
        ]

    def _axis(self, params, a: str) -> AxisValues:
        return next(axis for axis in self.axis_values(params) if axis.name == a)

    def chain(self, params, a: str) -> Chain:
        """Axis ``a`` as a :class:`~twin.machines.drive_train.Chain` (rigid links merged)."""
        return chain(self._axis(params, a))

    def plant(self, params, model):
        return diagonal_plant([chain(axis).transfer_function() for axis in self.axis_values(params)])

    def motor_plant(self, params, model):
        return tuple(chain(axis).transfer_function("motor") for axis in self.axis_values(params))

    def motor_travel(self, params):
        return {
            axis.name: axis.lead_m_per_rad / axis.values.gear_ratio
            for axis in self.axis_values(params)
            if isinstance(axis.values, BallScrewSpec)
        }

    def delay(self, params):
        return params["delay_s"]

    def coulomb_symbols(self) -> tuple[str, ...]:
        return tuple(f"{a}_friction_coulomb_N" for a in self.spec.machine.stacking)

    def encoder_resolution(self, params) -> tuple[float, ...]:
        return tuple(axis.values.encoder_resolution_m for axis in self.axis_values(params))

    def motor_encoder_resolution(self, params) -> tuple[float, ...]:
        travel = self.motor_travel(params)  # the ball-screw axes'
        out = []
        for axis in self.axis_values(params):
            counts = axis.values.motor_encoder_counts_per_rev if isinstance(axis.values, BallScrewSpec) else 0.0
            out.append(2.0 * math.pi * travel[axis.name] / counts if counts else 0.0)
        return tuple(out)

    def couplings(self, params):
        pairs, leads = [], {}
        for axis in self.axis_values(params):
            if not isinstance(axis.values, BallScrewSpec):
                continue
            a, lead = axis.name, axis.lead_m_per_rad
            if math.isinf(torsion_N_m_per_rad(axis)):
                pairs.append(Coupling(a, f"{a}_motor", f"{a}_screw", axis.values.gear_ratio))
            if math.isinf(axial_N_per_m(axis)):
                pairs.append(Coupling(a, f"{a}_screw", f"{a}_table", 1.0 / lead))
            leads[a] = lead
        return pairs, leads

    def axial_N_per_m(self, params, a: str) -> float:
        """Axis ``a``'s axial stiffness (N/m), :func:`twin.machines.drive_train.axial_N_per_m`."""
        return axial_N_per_m(self._axis(params, a))

    def torsion_N_m_per_rad(self, params, a: str) -> float:
        """Axis ``a``'s torsional stiffness (N m/rad), :func:`twin.machines.drive_train.torsion_N_m_per_rad`."""
        return torsion_N_m_per_rad(self._axis(params, a))

    def fastest_mode_hz(self, params) -> float:
        """The highest natural frequency (Hz) of the axes' chains (0 where every link is rigid)."""
        fastest = 0.0
        for axis in self.axis_values(params):
            den = chain(axis).transfer_function().den
            if len(den) > 3:
                fastest = max(fastest, float(np.abs(np.roots(den)).max()) / (2.0 * math.pi))
        return fastest

    def make_spec(self, params, timestep_s: float | None = None) -> mujoco.MjSpec:
        """The machine's MJCF, generated (:func:`twin.machines.datasheet_mjcf.machine_spec`).

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
        return machine_spec(self.name, self.axis_values(params), params["workpiece_mass_kg"], step)


def load_machine_file(path: str | Path) -> DatasheetMachine:
    """The :class:`DatasheetMachine` of a machine file (see :func:`twin.machines.machine_file.read_machine_file`)."""
    path = Path(path).resolve()
    return DatasheetMachine(path, read_machine_file(path))
