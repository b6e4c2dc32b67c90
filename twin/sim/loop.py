"""The tick loop, twice: compiled with numba (:func:`compiled_ticks`) and in Python
(:func:`python_ticks`, the reference implementation, which also runs Python blocks).

Both run ticks ``k0 <= k < k1`` of one closed-loop run and call the same kernels for every
piece of arithmetic: :func:`start_tick` (metrics, state recording),
:func:`twin.sim.drive.sense` (encoder, velocity, signals onto the bus),
:func:`controllers.kernels.run_blocks` (the blocks, every kind, relay included),
:func:`twin.sim.drive.drive_command`
(disturbance, saturation, delay line), :func:`twin.sim.drive.actuator_input`,
:func:`twin.machining.cutting.workpiece_forces` (into ``xfrc_applied`` before each physics step)
and :func:`end_tick` (recording, force maxima).  They differ only in how they step MuJoCo (ctypes ``mj_step`` on the
struct addresses, with the simulation time accumulated as MuJoCo accumulates it, against
``mujoco.mj_step`` and ``data.time``) and in running Python blocks.  The state they carry
between chunks lives in the argument arrays.

Both take the same argument groups, each a :class:`typing.NamedTuple` (numba compiles them as
tuples, so naming costs nothing): :class:`MjViews`, :class:`Sensor`, :class:`DriveState`,
:class:`ProgramArrays`, :class:`ForceState`, :class:`Chunk`, :class:`Recording` and
:class:`Accumulators`.

Each returns ``(status, k, s)``: :data:`OK`, or the first failure, at physics step ``s`` of
tick ``k``: :data:`RUNAWAY` (table not finite or beyond ``runaway_m`` at the start of tick k),
:data:`BAD_CONTROL` (a drive input not finite or beyond ``MAX_VALUE``), :data:`BAD_QACC`
(MuJoCo's instability test failed in step s).
"""

from __future__ import annotations

from typing import NamedTuple

import mujoco
import numpy as np
from numba import njit

from controllers.kernels import run_blocks
from twin.machining.cutting import workpiece_forces
from twin.numba_cache import configure as configure_numba_cache
from twin.sim.drive import (
    POS,
    accelerations_ok,
    actuator_input,
    axis_signal_index,
    drive_command,
    sense,
    table_in_bounds,
)

configure_numba_cache()  # before the first @njit(cache=True): see twin.numba_cache

OK, RUNAWAY, BAD_CONTROL, BAD_QACC = 0, 1, 2, 3


class MjViews(NamedTuple):
    """Views of ``MjData`` the loop reads and writes."""

    qpos: np.ndarray
    qvel: np.ndarray
    qacc: np.ndarray
    ctrl: np.ndarray
    actuator_force: np.ndarray
    xfrc_applied: np.ndarray


class Sensor(NamedTuple):
    """The encoders (:func:`twin.sim.drive.sense`): the tables' qpos indices per axis (runaway
    check, recorded error); per axis the position encoder's qpos index, gain (to table travel)
    and resolution (m); the velocity encoder's qpos and dof indices, gain, resolution and noise
    share (1: the position encoder itself, 0: the motor's own); tachometer or backward
    difference, the control period (s), the runaway limit (m), the velocity encoder's last
    reading per axis (updated in place) and the preview ticks on the bus."""

    q_idx: np.ndarray
    encoder_q_idx: np.ndarray
    gains: np.ndarray
    resolution: np.ndarray
    vel_q_idx: np.ndarray
    vel_v_idx: np.ndarray
    vel_gains: np.ndarray
    vel_resolution: np.ndarray
    vel_noise: np.ndarray
    tachometer: bool
    period_s: float
    runaway_m: float
    meas_prev: np.ndarray
    preview: int


