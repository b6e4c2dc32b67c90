"""The tick loop, twice: compiled with numba (:func:`compiled_ticks`) and in Python
(:func:`python_ticks`, the reference implementation, which also runs Python blocks).

Both run ticks ``k0 <= k < k1`` of one closed-loop run and call the same kernels for every
piece of arithmetic: :func:`start_tick` (metrics, state recording and
:func:`twin.sim.drive.sense`: encoder, velocity, signals onto the bus),
:func:`controllers.kernels.run_program` (the blocks), :func:`twin.sim.drive.drive_command`
(disturbance, saturation, delay line), :func:`twin.sim.drive.actuator_input`,
:func:`twin.process.cutting.workpiece_forces` (into ``xfrc_applied`` before each physics step)
and :func:`end_tick`.  They differ only in how they step MuJoCo (ctypes ``mj_step`` on the
struct addresses, with the simulation time accumulated as MuJoCo accumulates it, against
``mujoco.mj_step`` and ``data.time``) and in running Python blocks.  The state they carry
between chunks lives in the argument arrays.

Argument groups (tuples, so that both loops take the same ones):

- ``mj``: ``qpos, qvel, qacc, ctrl, actuator_force, xfrc_applied`` views of ``MjData``;
- ``sensor``: ``q_idx, v_idx, gains, resolution, tachometer, period_s, runaway_m, meas_prev,
  preview``;
- ``drive``: ``u_idx, limit, substeps, delay_steps, delay_line, u, ua`` (``ua`` holds the
  previous tick's drive input until :func:`twin.sim.drive.drive_command` overwrites it);
- ``prog``: ``ops, io, par, state, scratch, bus`` (:class:`controllers.blocks.Program`);
- ``force``: ``fops, fpar, fstate, workpiece_body, timestep_s, clock, f_step, f_sum``;
- ``chunk``: ``ref`` (rows k0 .. k1 + preview), ``noise``, ``u_dist`` (rows k0 .. k1);
- ``rec``: ``every, qpos, qvel, actuator_force, ref, meas, u, ua, workpiece_force``: tick k is
  recorded in row ``k // every`` when ``k % every == 0``; ``every = 0`` records nothing;
- ``acc``: ``error`` (n_axes, 2): max |e| and sum of e^2 of ``ref - table position`` over every
  tick; ``force_max`` (n_axes,): max |tick-mean workpiece force| along each axis.

Each returns ``(status, k, s)``: :data:`OK`, or the first failure, at physics step ``s`` of
tick ``k``: :data:`RUNAWAY` (table not finite or beyond ``runaway_m`` at the start of tick k),
:data:`BAD_CONTROL` (a drive input not finite or beyond ``MAX_VALUE``), :data:`BAD_QACC`
(MuJoCo's instability test failed in step s).
"""

from __future__ import annotations

import mujoco
from numba import njit

from controllers.kernels import run_program
from twin.process.cutting import workpiece_forces
from twin.sim.drive import STRIDE, accelerations_ok, actuator_input, drive_command, sense, table_in_bounds

OK, RUNAWAY, BAD_CONTROL, BAD_QACC = 0, 1, 2, 3


@njit(cache=True)
def start_tick(k, row, mj, sensor, drive, chunk, rec, acc, bus):  # pragma: no cover - compiled
    """Tick k's error metrics, state recording and loop signals; False if the table ran away."""
    qpos, qvel, act = mj[0], mj[1], mj[4]
    q_idx, v_idx, gains, resolution, tachometer, period_s, runaway_m, meas_prev, preview = sensor
    ref, noise = chunk[0], chunk[1]
    every, error = rec[0], acc[0]
    if not table_in_bounds(qpos, q_idx, runaway_m):
        return False
    for a in range(q_idx.shape[0]):
        e = ref[row, a, 0] - qpos[q_idx[a]]
        error[a, 0] = max(error[a, 0], abs(e))
        error[a, 1] += e * e
    if every > 0 and k % every == 0:
        r = k // every
        rec[1][r, :] = qpos
        rec[2][r, :] = qvel
        rec[3][r, :] = act
        rec[4][r, :, :] = ref[row]
    sense(k, row, qpos, qvel, q_idx, v_idx, gains, resolution, noise, ref, tachometer, period_s,
          meas_prev, drive[6], preview, bus)
    return True


