"""Closed-loop runner: controllers on the signal bus + drive + MuJoCo machine + encoders.

One control tick (period ``control_period_s``, a whole multiple of the physics timestep):

    table positions -> encoder, velocity measurement, reference (and its preview) -> signal bus
    -> the controllers' blocks -> u (V) -> drive (input disturbance, saturation, delay line)
    -> MjData.ctrl -> physics steps (``mj_step``; force models write the workpiece's
    ``xfrc_applied`` before each step)

The loop (:mod:`twin.sim.loop`) runs compiled whenever every block has a compiled kernel
(every kind but Python blocks), in chunks of ticks; between chunks the runner samples the next
stretch of the reference and disturbances, draws the noise, updates the progress bar and
reads MuJoCo's warning counters.  The state is recorded at the start of every recorded tick,
so ``u[k]`` is the input held over ``[t[k], t[k+1])`` (zero-order hold); so is the workpiece
force, recorded as the mean of the forces applied over that interval.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field

import mujoco
import numpy as np
from tqdm import tqdm

from controllers.blocks import BlockProgram, Controller, SignalError, preview_ticks_needed, standard_signals
from twin.errors import RunInterrupted, SimulationDiverged, TwinInputError
from twin.machines import BuiltMachine
from twin.machining.cutting import PROBE, ForceModels
from twin.sim import loop, mujoco_c
from twin.sim.drive import MAX_VALUE, Drive, Encoder, substeps_per_tick
from twin.sim.protocols import Disturbance, ForceModel, InputDisturbance, ProgramReference, Reference

#: Table travel (m) beyond which a run counts as runaway.
RUNAWAY_M = 10.0
#: Simulated physics steps above which a progress bar is shown (about 5 s of wall time).
PROGRESS_STEPS = 1_000_000
#: Ticks per chunk at most (bounds the reference, noise and disturbance arrays held at once).
CHUNK_TICKS = 8192
#: Physics steps per chunk at most: the loop returns to Python (progress, Ctrl-C) about every second.
CHUNK_STEPS = 200_000
#: Physics steps one run may take unless the caller allows more: 3-7 minutes of a plain run on
#: a 2-core machine (1e8 steps ran 14-35 minutes there); a run cutting a stock takes longer
#: per step.
MAX_PHYSICS_STEPS = 20_000_000
#: Recorded ticks at most when ``record_every`` is left to the runner: longer runs are decimated,
#: so memory stays bounded whatever the duration (about 25 MB for a two-axis machine).
MAX_RECORDED_TICKS = 100_000
#: MuJoCo warnings that mean the simulation is no longer valid.
FATAL_WARNINGS = (
    mujoco.mjtWarning.mjWARN_BADQACC,
    mujoco.mjtWarning.mjWARN_BADQVEL,
    mujoco.mjtWarning.mjWARN_BADQPOS,
    mujoco.mjtWarning.mjWARN_BADCTRL,
)


@dataclass
class ProgramTrace:
    """What a part program's reference says of a run's recorded ticks.

    Attributes
    ----------
    lines : ndarray of int, shape (n,)
        The program line at each recorded tick.
    texts : dict of int to str
        The text of each line that moved or dwelt.
    feed_mm_per_min : ndarray, shape (n,)
        The programmed feed at each recorded tick (0 on rapids and dwells).
    cycle_time_s : float
        The program's planned cycle time.
    extra_axes : dict of str to ndarray
        Planned axes the machine has not (a program's z), m, at the recorded ticks.
    engagement : ndarray, shape (n, 2)
        With a stock: the engaged angle (deg) and axial depth (mm) at each recorded tick (else
        empty).

    What is said of the whole program (its warnings, a stock's outlines, the part cut) is
    computed outside the run: :class:`twin.outcome.RunOutcome`.
    """

    lines: np.ndarray
    texts: dict[int, str]
    feed_mm_per_min: np.ndarray
    cycle_time_s: float
    extra_axes: dict[str, np.ndarray]
    engagement: np.ndarray


@dataclass
class RunResult:
    """Time series of one closed-loop run at the recorded ticks, and metrics over every tick.

    Attributes
    ----------
    machine : BuiltMachine
    t_s : ndarray, shape (n,)
        Times of the recorded ticks (s).
    ref : ndarray, shape (n, n_axes, 3)
        Reference position (m), velocity (m/s), acceleration (m/s^2).
    meas_m : ndarray, shape (n, n_axes)
        Encoder readings (m).
    u_V : ndarray, shape (n, n_axes)
        Controller outputs (V), before the drive.
    u_applied_V : ndarray, shape (n, n_axes)
        Drive input after disturbance and saturation (V), before the delay.
    qpos, qvel : ndarray, shape (n, nq), (n, nv)
        Every joint's position (m or rad) and velocity (m/s or rad/s).
    actuator_force : ndarray, shape (n, nu)
        Actuator force/torque (N or N m) at the last physics step before each tick.
    workpiece_force_N : ndarray, shape (n, 3)
        External force on the workpiece (world frame, N), mean over the tick's physics steps.
    vibration_probe : ndarray, shape (n, len(PROBE))
        The milling kernels' vibration probe (:data:`twin.machining.cutting.PROBE`) summed over
        the physics steps from each recorded tick to the next (:mod:`twin.machining.chatter`).
    control_period_s : float
    error_max_m, error_rms_m : ndarray, shape (n_axes,)
        Max |ref - table position| and its RMS over every tick, recorded or not (m).
    force_max_N : ndarray, shape (n_axes,)
        Largest tick-mean workpiece force along each axis (N).
    info : dict
        ``loop`` ("compiled" or "python"), ``record_every`` (ticks; 0: metrics only),
        ``completed_ticks`` (all of them, unless the run diverged or was interrupted).
    program : ProgramTrace or None
        For a part program's reference: its lines, feeds and engagement at the recorded ticks.
    """

    machine: BuiltMachine
    t_s: np.ndarray
    ref: np.ndarray
    meas_m: np.ndarray
    u_V: np.ndarray
    u_applied_V: np.ndarray
    qpos: np.ndarray
    qvel: np.ndarray
    actuator_force: np.ndarray
    workpiece_force_N: np.ndarray
    vibration_probe: np.ndarray
    control_period_s: float
    error_max_m: np.ndarray
    error_rms_m: np.ndarray
    force_max_N: np.ndarray
    info: dict = field(default_factory=dict)
    program: ProgramTrace | None = None

    @property
    def axis_names(self) -> list[str]:
        return [a.name for a in self.machine.axes]

    @property
    def has_workpiece_force(self) -> bool:
        """Whether a force model acted on the workpiece during the recorded ticks."""
        return bool(np.any(self.workpiece_force_N))

    def table_position_m(self) -> np.ndarray:
        """Table positions (m), shape (n, n_axes)."""
        return self.qpos[:, self.machine.table_qpos_indices()]

    def error_m(self) -> np.ndarray:
        """Tracking error reference - table position (m), shape (n, n_axes)."""
        return self.ref[:, :, 0] - self.table_position_m()


def _program(
    machine: BuiltMachine, controllers: Sequence[Controller], control_period_s: float
) -> tuple[BlockProgram, int]:
    """The controllers compiled onto the machine's bus, and the preview length (ticks) they read;
    checks that they drive each axis once."""
    names = [a.name for a in machine.axes]
    driven = []
    for c in controllers:
        if abs(c.dt - control_period_s) > 1e-12:
            raise TwinInputError(f"controller {c.name}.dt", c.dt, f"differs from control_period_s = {control_period_s}")
        driven += c.drives
    if sorted(driven) != sorted(names):
        raise TwinInputError(
            "controller",
            [c.name for c in controllers],
            f"drive axes {driven}; machine '{machine.name}' needs each of {names} once",
        )
    try:
        preview = preview_ticks_needed(s for c in controllers for s in c.inputs)
        return BlockProgram(controllers, standard_signals(names, preview)), preview
    except SignalError as exc:
        raise TwinInputError(f"controller block {exc.block}", exc.signal, exc.reason) from None
    except ValueError as exc:
        raise TwinInputError("controller", [c.name for c in controllers], str(exc)) from None


@dataclass(frozen=True)
class RunPlan:
    """A run checked and laid out before anything is allocated (:func:`_plan`).

    Attributes
    ----------
    n_ticks, substeps : int
        Control ticks of the run and physics steps per tick.
    control_period_s, timestep_s : float
        The control period and the physics step (s).
    record_every : int
        Record every Nth tick (0: none).
    program : controllers.blocks.BlockProgram
        The controllers on the machine's bus.
    preview : int
        Reference preview the controllers read (ticks).
    compiled : bool
        Whether the compiled loop runs.
    drive : Drive
    encoder : Encoder
    input_disturbances : list of InputDisturbance
    force_models : list of ForceModel
    """

    n_ticks: int
    substeps: int
    control_period_s: float
    timestep_s: float
    record_every: int
    program: BlockProgram
    preview: int
    compiled: bool
    drive: Drive
    encoder: Encoder
    input_disturbances: list[InputDisturbance]
    force_models: list[ForceModel]

    def recorded_rows(self, ticks: int) -> int:
        """Recorded rows among the first ``ticks`` ticks."""
        return 0 if self.record_every == 0 else -(-ticks // self.record_every)


def _plan(
    machine: BuiltMachine,
    controllers: list[Controller],
    reference: Reference,
    *,
    duration_s: float,
    control_period_s: float,
    drive: Drive | None,
    encoder: Encoder | None,
    disturbances: Sequence[Disturbance],
    record_every: int | None,
    compiled: bool | None,
    max_physics_steps: int,
) -> RunPlan:
    """Check a run's inputs against each other and the machine, and lay it out (see
    :func:`simulate` for the parameters and the errors)."""
    n_axes = len(machine.axes)
    dt = machine.model.opt.timestep
    substeps = substeps_per_tick(control_period_s, dt)
    if not (duration_s > 0 and math.isfinite(duration_s)):
        raise TwinInputError("duration_s", duration_s, "must be > 0")
    if not duration_s / dt <= max_physics_steps:
        raise TwinInputError(
            "duration_s",
            duration_s,
            f"needs {duration_s / dt:.3g} physics steps of {dt:g} s, more "
            f"than the {max_physics_steps:,} allowed (twin run --max-steps)",
        )
    if reference.n_axes != n_axes:
        raise TwinInputError(
            "reference", type(reference).__name__, f"has {reference.n_axes} axes, machine '{machine.name}' has {n_axes}"
        )
    if record_every is not None and (int(record_every) != record_every or record_every < 0):
        raise TwinInputError("record_every", record_every, "must be a whole number >= 0")
    program, preview = _program(machine, controllers, control_period_s)
    program.reset()
    can_compile = mujoco_c.available() and program.compiled
    if compiled and not can_compile:
        raise TwinInputError(
            "compiled", True, "needs compiled blocks only (no Python block) and MuJoCo's shared library"
        )
    drive = drive or Drive(n_axes, substeps, dt, machine.delay_s)
    encoder = encoder or Encoder(
        np.zeros(n_axes), np.zeros(n_axes), np.array(machine.sensor_gains), feedback=machine.feedback
    )
    if drive.n_axes != n_axes or drive.substeps != substeps:
        raise TwinInputError(
            "drive", (drive.n_axes, drive.substeps), f"needs {n_axes} axes and {substeps} physics steps per tick"
        )
    for name in ("gains", "resolution_m", "noise_std_m", "motor_resolution_m"):
        if getattr(encoder, name).shape != (n_axes,):
            raise TwinInputError(
                f"encoder.{name}", getattr(encoder, name).tolist(), f"needs one value per axis ({n_axes})"
            )
    n_ticks = round(duration_s / control_period_s)
    if n_ticks < 1:
        raise TwinInputError("duration_s", duration_s, f"shorter than one control period ({control_period_s:g} s)")
    return RunPlan(
        n_ticks=n_ticks,
        substeps=substeps,
        control_period_s=control_period_s,
        timestep_s=dt,
        record_every=-(-n_ticks // MAX_RECORDED_TICKS) if record_every is None else int(record_every),
        program=program,
        preview=preview,
        compiled=can_compile if compiled is None else compiled,
        drive=drive,
        encoder=encoder,
        input_disturbances=[d for d in disturbances if isinstance(d, InputDisturbance)],
        force_models=[d for d in disturbances if isinstance(d, ForceModel)],
    )


@dataclass
class LoopArrays:
    """Everything the loop reads and writes (:mod:`twin.sim.loop`), allocated once per run."""

    data: mujoco.MjData
    mj: loop.MjViews
    sensor: loop.Sensor
    drive: loop.DriveState
    force: loop.ForceState
    recording: loop.Recording
    accumulators: loop.Accumulators


def _allocate(machine: BuiltMachine, plan: RunPlan) -> LoopArrays:
    """The loop's state and recording arrays for ``plan`` on ``machine``."""
    model = machine.model
    n_axes = len(machine.axes)
    data = mujoco.MjData(model)
    rows = plan.recorded_rows(plan.n_ticks)
    recording = loop.Recording(
        every=plan.record_every,
        qpos=np.empty((rows, model.nq)),
        qvel=np.empty((rows, model.nv)),
        actuator_force=np.empty((rows, model.nu)),
        ref=np.empty((rows, n_axes, 3)),
        meas=np.empty((rows, n_axes)),
        u=np.empty((rows, n_axes)),
        ua=np.empty((rows, n_axes)),
        workpiece_force=np.empty((rows, 3)),
        probe=np.zeros((rows, len(PROBE))),
    )
    mj = loop.MjViews(
        qpos=data.qpos,
        qvel=data.qvel,
        qacc=data.qacc,
        ctrl=data.ctrl,
        actuator_force=data.actuator_force,
        xfrc_applied=data.xfrc_applied,
    )
    encoder = plan.encoder

    # each axis's encoders (twin.sim.drive.FEEDBACK): the position loop's and the velocity
    # loop's, on its table or on its motor (in table travel)
    def travel(a, joint):
        return machine.motor_travel_m_per_rad[a.name] if joint == a.motor_joint else 1.0

    def resolution(joints):
        on_motor = np.array([j == a.motor_joint for a, j in zip(machine.axes, joints)])
        return np.where(on_motor, encoder.motor_resolution_m, encoder.resolution_m)

    position = [a.encoder_joint(encoder.feedback) for a in machine.axes]
    velocity = [a.velocity_joint(encoder.feedback) for a in machine.axes]
    second = np.array([p != v for p, v in zip(position, velocity)])
    sensor = loop.Sensor(
        q_idx=machine.table_qpos_indices(),
        encoder_q_idx=np.array([machine.joint_qpos_index(j) for j in position]),
        gains=encoder.gains * np.array([travel(a, j) for a, j in zip(machine.axes, position)]),
        resolution=resolution(position),
        vel_q_idx=np.array([machine.joint_qpos_index(j) for j in velocity]),
        vel_v_idx=np.array([machine.joint_dof_index(j) for j in velocity]),
        vel_gains=encoder.gains * np.array([travel(a, j) for a, j in zip(machine.axes, velocity)]),
        vel_resolution=resolution(velocity),
        vel_noise=np.where(second, 0.0, 1.0),
        tachometer=encoder.velocity == "tachometer",
        period_s=float(plan.control_period_s),
        runaway_m=RUNAWAY_M,
        meas_prev=np.zeros(n_axes),
        preview=plan.preview,
    )
    drive = loop.DriveState(
        u_idx=np.array([plan.program.index(f"u.{a.name}") for a in machine.axes]),
        act_idx=np.array([model.actuator(a.actuator).id for a in machine.axes]),
        limit=plan.drive.limit_V,
        substeps=plan.substeps,
        delay_steps=plan.drive.delay_steps,
        delay_line=plan.drive.delay_line(),
        u=np.zeros(n_axes),
        ua=np.zeros(n_axes),  # the drive input of the last tick (V), reported on divergence
        u_sat=np.zeros(n_axes),
    )
    forces = ForceModels(plan.force_models, machine)
    force = loop.ForceState(
        fops=forces.fops,
        fpar=forces.fpar,
        fstate=forces.fstate,
        workpiece_body=machine.workpiece_body_id,
        timestep_s=plan.timestep_s,
        clock=np.array([data.time]),
        f_sum=np.zeros(3),
        feed_jacobian=np.ascontiguousarray(machine.workpiece_jacobian()[:, machine.table_qpos_indices()]),
        feed_velocity=np.zeros(2),
        probe=np.zeros(len(PROBE)),
    )
    accumulators = loop.Accumulators(error=np.zeros((n_axes, 2)), force_max=np.zeros(n_axes))
    return LoopArrays(data, mj, sensor, drive, force, recording, accumulators)


class _ProgramSeries:
    """What a program's reference says of the recorded ticks, gathered chunk by chunk as the run
    goes (a long program's reference is planned as it is asked for and keeps no past)."""

    def __init__(self, reference: ProgramReference, plan: RunPlan):
        self.reference, self.plan = reference, plan
        self.parts: dict[str, list] = {"extra": [], "lines": [], "engagement": [], "feeds": []}

    def record(self, k0: int, k1: int) -> None:
        """Gather ticks ``k0`` to ``k1`` (those recorded)."""
        every = self.plan.record_every
        if every == 0:
            return
        t_rec = np.arange(-(-k0 // every) * every, k1, every) * self.plan.control_period_s
        self.parts["extra"].append(self.reference.extra_series(t_rec))
        self.parts["lines"].append(self.reference.lines_at(t_rec))
        self.parts["engagement"].append(self.reference.engagement_at(t_rec))
        self.parts["feeds"].append(self.reference.feeds_at(t_rec))

    def _gathered(self, name: str, rows: int, empty: np.ndarray) -> np.ndarray:
        return np.concatenate(self.parts[name])[:rows] if self.parts[name] else empty

    def trace(self, rows: int) -> ProgramTrace:
        """The trace of the first ``rows`` recorded ticks."""
        extra = self.parts["extra"]
        return ProgramTrace(
            lines=self._gathered("lines", rows, np.zeros(0, int)),
            texts=self.reference.texts,
            feed_mm_per_min=self._gathered("feeds", rows, np.zeros(0)),
            cycle_time_s=self.reference.duration_s,
            extra_axes={name: np.concatenate([part[name] for part in extra])[:rows] for name in extra[0]}
            if extra
            else {},
            engagement=self._gathered("engagement", rows, np.zeros((0, 2))),
        )


def _result(
    machine: BuiltMachine,
    plan: RunPlan,
    *,
    arrays: LoopArrays,
    series: _ProgramSeries | None,
    ticks: int,
    accumulated: int,
) -> RunResult:
    """The run's first ``ticks`` ticks (metrics over the ``accumulated`` ones)."""
    rows = plan.recorded_rows(ticks)
    rec, acc = arrays.recording, arrays.accumulators
    return RunResult(
        machine=machine,
        t_s=np.arange(rows) * plan.record_every * plan.control_period_s,
        ref=rec.ref[:rows],
        meas_m=rec.meas[:rows],
        u_V=rec.u[:rows],
        u_applied_V=rec.ua[:rows],
        qpos=rec.qpos[:rows],
        qvel=rec.qvel[:rows],
        actuator_force=rec.actuator_force[:rows],
        workpiece_force_N=rec.workpiece_force[:rows],
        vibration_probe=rec.probe[:rows],
        control_period_s=plan.control_period_s,
        error_max_m=acc.error[:, 0].copy(),
        error_rms_m=np.sqrt(acc.error[:, 1] / max(accumulated, 1)),
        force_max_N=acc.force_max.copy(),
        info={
            "loop": "compiled" if plan.compiled else "python",
            "record_every": plan.record_every,
            "completed_ticks": ticks,
        },
        program=None if series is None else series.trace(rows),
    )


def simulate(
    machine: BuiltMachine,
    controllers: Sequence[Controller] | Controller,
    reference: Reference,
    *,
    duration_s: float,
    control_period_s: float,
    drive: Drive | None = None,
    encoder: Encoder | None = None,
    disturbances: Sequence[Disturbance] = (),
    record_every: int | None = None,
    progress: bool | None = None,
    compiled: bool | None = None,
    max_physics_steps: int = MAX_PHYSICS_STEPS,
) -> RunResult:
    """Run the closed loop for ``duration_s`` and return its time series and metrics.

    In four steps: check and lay out the run (:func:`_plan`), allocate the loop's arrays
    (:func:`_allocate`), run the loop chunk by chunk (:func:`_run_loop`) and build the result
    (:func:`_result`).

    Parameters
    ----------
    machine : BuiltMachine
    controllers : Controller or sequence of Controller
        Together they write ``u.<axis>`` for every machine axis once; each ``dt`` must equal
        ``control_period_s``.
    reference : Reference
        See :mod:`twin.references`; a :class:`~twin.sim.protocols.ProgramReference` adds a
        :class:`ProgramTrace` to the result.
    duration_s, control_period_s : float
        Run length and control period (s).
    drive, encoder : optional
        Default: machine delay, no saturation; ideal encoder with the machine's sensor gains.
    disturbances : sequence of InputDisturbance or ForceModel
        See :mod:`twin.sim.protocols`.
    record_every : int or None
        Record every Nth tick; 0 records no series (metrics only); None: every tick, or every
        Nth for runs over ``MAX_RECORDED_TICKS`` ticks so that at most that many are kept.
    progress : bool or None
        Progress bar; None shows one for runs over ``PROGRESS_STEPS`` physics steps.
    compiled : bool or None
        Run the compiled loop (every block compiled) or the Python loop.  None picks the
        compiled loop whenever it can run.
    max_physics_steps : int
        A run that would take more physics steps is refused before it starts.

    Raises
    ------
    SimulationDiverged
        Non-finite or huge state, acceleration or drive input, a fatal MuJoCo warning, or a
        table beyond ``RUNAWAY_M``; with the simulated time and, as ``result``, the run up to
        the last whole tick.
    RunInterrupted
        Ctrl-C (KeyboardInterrupt) during the run, with the run up to the last whole chunk.
    TwinInputError
        Inconsistent periods, references or controllers (a block reading a signal nothing
        provides), or ``compiled=True`` where the compiled loop cannot run.
    """
    controllers = [controllers] if isinstance(controllers, Controller) else list(controllers)
    plan = _plan(
        machine,
        controllers,
        reference,
        duration_s=duration_s,
        control_period_s=control_period_s,
        drive=drive,
        encoder=encoder,
        disturbances=disturbances,
        record_every=record_every,
        compiled=compiled,
        max_physics_steps=max_physics_steps,
    )
    arrays = _allocate(machine, plan)
    series = _ProgramSeries(reference, plan) if isinstance(reference, ProgramReference) else None
    show = progress if progress is not None else plan.n_ticks * plan.substeps > PROGRESS_STEPS
    _run_loop(machine, plan, arrays=arrays, reference=reference, series=series, show=show)
    return _result(machine, plan, arrays=arrays, series=series, ticks=plan.n_ticks, accumulated=plan.n_ticks)


def _run_loop(
    machine: BuiltMachine,
    plan: RunPlan,
    *,
    arrays: LoopArrays,
    reference: Reference,
    series: _ProgramSeries | None,
    show: bool,
) -> None:
    """Run every tick of ``plan``, chunk by chunk: sample the reference, disturbances and noise,
    run the loop (compiled or Python), check it and update the progress bar.  A failure raises
    with the result up to it (see :func:`simulate`)."""
    model, data = machine.model, arrays.data
    period, n_axes = plan.control_period_s, len(machine.axes)
    draw_noise = plan.encoder.noise_source()
    if plan.compiled:
        addresses = mujoco_c.struct_addresses(model, data)
        prog = loop.ProgramArrays(
            ops=plan.program.ops,
            io=plan.program.io,
            par=plan.program.par,
            state=plan.program.state,
            scratch=plan.program.scratch,
            bus=plan.program.bus,
        )

    def run_chunk(k0, k1, chunk):
        if plan.compiled:
            return loop.compiled_ticks(
                k0, k1, mujoco_c.MJ_STEP, *addresses, arrays.mj, arrays.sensor, arrays.drive, prog, arrays.force,
                chunk, arrays.recording, arrays.accumulators,
            )  # fmt: skip
        return loop.python_ticks(
            k0,
            k1,
            model=model,
            data=data,
            program=plan.program,
            mj=arrays.mj,
            sensor=arrays.sensor,
            drive=arrays.drive,
            force=arrays.force,
            chunk=chunk,
            rec=arrays.recording,
            acc=arrays.accumulators,
        )

    size = max(1, min(CHUNK_TICKS, CHUNK_STEPS // plan.substeps, plan.n_ticks))
    warnings0 = [data.warning[w].number for w in FATAL_WARNINGS]
    messages: list[str] = []
    done = 0
    try:
        with (
            _mujoco_warnings_into(messages),
            _progress_bar(reference, plan.n_ticks, machine.name, show) as bar,
        ):
            for k0 in range(0, plan.n_ticks, size):
                k1 = min(plan.n_ticks, k0 + size)
                t = np.arange(k0, k1 + plan.preview) * period
                u_dist = np.zeros((k1 - k0, n_axes))
                with np.errstate(all="ignore"):  # overflow shows as non-finite values, reported below
                    for dist in plan.input_disturbances:
                        u_dist += dist.input_V(t[: k1 - k0])
                    ref = np.ascontiguousarray(reference.sample(t))
                bad = ~np.isfinite(ref).all(axis=(1, 2))
                if bad.any():  # the ticks before this chunk are kept
                    exc = SimulationDiverged(
                        (k0 + int(np.argmax(bad))) * period,
                        "the reference (position, velocity or acceleration) is not finite here: it overflows",
                    )
                    exc.result = _result(machine, plan, arrays=arrays, series=series, ticks=k0, accumulated=k0)
                    raise exc
                if series is not None:
                    series.record(k0, k1)
                chunk = loop.Chunk(ref=ref, noise=draw_noise(k1 - k0), u_dist=u_dist)
                status, k, s = run_chunk(k0, k1, chunk)
                try:
                    _check(
                        status,
                        k,
                        s=s,
                        data=data,
                        q_idx=arrays.sensor.q_idx,
                        ua=arrays.drive.ua,
                        period=period,
                        dt=plan.timestep_s,
                        warnings0=warnings0,
                        messages=messages,
                    )
                except SimulationDiverged as exc:  # keep what was computed: the ticks before k
                    accumulated = k + (status in (loop.BAD_CONTROL, loop.BAD_QACC))
                    exc.result = _result(machine, plan, arrays=arrays, series=series, ticks=k, accumulated=accumulated)
                    raise
                done = k1
                if series is not None:  # a program: progress in its lines, all of them at the end
                    program = series.reference
                    line = program.n_lines if k1 == plan.n_ticks else program.line_at(k1 * period)
                    bar.update(max(line - bar.n, 0))
                else:
                    bar.update(k1 - k0)
    except KeyboardInterrupt:
        raise RunInterrupted(
            done * period, _result(machine, plan, arrays=arrays, series=series, ticks=done, accumulated=done)
        ) from None


def _progress_bar(reference: Reference, n_ticks: int, name: str, show: bool) -> tqdm:
    """The run's progress bar: in ticks, or in program lines for a G-code reference."""
    if isinstance(reference, ProgramReference):
        return tqdm(total=reference.n_lines, desc=f"{name} program", unit="line", disable=not show, leave=False)
    return tqdm(total=n_ticks, desc=name, unit="tick", disable=not show, mininterval=0.5, leave=False)


@contextmanager
def _mujoco_warnings_into(messages: list):
    """Collect MuJoCo's warning texts in ``messages`` instead of printing them and writing
    ``MUJOCO_LOG.TXT`` into the working folder (``mujoco.set_mju_user_warning``)."""
    previous = mujoco.get_mju_user_warning()
    mujoco.set_mju_user_warning(messages.append)
    try:
        yield
    finally:
        mujoco.set_mju_user_warning(previous)


def _check(status, k, *, s, data, q_idx, ua, period, dt, warnings0, messages) -> None:
    """Raise :class:`SimulationDiverged` for a failed chunk or a new fatal MuJoCo warning
    (with MuJoCo's own words where it gave any)."""
    t = _failure_time(status, k, s=s, period=period, dt=dt)
    if status != loop.OK and messages:
        raise SimulationDiverged(t, f"{messages[0]} (MuJoCo)")
    if status == loop.RUNAWAY:
        raise SimulationDiverged(t, f"table position {data.qpos[q_idx].tolist()} m beyond {RUNAWAY_M} m or not finite")
    if status == loop.BAD_CONTROL:
        raise SimulationDiverged(t, f"drive input {ua.tolist()} V not finite or beyond {MAX_VALUE:g}")
    if status == loop.BAD_QACC:
        raise SimulationDiverged(t, f"accelerations not finite or beyond {MAX_VALUE:g} (MuJoCo's BADQACC test)")
    for w, before in zip(FATAL_WARNINGS, warnings0):
        if data.warning[w].number != before:
            raise SimulationDiverged(data.time, " ".join(messages) or f"MuJoCo warning {mujoco.mjtWarning(w).name}")


def _failure_time(status, k, *, s, period, dt) -> float:
    """Simulated time (s) of a failure: the start of tick k, or the end of its physics step s."""
    return k * period + (s + 1) * dt if status == loop.BAD_QACC else k * period