class DriveState(NamedTuple):
    """The drive: bus indices of ``u.<axis>``, the axes' actuator ids in ``ctrl``, the
    saturation (V), physics steps per tick, the delay (physics steps), the delay line, and per
    axis the tick's command, drive input and saturated command (``u_prev`` until
    :func:`twin.sim.drive.drive_command` overwrites it)."""

    u_idx: np.ndarray
    act_idx: np.ndarray
    limit: float
    substeps: int
    delay_steps: int
    delay_line: np.ndarray
    u: np.ndarray
    ua: np.ndarray
    u_sat: np.ndarray


class ProgramArrays(NamedTuple):
    """The compiled controllers (:class:`controllers.blocks.BlockProgram`)."""

    ops: np.ndarray
    io: np.ndarray
    par: np.ndarray
    state: np.ndarray
    scratch: np.ndarray
    bus: np.ndarray


class ForceState(NamedTuple):
    """The force models on the workpiece: their ops, parameters and states, the workpiece body,
    the physics step (s), the simulation clock (s, in place), the tick's summed force (N), the
    workpiece's XY velocity per axis velocity (2, n_axes: the reference's velocity to the planned
    feed), the planned feed velocity (2, m/s, in place) and the tick's vibration probe
    (:data:`twin.machining.cutting.PROBE`)."""

    fops: np.ndarray
    fpar: np.ndarray
    fstate: np.ndarray
    workpiece_body: int
    timestep_s: float
    clock: np.ndarray
    f_sum: np.ndarray
    feed_jacobian: np.ndarray
    feed_velocity: np.ndarray
    probe: np.ndarray


class Chunk(NamedTuple):
    """One chunk of ticks k0 .. k1: the reference (rows k0 .. k1 + preview), encoder noise and
    drive-input disturbance (rows k0 .. k1)."""

    ref: np.ndarray
    noise: np.ndarray
    u_dist: np.ndarray


class Recording(NamedTuple):
    """What is recorded: tick k in row ``k // every`` when ``k % every == 0`` (``every = 0``
    records nothing); the vibration probe is summed over every tick into its row."""

    every: int
    qpos: np.ndarray
    qvel: np.ndarray
    actuator_force: np.ndarray
    ref: np.ndarray
    meas: np.ndarray
    u: np.ndarray
    ua: np.ndarray
    workpiece_force: np.ndarray
    probe: np.ndarray


class Accumulators(NamedTuple):
    """Over every tick: per axis max |e| and the sum of e^2 of ``ref - table position``, and
    the largest |tick-mean workpiece force|."""

    error: np.ndarray
    force_max: np.ndarray


@njit(cache=True, inline="always")
def start_tick(
    k, row, qpos, qvel, act, q_idx, runaway_m, ref, error, every, rec_qpos, rec_qvel, rec_act, rec_ref
):  # pragma: no cover - compiled
    """Tick k's error metrics (into ``error``, an :class:`Accumulators`' field) and state
    recording (into a :class:`Recording`'s fields); False if the table ran away."""
    if not table_in_bounds(qpos, q_idx, runaway_m):
        return False
    for a in range(q_idx.shape[0]):
        e = ref[row, a, 0] - qpos[q_idx[a]]
        error[a, 0] = max(error[a, 0], abs(e))
        error[a, 1] += e * e
    if every > 0 and k % every == 0:
        r = k // every
        for i in range(qpos.shape[0]):
            rec_qpos[r, i] = qpos[i]
        for i in range(qvel.shape[0]):
            rec_qvel[r, i] = qvel[i]
        for i in range(act.shape[0]):
            rec_act[r, i] = act[i]
        for a in range(q_idx.shape[0]):
            for i in range(3):
                rec_ref[r, a, i] = ref[row, a, i]
    return True


@njit(cache=True, inline="always")
def start_forces(row, ref, feed_jacobian, feed_velocity, f_sum, probe):  # pragma: no cover - compiled
    """Zero the tick's force sum and vibration probe; the planned feed velocity from the
    reference's velocity at the tick (a :class:`ForceState`'s fields)."""
    f_sum[:] = 0.0
    probe[:] = 0.0
    for r in range(2):
        v = 0.0
        for a in range(feed_jacobian.shape[1]):
            v += feed_jacobian[r, a] * ref[row, a, 1]
        feed_velocity[r] = v


