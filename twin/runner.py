"""Closed-loop runner: controller blocks + drive + MuJoCo machine + encoders, at a fixed rate.

One control tick (period ``control_period_s``, a whole multiple of the physics timestep):

    measure table positions (encoder) -> each block's step(ref, meas) -> u (V)
    -> drive (input disturbance, saturation, transport delay) -> MjData.ctrl
    -> physics steps (``mj_step``; per-step hooks write cutting forces into xfrc_applied)

The state is recorded at the start of every tick, so ``u[k]`` is the input held over
``[t[k], t[k+1])`` (zero-order hold); so is the workpiece force, recorded as the mean of
the forces applied over that interval.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Protocol, Sequence

import mujoco
import numpy as np
from tqdm import tqdm

from controllers.base import ControlBlock
from twin import compiled_loop
from twin.drive import Drive, Encoder, substeps_per_tick
from twin.errors import SimulationDiverged, TwinInputError
from twin.machines import BuiltMachine

#: Table travel (m) beyond which a run counts as runaway.
RUNAWAY_M = 10.0
#: Simulated physics steps above which a progress bar is shown (about 5 s of wall time).
PROGRESS_STEPS = 1_000_000


class Disturbance(Protocol):
    """A disturbance may add to the drive input and/or act before every physics step.

    ``input_V(t)`` returns ndarray (len(t), n_axes) added to the control input (V);
    ``step_hook(machine)`` returns a fresh ``hook(model, data)`` for one run, called before
    each ``mj_step`` to add its force to the workpiece's ``data.xfrc_applied`` (zeroed first).
    Either may be absent.
    """


@dataclass
class RunResult:
    """Time series of one closed-loop run, sampled at the start of every control tick.

    Attributes
    ----------
    machine : BuiltMachine
    t_s : ndarray, shape (n,)
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
    info: dict = field(default_factory=dict)

    @property
    def axis_names(self) -> list[str]:
        return [a.name for a in self.machine.axes]

    def table_position_m(self) -> np.ndarray:
        """Table positions (m), shape (n, n_axes)."""
        return self.qpos[:, self.machine.table_qpos_indices()]

    def error_m(self) -> np.ndarray:
        """Tracking error reference - table position (m), shape (n, n_axes)."""
        return self.ref[:, :, 0] - self.table_position_m()


def assign_controllers(blocks: Sequence[ControlBlock], n_axes: int) -> list[tuple[ControlBlock, np.ndarray]]:
    """Map blocks to axes in order: a SISO block takes one axis, a MIMO block several.

    Raises
    ------
    TwinInputError
        If the blocks do not cover the machine's axes exactly.
    """
    out, start = [], 0
    for b in blocks:
        out.append((b, np.arange(start, start + b.n_axes)))
        start += b.n_axes
    if start != n_axes:
        raise TwinInputError("controller", [getattr(b, "name", repr(b)) for b in blocks],
                             f"blocks serve {start} axes, the machine has {n_axes}")
    return out