@njit(cache=True)
def end_tick(k, drive, force, rec, acc, bus):  # pragma: no cover - compiled
    """Record tick k's measurement, inputs and mean workpiece force; update the force maxima."""
    substeps, u, ua = drive[2], drive[5], drive[6]
    f_sum = force[7]
    every, force_max = rec[0], acc[1]
    for a in range(u.shape[0]):
        force_max[a] = max(force_max[a], abs(f_sum[a] / substeps))
    if every > 0 and k % every == 0:
        r = k // every
        for a in range(u.shape[0]):
            rec[5][r, a] = bus[1 + STRIDE * a + 3]
        rec[6][r, :] = u
        rec[7][r, :] = ua
        for i in range(3):
            rec[8][r, i] = f_sum[i] / substeps


@njit(cache=True)
def compiled_ticks(k0, k1, mj_step, m_addr, d_addr, mj, sensor, drive, prog, force, chunk, rec,
                   acc):  # pragma: no cover - compiled
    """Ticks ``k0 <= k < k1``, compiled; ``mj_step`` is :data:`twin.sim.mujoco_c.MJ_STEP`
    (an argument, so numba can cache the loop), ``m_addr``/``d_addr`` the struct addresses."""
    qpos, qvel, qacc, ctrl, xfrc = mj[0], mj[1], mj[2], mj[3], mj[5]
    u_idx, limit, substeps, delay_steps, delay_line, u, ua = drive
    ops, io, par, state, scratch, bus = prog
    fops, fpar, fstate, wp, dt, clock, f_step, f_sum = force
    u_dist = chunk[2]
    for k in range(k0, k1):
        row = k - k0
        if not start_tick(k, row, mj, sensor, drive, chunk, rec, acc, bus):
            return RUNAWAY, k, 0
        run_program(ops, io, par, state, scratch, bus)
        if not drive_command(k, row, bus, u_idx, u_dist, limit, u, ua, delay_line):
            return BAD_CONTROL, k, 0
        f_sum[:] = 0.0
        for s in range(substeps):
            actuator_input(k, s, substeps, delay_steps, delay_line, ctrl)
            if fops.shape[0]:
                workpiece_forces(fops, fpar, fstate, qpos, qvel, clock[0], f_step)
                xfrc[wp, 0:3] = f_step
                f_sum += f_step
            mj_step(m_addr, d_addr)
            clock[0] += dt
            if not accelerations_ok(qacc):
                return BAD_QACC, k, s
        end_tick(k, drive, force, rec, acc, bus)
    return OK, k1, 0


def python_ticks(k0, k1, model, data, program, mj, sensor, drive, force, chunk, rec, acc):
    """Ticks ``k0 <= k < k1`` in Python: ``program.run()`` (Python blocks too) and
    ``mujoco.mj_step``; the simulation time is ``data.time``."""
    qpos, qvel, qacc, ctrl, xfrc = mj[0], mj[1], mj[2], mj[3], mj[5]
    u_idx, limit, substeps, delay_steps, delay_line, u, ua = drive
    fops, fpar, fstate, wp, dt, clock, f_step, f_sum = force
    u_dist, bus = chunk[2], program.bus
    for k in range(k0, k1):
        row = k - k0
        if not start_tick(k, row, mj, sensor, drive, chunk, rec, acc, bus):
            return RUNAWAY, k, 0
        program.run()
        if not drive_command(k, row, bus, u_idx, u_dist, limit, u, ua, delay_line):
            return BAD_CONTROL, k, 0
        f_sum[:] = 0.0
        for s in range(substeps):
            actuator_input(k, s, substeps, delay_steps, delay_line, ctrl)
            if fops.shape[0]:
                workpiece_forces(fops, fpar, fstate, qpos, qvel, data.time, f_step)
                xfrc[wp, 0:3] = f_step
                f_sum += f_step
            mujoco.mj_step(model, data)
            if not accelerations_ok(qacc):
                return BAD_QACC, k, s
        end_tick(k, drive, force, rec, acc, bus)
    return OK, k1, 0