@njit(cache=True, inline="always")
def end_tick(
    k, substeps, u, ua, f_sum, probe, force_max, bus, every, rec_meas, rec_u, rec_ua, rec_force, rec_probe
):  # pragma: no cover - compiled
    """Record tick k's measurement, inputs and mean workpiece force (``f_sum`` over the tick's
    physics steps), add its vibration probe to its row; update the force maxima."""
    if every > 0:
        r = k // every
        for i in range(probe.shape[0]):
            rec_probe[r, i] += probe[i]
    for a in range(u.shape[0]):
        force_max[a] = max(force_max[a], abs(f_sum[a] / substeps))
    if every > 0 and k % every == 0:
        r = k // every
        for a in range(u.shape[0]):
            rec_meas[r, a] = bus[axis_signal_index(a, POS)]
            rec_u[r, a] = u[a]
            rec_ua[r, a] = ua[a]
        for i in range(3):
            rec_force[r, i] = f_sum[i] / substeps


@njit(cache=True)
def compiled_ticks(
    k0, k1, mj_step, m_addr, d_addr, mj, sensor, drive, prog, force, chunk, rec, acc
):  # pragma: no cover - compiled
    """Ticks ``k0 <= k < k1``, compiled; ``mj_step`` is :data:`twin.sim.mujoco_c.MJ_STEP`
    (an argument, so numba can cache the loop), ``m_addr``/``d_addr`` the struct addresses.
    The groups are unpacked once, before the first tick: numba counts a reference up and down
    (atomically) each time an array is taken out of a tuple, which on every tick cost about 4 %
    of the loop's speed (issue 49)."""
    qpos, qvel, qacc, ctrl, act, xfrc = mj.qpos, mj.qvel, mj.qacc, mj.ctrl, mj.actuator_force, mj.xfrc_applied
    q_idx, encoder_q_idx, gains, resolution = sensor.q_idx, sensor.encoder_q_idx, sensor.gains, sensor.resolution
    vel_q_idx, vel_v_idx, vel_gains = sensor.vel_q_idx, sensor.vel_v_idx, sensor.vel_gains
    vel_resolution, vel_noise, meas_prev = sensor.vel_resolution, sensor.vel_noise, sensor.meas_prev
    tachometer, period_s, runaway_m, preview = sensor.tachometer, sensor.period_s, sensor.runaway_m, sensor.preview
    u_idx, act_idx, limit, substeps = drive.u_idx, drive.act_idx, drive.limit, drive.substeps
    delay_steps, delay_line, u, ua, u_sat = drive.delay_steps, drive.delay_line, drive.u, drive.ua, drive.u_sat
    fops, fpar, fstate, f_sum, clock = force.fops, force.fpar, force.fstate, force.f_sum, force.clock
    wp, dt, jac, feed, probe = (
        force.workpiece_body,
        force.timestep_s,
        force.feed_jacobian,
        force.feed_velocity,
        force.probe,
    )
    ref, noise, u_dist = chunk.ref, chunk.noise, chunk.u_dist
    every, rec_qpos, rec_qvel, rec_act, rec_ref = rec.every, rec.qpos, rec.qvel, rec.actuator_force, rec.ref
    rec_meas, rec_u, rec_ua, rec_force, rec_probe = rec.meas, rec.u, rec.ua, rec.workpiece_force, rec.probe
    error, force_max = acc.error, acc.force_max
    ops, io, par, state, scratch, bus = prog.ops, prog.io, prog.par, prog.state, prog.scratch, prog.bus
    n_blocks = ops.shape[0]
    for k in range(k0, k1):
        row = k - k0
        if not start_tick(
            k, row, qpos, qvel, act, q_idx, runaway_m, ref, error, every, rec_qpos, rec_qvel, rec_act, rec_ref
        ):
            return RUNAWAY, k, 0
        sense(
            k, row, qpos, qvel, encoder_q_idx, gains, resolution, vel_q_idx, vel_v_idx, vel_gains, vel_resolution,
            vel_noise, tachometer, period_s, meas_prev, preview, noise, ref, u_sat, bus,
        )  # fmt: skip
        run_blocks(0, n_blocks, ops, io, par, state, scratch, bus)
        if not drive_command(k, row, bus, u_idx, u_dist, limit, u, ua, u_sat, delay_line):
            return BAD_CONTROL, k, 0
        start_forces(row, ref, jac, feed, f_sum, probe)
        for s in range(substeps):
            actuator_input(k, s, substeps, delay_steps, delay_line, act_idx, ctrl)
            if fops.shape[0]:
                workpiece_forces(fops, fpar, fstate, qpos, qvel, feed, clock[0], xfrc, wp, f_sum, probe)
            mj_step(m_addr, d_addr)
            clock[0] += dt
            if not accelerations_ok(qacc):
                return BAD_QACC, k, s
        end_tick(k, substeps, u, ua, f_sum, probe, force_max, bus, every, rec_meas, rec_u, rec_ua, rec_force, rec_probe)
    return OK, k1, 0