def simulate(machine: BuiltMachine, controllers: Sequence[ControlBlock], reference,
             duration_s: float, control_period_s: float, *, drive: Drive | None = None,
             encoder: Encoder | None = None, disturbances: Sequence[Disturbance] = (),
             progress: bool | None = None, compiled: bool | None = None) -> RunResult:
    """Run the closed loop for ``duration_s`` and return its time series.

    Parameters
    ----------
    machine : BuiltMachine
    controllers : sequence of ControlBlock
        Blocks in axis order (see :func:`assign_controllers`); each block's ``dt`` must equal
        ``control_period_s``.
    reference : object with ``n_axes`` and ``sample(t)``
        See :mod:`twin.references`.
    duration_s, control_period_s : float
        Run length and control period (s).
    drive, encoder : optional
        Default: machine delay, no saturation; ideal encoder with the machine's sensor gains.
    disturbances : sequence
        See :class:`Disturbance`.
    progress : bool or None
        Progress bar; None shows one for runs over ``PROGRESS_STEPS`` physics steps.
    compiled : bool or None
        Run the loop compiled (:mod:`twin.compiled_loop`; linear blocks only, no per-step
        hooks) or in Python.  None picks the compiled loop whenever it can run.

    Raises
    ------
    SimulationDiverged
        Non-finite state, a MuJoCo instability warning or a table beyond ``RUNAWAY_M``.
    TwinInputError
        Inconsistent periods, references or controllers, or ``compiled=True`` where the
        compiled loop cannot run.
    """
    model = machine.model
    n_axes = len(machine.axes)
    dt = model.opt.timestep
    substeps = substeps_per_tick(control_period_s, dt)
    if not (duration_s > 0 and math.isfinite(duration_s)):
        raise TwinInputError("duration_s", duration_s, "must be > 0")
    if reference.n_axes != n_axes:
        raise TwinInputError("reference", type(reference).__name__,
                             f"has {reference.n_axes} axes, machine '{machine.name}' has {n_axes}")
    blocks = assign_controllers(controllers, n_axes)
    for b, _ in blocks:
        if abs(b.dt - control_period_s) > 1e-12:
            raise TwinInputError("controller.dt", b.dt, f"differs from control_period_s = {control_period_s}")
        b.reset()
    drive = drive or Drive(n_axes, substeps, dt, machine.delay_s)
    encoder = encoder or Encoder(np.zeros(n_axes), np.zeros(n_axes), np.array(machine.sensor_gains))

    n = int(round(duration_s / control_period_s))
    t = np.arange(n) * control_period_s
    ref = reference.sample(t)
    u_dist = np.zeros((n, n_axes))
    step_hooks = []
    for dist in disturbances:
        if hasattr(dist, "input_V"):
            u_dist += dist.input_V(t)
        if hasattr(dist, "step_hook"):
            step_hooks.append(dist.step_hook(machine))
    can_compile = (compiled_loop.available() and not step_hooks
                   and all(hasattr(b, "discrete_state_space") for b, _ in blocks))
    if compiled and not can_compile:
        raise TwinInputError("compiled", True, "needs linear controller blocks, no per-step "
                             "disturbance hooks and MuJoCo's shared library")
    use_compiled = can_compile if compiled is None else compiled

    data = mujoco.MjData(model)
    rec = {"qpos": np.empty((n, model.nq)), "qvel": np.empty((n, model.nv)),
           "act": np.empty((n, model.nu)), "wp": np.empty((n, 3)), "meas": np.empty((n, n_axes)),
           "u": np.empty((n, n_axes)), "ua": np.empty((n, n_axes))}
    loop = _CompiledLoop if use_compiled else _PythonLoop
    run = loop(machine, data, blocks, drive, encoder, encoder.noise_m(n), ref, u_dist, step_hooks, rec)
    show = progress if progress is not None else n * substeps > PROGRESS_STEPS
    chunk = max(1, n // 200)
    with tqdm(total=n, desc=f"{machine.name}", unit="tick", disable=not show, mininterval=0.5,
              leave=False) as bar:
        for k0 in range(0, n, chunk):
            k1 = min(n, k0 + chunk)
            status, k = run.ticks(k0, k1)
            if status == compiled_loop.RUNAWAY:
                pos = data.qpos[run.q_idx]
                raise SimulationDiverged(t[k], f"table position {pos.tolist()} m beyond {RUNAWAY_M} m "
                                         "or not finite")
            if status == compiled_loop.BAD_QACC:
                raise SimulationDiverged(t[k] + control_period_s,
                                         "MuJoCo reported unstable accelerations (BADQACC)")
            bar.update(k1 - k0)
    run.finish()
    return RunResult(machine, t, ref, rec["meas"], rec["u"], rec["ua"], rec["qpos"], rec["qvel"],
                     rec["act"], rec["wp"], control_period_s,
                     info={"loop": "compiled" if use_compiled else "python"})


class _PythonLoop:
    """The tick loop in Python: any control blocks, per-step disturbance hooks."""

    def __init__(self, machine, data, blocks, drive, encoder, noise, ref, u_dist, step_hooks, rec):
        self.model, self.data, self.blocks, self.drive, self.encoder = machine.model, data, blocks, drive, encoder
        self.noise, self.ref, self.u_dist, self.hooks, self.rec = noise, ref, u_dist, step_hooks, rec
        self.q_idx = machine.table_qpos_indices()
        self.v_idx = np.array([machine.joint_dof_index(a.table_joint) for a in machine.axes])
        self.wp = machine.workpiece_body_id
        self.bad_qacc = data.warning[mujoco.mjtWarning.mjWARN_BADQACC]

    def ticks(self, k0: int, k1: int) -> tuple[int, int]:
        """Run ticks ``k0 <= k < k1``; returns ``(status, k)`` as the compiled loop does."""
        model, data, rec = self.model, self.data, self.rec
        qpos, qvel, ctrl = data.qpos, data.qvel, data.ctrl
        n_axes = len(self.q_idx)
        meas = np.zeros((n_axes, 2))
        u = np.zeros(n_axes)
        warn0 = self.bad_qacc.number
        for k in range(k0, k1):
            pos = qpos[self.q_idx]
            if not (abs(pos).max() < RUNAWAY_M):  # also catches NaN
                return compiled_loop.RUNAWAY, k
            rec["qpos"][k] = qpos
            rec["qvel"][k] = qvel
            rec["act"][k] = data.actuator_force
            meas[:, 0] = self.encoder.measure(pos, self.noise[k])
            meas[:, 1] = qvel[self.v_idx]
            rec["meas"][k] = meas[:, 0]
            for block, idx in self.blocks:
                u[idx] = block.step(self.ref[k, idx], meas[idx])
            rec["u"][k] = u
            rec["ua"][k] = self.drive.saturate(u + self.u_dist[k])
            force_sum = 0.0
            for nsteps, src in self.drive.segments(k):
                ctrl[:] = rec["ua"][src] if src >= 0 else 0.0
                if self.hooks:
                    for _ in range(nsteps):
                        data.xfrc_applied[self.wp, :3] = 0.0  # hooks add their forces
                        for hook in self.hooks:
                            hook(model, data)
                        force_sum = force_sum + data.xfrc_applied[self.wp, :3]
                        mujoco.mj_step(model, data)
                else:
                    mujoco.mj_step(model, data, nstep=nsteps)
            # without hooks nothing writes xfrc_applied: the force held over the whole tick
            rec["wp"][k] = force_sum / self.drive.substeps if self.hooks else data.xfrc_applied[self.wp, :3]
            if self.bad_qacc.number != warn0:
                return compiled_loop.BAD_QACC, k
        return compiled_loop.OK, k1

    def finish(self) -> None:
        """Nothing to hand back: the blocks kept their own state."""


class _CompiledLoop:
    """The tick loop of :mod:`twin.compiled_loop` for linear blocks."""

    def __init__(self, machine, data, blocks, drive, encoder, noise, ref, u_dist, step_hooks, rec):
        self.model, self.data, self.blocks, self.rec = machine.model, data, blocks, rec
        self.q_idx = machine.table_qpos_indices()
        self.A, self.B, self.C, self.D, self.kv, self.ka = compiled_loop.combine([b for b, _ in blocks])
        self.x = np.zeros(self.A.shape[0])
        self.args = (data.qpos, data.qvel, data.ctrl, data.actuator_force, data.xfrc_applied,
                     compiled_loop.warning_counter(data), self.q_idx, machine.workpiece_body_id,
                     RUNAWAY_M, encoder.gains, encoder.resolution_m,
                     noise, np.ascontiguousarray(ref), u_dist, drive.limit_V, drive.substeps,
                     drive.delay_steps, self.A, self.B, self.C, self.D, self.kv, self.ka, self.x,
                     np.zeros_like(self.x), rec["qpos"], rec["qvel"], rec["act"], rec["wp"],
                     rec["meas"], rec["u"], rec["ua"])

    def ticks(self, k0: int, k1: int) -> tuple[int, int]:
        """Run ticks ``k0 <= k < k1``; returns ``(status, k)``."""
        return compiled_loop.tick_loop(k0, k1, compiled_loop.MJ_STEP, self.model._address, self.data._address, *self.args)

    def finish(self) -> None:
        """Hand the final controller state back to the blocks, as the Python loop leaves it."""
        start = 0
        for block, _ in self.blocks:
            x = block.discrete_state_space()[-1]
            x[:] = self.x[start:start + len(x)]
            start += len(x)
