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
from typing import Any, Protocol

import mujoco
import numpy as np
from tqdm import tqdm

from controllers.blocks import Controller, Program, SignalError, preview_ticks_needed, standard_signals
from twin.errors import RunInterrupted, SimulationDiverged, TwinInputError
from twin.machines import BuiltMachine
from twin.process.cutting import ForceModels
from twin.sim import loop, mujoco_c
from twin.sim.drive import MAX_VALUE, Drive, Encoder, substeps_per_tick

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


class Disturbance(Protocol):
    """A disturbance adds to the drive input, or acts on the workpiece before each physics step.

    ``input_V(t)`` returns ndarray (len(t), n_axes) added to the control input (V);
    ``kernel_arrays(machine)`` returns ``(kind, params, state)`` of a compiled force model
    (:mod:`twin.process.cutting`).  A disturbance has one of the two.
    """


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
    control_period_s : float
    error_max_m, error_rms_m : ndarray, shape (n_axes,)
        Max |ref - table position| and its RMS over every tick, recorded or not (m).
    force_max_N : ndarray, shape (n_axes,)
        Largest tick-mean workpiece force along each axis (N).
    info : dict
        ``loop`` ("compiled" or "python"), ``record_every`` (ticks; 0: metrics only),
        ``completed_ticks`` (all of them, unless the run diverged or was interrupted).
    reference_extra : dict of str to ndarray
        Planned axes the machine does not have (a G-code program's z), m, at the recorded ticks.
    program_lines : ndarray of int
        For a G-code reference, the program line at each recorded tick (else empty).
    program_texts : dict of int to str
        For a G-code reference, the text of each line that moved.
    engagement : ndarray (n, 2)
        With a stock: the engaged angle (deg) and axial depth (mm) at each recorded tick (else
        empty).
    program_feed_mm_per_min : ndarray (n,)
        For a G-code reference, the programmed feed at each recorded tick (else empty).
    part_outlines : dict of str to list of ndarray
        With a stock: ``stock`` and ``machined`` outlines (mm), as the program leaves them.
    machining_warnings : list of dict
        With a stock: crashes and misuse by program line
        (:func:`twin.process.misuse.machining_warnings`); ``info["machining_warnings_total"]``
        counts them all.
    part : twin.process.part.MachinedPart or None
        With a stock: the part the actual motion cut, against the nominal one.
    inspection : list of dict
        The ``[[inspect]]`` features measured on it (:func:`twin.process.inspection.measure`).
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
    control_period_s: float
    error_max_m: np.ndarray
    error_rms_m: np.ndarray
    force_max_N: np.ndarray
    info: dict = field(default_factory=dict)
    reference_extra: dict = field(default_factory=dict)
    program_lines: np.ndarray = field(default_factory=lambda: np.zeros(0, int))
    program_texts: dict = field(default_factory=dict)
    engagement: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    program_feed_mm_per_min: np.ndarray = field(default_factory=lambda: np.zeros(0))
    part_outlines: dict = field(default_factory=dict)
    machining_warnings: list = field(default_factory=list)
    part: Any = None
    inspection: list = field(default_factory=list)

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


def _program(machine: BuiltMachine, controllers: Sequence[Controller], control_period_s: float) -> tuple[Program, int]:
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
        return Program(controllers, standard_signals(names, preview)), preview
    except SignalError as exc:
        raise TwinInputError(f"controller block {exc.block}", exc.signal, exc.reason) from None
    except ValueError as exc:
        raise TwinInputError("controller", [c.name for c in controllers], str(exc)) from None


def simulate(
    machine: BuiltMachine,
    controllers: Sequence[Controller] | Controller,
    reference,
    duration_s: float,
    control_period_s: float,
    *,
    drive: Drive | None = None,
    encoder: Encoder | None = None,
    disturbances: Sequence[Disturbance] = (),
    record_every: int | None = None,
    progress: bool | None = None,
    compiled: bool | None = None,
    max_physics_steps: int = MAX_PHYSICS_STEPS,
) -> RunResult:
    """Run the closed loop for ``duration_s`` and return its time series and metrics.

    Parameters
    ----------
    machine : BuiltMachine
    controllers : Controller or sequence of Controller
        Together they write ``u.<axis>`` for every machine axis once; each ``dt`` must equal
        ``control_period_s``.
    reference : object with ``n_axes`` and ``sample(t)``
        See :mod:`twin.references`.
    duration_s, control_period_s : float
        Run length and control period (s).
    drive, encoder : optional
        Default: machine delay, no saturation; ideal encoder with the machine's sensor gains.
    disturbances : sequence
        See :class:`Disturbance`.
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
    model = machine.model
    names = [a.name for a in machine.axes]
    n_axes = len(names)
    dt = model.opt.timestep
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
    controllers = [controllers] if isinstance(controllers, Controller) else list(controllers)
    program, preview = _program(machine, controllers, control_period_s)
    program.reset()
    can_compile = mujoco_c.available() and program.compiled
    if compiled and not can_compile:
        raise TwinInputError(
            "compiled", True, "needs compiled blocks only (no Python block) and MuJoCo's shared library"
        )
    use_compiled = can_compile if compiled is None else compiled
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
    input_disturbances = [d for d in disturbances if hasattr(d, "input_V")]
    forces = ForceModels([d for d in disturbances if hasattr(d, "kernel_arrays")], machine)

    n = round(duration_s / control_period_s)
    if n < 1:
        raise TwinInputError("duration_s", duration_s, f"shorter than one control period ({control_period_s:g} s)")
    if record_every is None:
        record_every = -(-n // MAX_RECORDED_TICKS)
    data = mujoco.MjData(model)
    n_rec = 0 if record_every == 0 else -(-n // record_every)
    rec = loop.Recording(
        int(record_every),
        np.empty((n_rec, model.nq)),
        np.empty((n_rec, model.nv)),
        np.empty((n_rec, model.nu)),
        np.empty((n_rec, n_axes, 3)),
        np.empty((n_rec, n_axes)),
        np.empty((n_rec, n_axes)),
        np.empty((n_rec, n_axes)),
        np.empty((n_rec, 3)),
    )
    acc = loop.Accumulators(np.zeros((n_axes, 2)), np.zeros(n_axes))
    mj = loop.MjViews(data.qpos, data.qvel, data.qacc, data.ctrl, data.actuator_force, data.xfrc_applied)

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
        period_s=float(control_period_s),
        runaway_m=RUNAWAY_M,
        meas_prev=np.zeros(n_axes),
        preview=preview,
    )
    u_applied = np.zeros(n_axes)  # the drive input of the last tick (V), reported on divergence
    drive_args = loop.DriveState(
        np.array([program.index(f"u.{a}") for a in names]),
        np.array([model.actuator(a.actuator).id for a in machine.axes]),
        drive.limit_V,
        substeps,
        drive.delay_steps,
        drive.delay_line(),
        np.zeros(n_axes),
        u_applied,
        np.zeros(n_axes),
    )
    force = loop.ForceState(
        forces.fops, forces.fpar, forces.fstate, machine.workpiece_body_id, dt, np.array([data.time]), np.zeros(3)
    )
    draw_noise = encoder.noise_source()
    if use_compiled:
        addresses = mujoco_c.struct_addresses(model, data)
        prog = loop.ProgramArrays(program.ops, program.io, program.par, program.state, program.scratch, program.bus)

    def run_chunk(k0, k1, chunk):
        if use_compiled:
            return loop.compiled_ticks(
                k0, k1, mujoco_c.MJ_STEP, *addresses, mj, sensor, drive_args, prog, force, chunk, rec, acc
            )
        return loop.python_ticks(k0, k1, model, data, program, mj, sensor, drive_args, force, chunk, rec, acc)

    is_program = hasattr(reference, "lines_at")
    # what a program's reference says of the recorded ticks, gathered chunk by chunk as the run
    # goes (a long program's reference is planned as it is asked for and keeps no past)
    recorded: dict[str, list] = {"extra": [], "lines": [], "engagement": [], "feeds": []}

    def record_program(k0: int, k1: int) -> None:
        if record_every == 0:
            return
        ticks = np.arange(-(-k0 // record_every) * record_every, k1, record_every)
        t_rec = ticks * control_period_s
        if hasattr(reference, "extra_series"):
            recorded["extra"].append(reference.extra_series(t_rec))
        if is_program:
            recorded["lines"].append(reference.lines_at(t_rec))
            recorded["engagement"].append(reference.engagement_at(t_rec))
            recorded["feeds"].append(reference.feeds_at(t_rec))

    def gathered(name: str, rows: int, empty: np.ndarray) -> np.ndarray:
        return np.concatenate(recorded[name])[:rows] if recorded[name] else empty

    def result(ticks: int, accumulated: int) -> RunResult:
        """The run's first ``ticks`` ticks (metrics over the ``accumulated`` ones)."""
        rows = 0 if record_every == 0 else -(-ticks // record_every)
        qpos, qvel, act, ref = rec.qpos[:rows], rec.qvel[:rows], rec.actuator_force[:rows], rec.ref[:rows]
        meas, u, ua, force_N = rec.meas[:rows], rec.u[:rows], rec.ua[:rows], rec.workpiece_force[:rows]
        error, force_max = acc.error, acc.force_max
        t_rec = np.arange(rows) * record_every * control_period_s
        extra = (
            {name: np.concatenate([part[name] for part in recorded["extra"]])[:rows] for name in recorded["extra"][0]}
            if recorded["extra"]
            else {}
        )
        return RunResult(
            machine,
            t_rec,
            ref,
            meas,
            u,
            ua,
            qpos,
            qvel,
            act,
            force_N,
            control_period_s,
            error[:, 0].copy(),
            np.sqrt(error[:, 1] / max(accumulated, 1)),
            force_max.copy(),
            info={
                "loop": "compiled" if use_compiled else "python",
                "record_every": int(record_every),
                "completed_ticks": ticks,
                **({"program_cycle_time_s": reference.duration_s} if is_program else {}),
                **({"machining_warnings_total": warnings_total} if warnings_total else {}),
            },
            reference_extra=extra,
            program_lines=gathered("lines", rows, np.zeros(0, int)),
            program_texts=reference.texts if is_program else {},
            engagement=gathered("engagement", rows, np.zeros((0, 2))),
            program_feed_mm_per_min=gathered("feeds", rows, np.zeros(0)),
            part_outlines=outlines,
            machining_warnings=warnings,
        )

    outlines = reference.outlines if hasattr(reference, "outlines") else {}
    warnings = getattr(reference, "warnings", [])
    warnings_total = getattr(reference, "warnings_total", 0)
    show = progress if progress is not None else n * substeps > PROGRESS_STEPS
    size = max(1, min(CHUNK_TICKS, CHUNK_STEPS // substeps, n))
    warnings0 = [data.warning[w].number for w in FATAL_WARNINGS]
    messages: list[str] = []
    done = 0
    try:
        with (
            _mujoco_warnings_into(messages),
            _progress_bar(reference, n, machine.name, show) as bar,
        ):
            for k0 in range(0, n, size):
                k1 = min(n, k0 + size)
                t = np.arange(k0, k1 + preview) * control_period_s
                u_dist = np.zeros((k1 - k0, n_axes))
                with np.errstate(all="ignore"):  # overflow shows as non-finite values, reported below
                    for dist in input_disturbances:
                        u_dist += dist.input_V(t[: k1 - k0])
                    ref = np.ascontiguousarray(reference.sample(t))
                bad = ~np.isfinite(ref).all(axis=(1, 2))
                if bad.any():  # the ticks before this chunk are kept
                    exc = SimulationDiverged(
                        (k0 + int(np.argmax(bad))) * control_period_s,
                        "the reference (position, velocity or acceleration) is not finite here: it overflows",
                    )
                    exc.result = result(k0, k0)
                    raise exc
                record_program(k0, k1)
                chunk = loop.Chunk(ref, draw_noise(k1 - k0), u_dist)
                status, k, s = run_chunk(k0, k1, chunk)
                try:
                    _check(status, k, s, data, sensor.q_idx, u_applied, control_period_s, dt, warnings0, messages)
                except SimulationDiverged as exc:  # keep what was computed: the ticks before k
                    exc.result = result(k, k + (status in (loop.BAD_CONTROL, loop.BAD_QACC)))
                    raise
                done = k1
                if hasattr(reference, "line_at"):  # a program: progress in its lines, all of them at the end
                    line = reference.n_lines if k1 == n else reference.line_at(k1 * control_period_s)
                    bar.update(max(line - bar.n, 0))
                else:
                    bar.update(k1 - k0)
    except KeyboardInterrupt:
        raise RunInterrupted(done * control_period_s, result(done, done)) from None
    return result(n, n)


def _progress_bar(reference, n_ticks: int, name: str, show: bool) -> tqdm:
    """The run's progress bar: in ticks, or in program lines for a G-code reference."""
    if hasattr(reference, "line_at"):
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


def _check(status, k, s, data, q_idx, ua, period, dt, warnings0, messages) -> None:
    """Raise :class:`SimulationDiverged` for a failed chunk or a new fatal MuJoCo warning
    (with MuJoCo's own words where it gave any)."""
    t = _failure_time(status, k, s, period, dt)
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


def _failure_time(status, k, s, period, dt) -> float:
    """Simulated time (s) of a failure: the start of tick k, or the end of its physics step s."""
    return k * period + (s + 1) * dt if status == loop.BAD_QACC else k * period