def python_ticks(k0, k1, *, model, data, program, mj, sensor, drive, force, chunk, rec, acc):
    """Ticks ``k0 <= k < k1`` in Python: ``program.run()`` (Python blocks too) and
    ``mujoco.mj_step``; the simulation time is ``data.time``."""
    qpos, qvel, qacc, ctrl, xfrc = mj.qpos, mj.qvel, mj.qacc, mj.ctrl, mj.xfrc_applied
    f_sum, probe, feed = force.f_sum, force.probe, force.feed_velocity
    ref, bus = chunk.ref, program.bus
    for k in range(k0, k1):
        row = k - k0
        if not start_tick(
            k, row, qpos, qvel, mj.actuator_force, sensor.q_idx, sensor.runaway_m, ref, acc.error, rec.every,
            rec.qpos, rec.qvel, rec.actuator_force, rec.ref,
        ):  # fmt: skip
            return RUNAWAY, k, 0
        sense(
            k, row, qpos, qvel, sensor.encoder_q_idx, sensor.gains, sensor.resolution, sensor.vel_q_idx,
            sensor.vel_v_idx, sensor.vel_gains, sensor.vel_resolution, sensor.vel_noise, sensor.tachometer,
            sensor.period_s, sensor.meas_prev, sensor.preview, chunk.noise, ref, drive.u_sat, bus,
        )  # fmt: skip
        program.run()
        if not drive_command(
            k, row, bus, drive.u_idx, chunk.u_dist, drive.limit, drive.u, drive.ua, drive.u_sat, drive.delay_line
        ):
            return BAD_CONTROL, k, 0
        start_forces(row, ref, force.feed_jacobian, feed, f_sum, probe)
        for s in range(drive.substeps):
            actuator_input(k, s, drive.substeps, drive.delay_steps, drive.delay_line, drive.act_idx, ctrl)
            if force.fops.shape[0]:
                workpiece_forces(
                    force.fops, force.fpar, force.fstate, qpos, qvel, feed, data.time, xfrc, force.workpiece_body,
                    f_sum, probe,
                )  # fmt: skip
            mujoco.mj_step(model, data)
            if not accelerations_ok(qacc):
                return BAD_QACC, k, s
        end_tick(
            k, drive.substeps, drive.u, drive.ua, f_sum, probe, acc.force_max, bus, rec.every, rec.meas, rec.u,
            rec.ua, rec.workpiece_force, rec.probe,
        )  # fmt: skip
    return OK, k1, 0
