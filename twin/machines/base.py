"""Machine definitions: MJCF file + parameters by the source's symbols + reference model.

A :class:`Machine` loads its MJCF with :class:`mujoco.MjSpec`, applies parameter values
(nominal or overridden by the source's symbols) with spec edits, compiles it, and derives
its reference transfer-function model from the same parameter values.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import NamedTuple

import mujoco
import numpy as np

from controllers.lti import SisoTf
from controllers.registries import Registry
from twin.errors import TwinInputError
from twin.machines.machine_file import PhysicalRange


def mjcf_dir() -> Path:
    """Folder holding the machine MJCF folders (inside the wheel, or the repo's ``mjcf/``)."""
    here = Path(__file__).resolve().parent.parent
    for candidate in (here / "mjcf", here.parent / "mjcf"):
        if candidate.is_dir():
            return candidate
    raise FileNotFoundError("mjcf/ folder not found next to the twin package")


@dataclass(frozen=True)
class Parameter:
    """One model parameter, named by the source's symbol.

    Attributes
    ----------
    value : float
        Nominal value in ``unit``.
    unit : str
        SI unit (or as stated).
    description : str
        What it is and where it comes from (seed file, table or equation).
    box : tuple of float or None
        (lower, upper) uncertainty box from the source, if it gives one.
    positive : bool
        Whether the value must be strictly positive.
    nonnegative : bool
        Whether the value must be >= 0 (for parameters that may be zero, e.g. friction).
    infinite : bool
        Whether the value may be infinite (a stiffness: infinite is rigid).
    bounds : PhysicalRange or None
        The physical range a value must lie in (a machine file's,
        :class:`twin.machines.machine_file.PhysicalRange`).
    """

    value: float
    unit: str
    description: str
    box: tuple[float, float] | None = None
    positive: bool = True
    nonnegative: bool = False
    infinite: bool = False
    bounds: PhysicalRange | None = None


@dataclass(frozen=True)
class Axis:
    """One feed axis of a machine and the MJCF names that make it.

    Attributes
    ----------
    name : str
        ``"x"`` or ``"y"``.
    actuator : str
        Actuator driven by the axis's control input (V).
    table_joint : str
        Slide joint whose position (m) is the axis output.
    motor_joint, screw_joint : str or None
        Hinge joints of the motor rotor and lead screw (ball/lead-screw axes only).
    """

    name: str
    actuator: str
    table_joint: str
    motor_joint: str | None = None
    screw_joint: str | None = None

    def encoder_joint(self, feedback: str) -> str:
        """The joint the position loop reads (:data:`twin.sim.drive.FEEDBACK`): the motor's with
        ``feedback = "motor"`` where the axis has one (a semi-closed loop), else the table's."""
        return self.motor_joint if feedback == "motor" and self.motor_joint else self.table_joint

    def velocity_joint(self, feedback: str) -> str:
        """The joint the velocity loop reads: the motor's with ``feedback = "motor"`` or
        ``"dual"`` where the axis has one, else the table's."""
        return self.motor_joint if feedback in ("motor", "dual") and self.motor_joint else self.table_joint


class Coupling(NamedTuple):
    """A gear coupling of axis ``axis``: joint ``first`` = ``ratio`` x joint ``second`` (a motor to
    its screw, a screw to its table in rad/m)."""

    axis: str
    first: str
    second: str
    ratio: float


@dataclass(frozen=True)
class MotionLimits:
    """One axis's kinematic limits, what the G-code interpolator plans within.

    Attributes
    ----------
    velocity_m_per_s, acceleration_m_per_s2, jerk_m_per_s3 : float
        The limits (SI).
    source : str
        Where they come from (a datasheet value of the source, or ours).
    """

    velocity_m_per_s: float
    acceleration_m_per_s2: float
    jerk_m_per_s3: float
    source: str


#: The spindle head's Z of the XY tables, which the twin does not simulate (ours: a small ball-screw
#: head; the interpolator plans Z within these and the recording shows it).
SPINDLE_HEAD_Z = MotionLimits(0.2, 2.0, 200.0, "ours: a small ball-screw spindle head (Z is not simulated)")


@dataclass
class BuiltMachine:
    """A compiled machine: MuJoCo model plus its reference model.

    Attributes
    ----------
    name : str
    model : mujoco.MjModel
    params : dict of str to float
        Parameter values in effect (nominal merged with overrides).
    axes : tuple of Axis
    plant : tuple of tuple of SisoTf
        Input (V) to table position (m) model, delay excluded: ``plant[i][j]`` from axis j's
        input to axis i's position; :meth:`plant_lti` gives it as a python-control model.
    delay_s : float
        Transport delay (s) of the drive, applied by the runner's drive model.
    couplings : list of Coupling
        Gear couplings of an axis, ``q_first = ratio * q_second``; used to measure slip. Ratios of
        nut couplings are in rad/m.
    table_per_screw_m_per_rad : dict of str to float
        Lead p (m/rad) per axis, to express screw-side slip as table travel.
    sensor_gains : tuple of float
        Encoder gain per axis (measured position = gain * table position).
    motion_limits : dict of str to MotionLimits
        Each axis's kinematic limits for the G-code interpolator, z included.
    encoder_resolution_m : tuple of float
        Each axis's table encoder (linear scale) resolution (m; 0: ideal), a scenario's default.
    motor_encoder_resolution_m : tuple of float
        Each axis's motor encoder resolution in table travel (m; 0: ideal or no motor).
    feedback : str
        What a scenario's loops close on unless it says (:data:`twin.sim.drive.FEEDBACK`):
        ``"dual"`` for a machine file's drives, ``"table"`` for the papers' machines (their
        measurements are of one encoder).
    motor_plant : tuple of SisoTf
        Per axis, drive input (V) to the motor's angle in table travel (m), where it differs from
        the table's (a compliant drive train); empty otherwise.
    motor_travel_m_per_rad : dict of str to float
        Table travel per motor radian (m/rad) of each axis with a motor joint (lead / gear ratio).
    planner_mode : str or None
        The machine file's ``planner_mode``: how a program is planned unless a scenario's
        ``[planner] mode`` says (None: the planner's default).
    """

    name: str
    model: mujoco.MjModel
    params: dict[str, float]
    axes: tuple[Axis, ...]
    plant: tuple[tuple[SisoTf, ...], ...]
    delay_s: float
    couplings: list[Coupling] = field(default_factory=list)
    table_per_screw_m_per_rad: dict[str, float] = field(default_factory=dict)
    sensor_gains: tuple[float, ...] = ()
    motion_limits: dict[str, MotionLimits] = field(default_factory=dict)
    encoder_resolution_m: tuple[float, ...] = ()
    motor_encoder_resolution_m: tuple[float, ...] = ()
    feedback: str = "table"
    motor_plant: tuple[SisoTf, ...] = ()
    motor_travel_m_per_rad: dict[str, float] = field(default_factory=dict)
    planner_mode: str | None = None

    def plant_lti(self):
        """:attr:`plant` as a ``control.TransferFunction`` (imports python-control)."""
        import control

        return control.tf(
            [[list(g.num) for g in row] for row in self.plant], [[list(g.den) for g in row] for row in self.plant]
        )

    def drive_quantity(self, axis: Axis) -> tuple[str, str]:
        """(``"torque"``, ``"N m"``) for an axis driven on a hinge (a motor shaft), else
        (``"force"``, ``"N"``: a linear motor, or a tendon over slides)."""
        act = self.model.actuator(axis.actuator).id
        if (
            self.model.actuator_trntype[act] == mujoco.mjtTrn.mjTRN_JOINT
            and self.model.jnt_type[self.model.actuator_trnid[act, 0]] == mujoco.mjtJoint.mjJNT_HINGE
        ):
            return "torque", "N m"
        return "force", "N"

    def joint_qpos_index(self, joint: str) -> int:
        """Index of a joint's position in ``MjData.qpos``."""
        return int(self.model.jnt_qposadr[self.model.joint(joint).id])

    def table_qpos_indices(self) -> np.ndarray:
        """Indices of the axes' table positions in ``MjData.qpos``, in axis order."""
        return np.array([self.joint_qpos_index(a.table_joint) for a in self.axes])

    def joint_dof_index(self, joint: str) -> int:
        """Index of a joint's velocity in ``MjData.qvel``."""
        return int(self.model.jnt_dofadr[self.model.joint(joint).id])

    @property
    def workpiece_body_id(self) -> int:
        """Body id of the workpiece, where cutting forces go (``xfrc_applied``)."""
        return int(self.model.body("workpiece").id)

    def workpiece_jacobian(self) -> np.ndarray:
        """Matrix ``J``, shape (2, nv): world x/y velocity of the workpiece (m/s) = ``J @ qvel``.

        The workpiece rides on slide joints only, so ``J`` does not depend on the configuration,
        and its displacement from the model's reference pose is ``J @ qpos`` wherever ``J`` is
        non-zero (a slide's qpos and qvel share their address in models of hinges and slides).

        Raises
        ------
        ValueError
            If a joint carrying the workpiece is not a slide, or the model has joints whose
            positions and velocities are numbered differently (free or ball joints).
        """
        m = self.model
        if m.nq != m.nv:
            raise ValueError("workpiece_jacobian needs a model of hinge and slide joints only")
        body = self.workpiece_body_id
        while body:
            for j in range(m.body_jntadr[body], m.body_jntadr[body] + m.body_jntnum[body]):
                if m.jnt_type[j] != mujoco.mjtJoint.mjJNT_SLIDE:
                    raise ValueError(f"joint {m.joint(j).name!r} carrying the workpiece is not a slide")
            body = m.body_parentid[body]
        data = mujoco.MjData(m)
        mujoco.mj_forward(m, data)
        jacp = np.zeros((3, m.nv))
        mujoco.mj_jacBodyCom(m, data, jacp, None, self.workpiece_body_id)
        return jacp[:2].copy()

    def slip_m(self, qpos: np.ndarray) -> np.ndarray:
        """Kinematic mismatch (m of table travel) of each gear coupling.

        Parameters
        ----------
        qpos : ndarray, shape (n_samples, nq)
            Joint positions over time.

        Returns
        -------
        ndarray, shape (n_samples, n_couplings)
            ``|q_a - ratio q_b|`` converted to table travel with the axis lead.
        """
        cols = []
        for c in self.couplings:
            lead = self.table_per_screw_m_per_rad[c.axis]
            qa = qpos[:, self.joint_qpos_index(c.first)]
            qb = qpos[:, self.joint_qpos_index(c.second)]
            # motor-screw residual is in motor rad: table travel = residual * lead / n
            scale = lead / c.ratio if self.model.joint(c.second).type == mujoco.mjtJoint.mjJNT_HINGE else lead
            cols.append(np.abs(qa - c.ratio * qb) * scale)
        return np.stack(cols, axis=1) if cols else np.zeros((len(qpos), 0))


#: An override must lie within this factor of its nominal value (or below it in magnitude where
#: the nominal is 0): beyond, the models lose their meaning and their arithmetic overflows.
OVERRIDE_RANGE = 1e6


class Machine:
    """Base class: subclasses set the class attributes and implement the two hooks."""

    name: str = ""
    xml: str = ""
    summary: str = ""
    parameters: dict[str, Parameter] = {}
    axes: tuple[Axis, ...] = ()
    #: Each axis's limits for the G-code interpolator (Z: :data:`SPINDLE_HEAD_Z` unless given).
    motion_limits: dict[str, MotionLimits] = {}
    #: What a scenario's loops close on unless it says (:attr:`BuiltMachine.feedback`).
    feedback: str = "table"
    #: How a program is planned for it unless a scenario's ``[planner] mode`` says (None: the
    #: planner's default).
    planner_mode: str | None = None

    def resolve(self, overrides: dict[str, float] | None = None) -> dict[str, float]:
        """Merge overrides into the nominal values, validating names and values.

        Raises
        ------
        TwinInputError
            Unknown symbol, non-finite value, or a non-positive value for a positive parameter.
        """
        params = {k: p.value for k, p in self.parameters.items()}
        for key, value in (overrides or {}).items():
            if key not in self.parameters:
                known = ", ".join(self.parameters)
                raise TwinInputError(
                    f"overrides.{key}", value, f"unknown parameter of machine '{self.name}' (known: {known})"
                )
            try:
                value = float(value)
            except (TypeError, ValueError):
                raise TwinInputError(f"overrides.{key}", value, "must be a number") from None
            infinite = self.parameters[key].infinite and value == math.inf
            if not (math.isfinite(value) or infinite):
                raise TwinInputError(
                    f"overrides.{key}", value, "must be finite" + (" or inf" if self.parameters[key].infinite else "")
                )
            nominal = self.parameters[key].value
            limit = OVERRIDE_RANGE * abs(nominal) if nominal else OVERRIDE_RANGE
            in_range = (
                infinite
                or math.isinf(nominal)
                or not (abs(value) > limit or (nominal and value and abs(value) < abs(nominal) / OVERRIDE_RANGE))
            )
            if not in_range:
                raise TwinInputError(
                    f"overrides.{key}",
                    value,
                    f"must be within a factor {OVERRIDE_RANGE:g} of the "
                    f"nominal {nominal:g} {self.parameters[key].unit}",
                )
            if self.parameters[key].positive and value <= 0:
                raise TwinInputError(f"overrides.{key}", value, f"must be > 0 ({self.parameters[key].description})")
            if self.parameters[key].nonnegative and value < 0:
                raise TwinInputError(f"overrides.{key}", value, f"must be >= 0 ({self.parameters[key].description})")
            bounds = self.parameters[key].bounds
            if bounds is not None and not (
                bounds.low <= value <= bounds.high or infinite or (bounds.zero and value == 0)
            ):
                raise TwinInputError(f"overrides.{key}", value, f"must be {bounds.describe()}: {bounds.why}")
            params[key] = value
        self.check(params)
        return params

    def check(self, params: dict[str, float]) -> None:
        """Cross-parameter checks (override in subclasses)."""

    def configure(self, spec: mujoco.MjSpec, params: dict[str, float]) -> None:
        """Write parameter values into the spec (MjSpec edits)."""
        raise NotImplementedError

    def plant(self, params: dict[str, float], model: mujoco.MjModel) -> tuple[tuple[SisoTf, ...], ...]:
        """Reference transfer-function model, input (V) to table position (m), as
        :attr:`BuiltMachine.plant`."""
        raise NotImplementedError

    def delay(self, params: dict[str, float]) -> float:
        """Drive transport delay (s)."""
        return 0.0

    def couplings(self, params: dict[str, float]) -> tuple[list[Coupling], dict[str, float]]:
        """Gear couplings and leads (see :class:`BuiltMachine`)."""
        return [], {}

    def sensor_gains(self, params: dict[str, float]) -> tuple[float, ...]:
        """Encoder gain per axis."""
        return (1.0,) * len(self.axes)

    def motor_plant(self, params: dict[str, float], model: mujoco.MjModel) -> tuple[SisoTf, ...]:
        """Per axis, drive input (V) to motor angle in table travel (m); empty: as the table."""
        return ()

    def motor_travel(self, params: dict[str, float]) -> dict[str, float]:
        """Table travel per motor radian (m/rad) per axis with a motor: the lead over the
        motor-screw coupling's ratio."""
        couplings, leads = self.couplings(params)
        ratios = {a.name: c.ratio for a in self.axes for c in couplings if c.first == a.motor_joint}
        return {a: leads[a] / r for a, r in ratios.items()}

    def encoder_resolution(self, params: dict[str, float]) -> tuple[float, ...]:
        """Encoder resolution (m) per axis (0: ideal, the papers' machines)."""
        return (0.0,) * len(self.axes)

    def motor_encoder_resolution(self, params: dict[str, float]) -> tuple[float, ...]:
        """Motor encoder resolution in table travel (m) per axis (0: ideal, the papers' machines)."""
        return (0.0,) * len(self.axes)

    def coulomb_symbols(self) -> tuple[str, ...]:
        """The symbols of the guideways' Coulomb friction (what ``twin fidelity`` forces off)."""
        return tuple(s for s in (f"F_coul_{a.name}" for a in self.axes) if s in self.parameters)

    def make_spec(self, params: dict[str, float], timestep_s: float | None = None) -> mujoco.MjSpec:
        """The machine's MJCF with the parameter values written in: the hand-written file
        :attr:`xml` edited by :meth:`configure` (a machine file generates its own)."""
        spec = mujoco.MjSpec.from_file(str(mjcf_dir() / self.xml))
        if timestep_s is not None:
            spec.option.timestep = timestep_s
        self.configure(spec, params)
        for axis in self.axes:
            spec.joint(axis.table_joint).frictionloss = params.get(f"F_coul_{axis.name}", 0.0)
        return spec

    def mjcf(self, overrides: dict[str, float] | None = None, timestep_s: float | None = None) -> str:
        """The MJCF the twin simulates, with the parameter values written in, as XML text (for
        the user's own MuJoCo code: ``mujoco.MjModel.from_xml_string``)."""
        spec = self.make_spec(self.resolve(overrides), timestep_s)
        spec.compile()  # MjSpec writes XML of a compiled spec
        return spec.to_xml()

    def build(self, overrides: dict[str, float] | None = None, timestep_s: float | None = None) -> BuiltMachine:
        """Apply parameters with MjSpec, compile, and derive the reference model."""
        params = self.resolve(overrides)
        model = self.make_spec(params, timestep_s).compile()
        # a diverged state stays in MjData (not reset to the initial one) so the runner reports it
        model.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_AUTORESET
        couplings, leads = self.couplings(params)
        return BuiltMachine(
            self.name,
            model,
            params,
            self.axes,
            self.plant(params, model),
            self.delay(params),
            couplings,
            leads,
            self.sensor_gains(params),
            motion_limits={**self.motion_limits, "z": self.motion_limits.get("z", SPINDLE_HEAD_Z)},
            encoder_resolution_m=self.encoder_resolution(params),
            motor_encoder_resolution_m=self.motor_encoder_resolution(params),
            feedback=self.feedback,
            motor_plant=self.motor_plant(params, model),
            motor_travel_m_per_rad=self.motor_travel(params),
            planner_mode=self.planner_mode,
        )


def coulomb_friction_parameters(axes: tuple[str, ...], source: str = "") -> dict[str, Parameter]:
    """``F_coul_<axis>``: Coulomb friction (N) on each axis's guideway (table slide), MuJoCo
    ``frictionloss``; 0 by default (the papers' models have none); the catalogue estimates
    mu m g + 4 seals in the machine READMEs."""
    note = source or "the source gives no value; catalogue estimate in the machine README"
    return {
        f"F_coul_{a}": Parameter(
            0.0, "N", f"Coulomb friction on the {a.upper()} guideway ({note})", positive=False, nonnegative=True
        )
        for a in axes
    }


def set_gear(spec: mujoco.MjSpec, equality: str, ratio: float) -> None:
    """Set a joint-equality gear: ``q1 = ratio * q2``."""
    eq = spec.equality(equality)
    data = np.array(eq.data)
    data[:5] = [0.0, ratio, 0.0, 0.0, 0.0]
    eq.data = data


def set_mass(spec: mujoco.MjSpec, body: str, mass_kg: float) -> None:
    """Set a body's mass (kg), keeping its inertia tensor."""
    spec.body(body).mass = mass_kg


def set_axial_inertia(spec: mujoco.MjSpec, body: str, axis: int, inertia_kg_m2: float) -> None:
    """Set a body's principal inertia (kg m^2) about one of its axes (0 = x, 1 = y).

    The two other principal inertias are raised to at least this value so the tensor stays
    physical (triangle inequality); they do not enter the dynamics of a one-axis joint.
    """
    b = spec.body(body)
    inertia = np.maximum(np.array(b.inertia), inertia_kg_m2)
    inertia[axis] = inertia_kg_m2
    b.inertia = inertia


def check_stacked_masses(params: dict[str, float]) -> None:
    """Y rides on X: require m_x > m_y > m_workpiece (kg), naming the offending symbol."""
    if params["m_y"] <= params["m_workpiece"]:
        raise TwinInputError("overrides.m_y", params["m_y"], f"must exceed m_workpiece = {params['m_workpiece']:g} kg")
    if params["m_x"] <= params["m_y"]:
        raise TwinInputError("overrides.m_x", params["m_x"], f"must exceed m_y = {params['m_y']:g} kg (Y rides on X)")


def diagonal_plant(channels: list[SisoTf]) -> tuple[tuple[SisoTf, ...], ...]:
    """Diagonal transfer matrix from SISO channels (zeros elsewhere)."""
    zero = SisoTf((0.0,), (1.0,))
    return tuple(tuple(g if i == j else zero for j in range(len(channels))) for i, g in enumerate(channels))


#: Machines by name, in registration order: each machine's module registers its class with
#: :func:`register_machine` (every module of :mod:`twin.machines` is imported by the package);
#: each entry's value is the machine, its summary the machine's ``summary``.
MACHINES: Registry[Machine] = Registry("machine")


def register_machine(cls: type[Machine]) -> type[Machine]:
    """Class decorator: add an instance of the machine ``cls`` to :data:`MACHINES` under its
    ``name``; its parameters (values, units, sources, limits), model file and ``summary`` (the
    docs line) are the class's own.

    Raises
    ------
    ValueError
        A class without a name, or a name registered already.
    """
    MACHINES.add(cls.name, cls(), summary=cls.summary)
    return cls
