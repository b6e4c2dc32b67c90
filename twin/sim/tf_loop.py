"""The same closed loop on the transfer functions: one axis, the plant's zero-order-hold
discretization at the control period instead of MuJoCo.

It is the reference a reproduction compares the twin with.  The timing is the twin's (see
:mod:`twin.sim.drive`): at tick k the controller reads the position ``y[k]``, its command goes
through the drive (input disturbance, saturation) into a delay line, and the plant holds the
command of tick ``k - N`` over ``[t_k, t_k+1)``, ``N = round(delay / dt)``; a force on the
table enters as an equivalent voltage at the plant input, after the delay.  The controller is
any compiled :class:`~controllers.blocks.core.Controller` on the loop's bus (signals ``ref``,
``ref_vel``, ``ref_acc``, ``pos``, ``vel`` as the encoder's backward difference, ``error``,
``u_prev``, ``tick``), run by the same kernel as the twin's loop.

numba caches this loop with :func:`controllers.kernels.run_blocks` inlined; the cache folder is
keyed on every kernel's source (:mod:`twin.numba_cache`), so an edited kernel is recompiled in.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from controllers.blocks import BlockProgram, preview_ticks_needed, standard_signals
from controllers.kernels import run_blocks
from controllers.lti import SisoTf, discretize, tf_to_ss
from twin.numba_cache import configure as configure_numba_cache
from twin.sim.drive import actuator_input, drive_command, sense
from twin.sim.loop import Chunk, DriveState, ProgramArrays, Sensor

configure_numba_cache()  # before the first @njit(cache=True): see twin.numba_cache


@njit(cache=True)
def _ticks(Ad, Bd, Cd, prog, sensor, drive, chunk, plant_dist, pos, u):  # pragma: no cover - compiled
    """The loop on the sampled plant ``x <- Ad x + Bd v, y = Cd x``, tick by tick, with the twin's
    own kernels and groups (:mod:`twin.sim.loop`): :func:`twin.sim.drive.sense` (``sensor`` an
    ideal encoder of the plant's outputs), :func:`controllers.kernels.run_blocks` (``prog``),
    :func:`twin.sim.drive.drive_command` (disturbance, saturation, delay line) and
    :func:`twin.sim.drive.actuator_input` (one plant step a tick); ``plant_dist`` is added at the
    plant input after the delay."""
    n, n_axes = pos.shape
    ops, io, par, state, scratch, bus = prog.ops, prog.io, prog.par, prog.state, prog.scratch, prog.bus
    enc, gains, resolution = sensor.encoder_q_idx, sensor.gains, sensor.resolution
    vel_enc, vel_gains, vel_resolution, vel_noise = (
        sensor.vel_q_idx,
        sensor.vel_gains,
        sensor.vel_resolution,
        sensor.vel_noise,
    )
    u_idx, limit, u_drive, ua, u_sat, delay_line = (
        drive.u_idx,
        drive.limit,
        drive.u,
        drive.ua,
        drive.u_sat,
        drive.delay_line,
    )
    ref, noise, u_dist = chunk.ref, chunk.noise, chunk.u_dist
    x = np.zeros(Ad.shape[0])
    y = np.zeros(n_axes)
    applied = np.zeros(n_axes)
    for k in range(n):
        for a in range(n_axes):
            y[a] = 0.0
            for i in range(x.shape[0]):
                y[a] += Cd[a, i] * x[i]
            pos[k, a] = y[a]
        sense(
            k, k, y, y, enc, gains, resolution, vel_enc, sensor.vel_v_idx, vel_gains, vel_resolution, vel_noise,
            sensor.tachometer, sensor.period_s, sensor.meas_prev, sensor.preview, noise, ref, u_sat, bus,
        )  # fmt: skip
        run_blocks(0, ops.shape[0], ops, io, par, state, scratch, bus)
        drive_command(k, k, bus, u_idx, u_dist, limit, u_drive, ua, u_sat, delay_line)
        actuator_input(k, 0, drive.substeps, drive.delay_steps, delay_line, drive.act_idx, applied)
        for a in range(n_axes):
            u[k, a] = u_drive[a]
            applied[a] += plant_dist[k, a]
        x[:] = Ad @ x + Bd @ applied


def tf_loop(
    plant,
    controller,
    ref: np.ndarray,
    *,
    dt: float,
    delay_s: float = 0.0,
    u_dist_V: np.ndarray | None = None,
    plant_dist_V: np.ndarray | None = None,
    saturation_V: float = np.inf,
    axes=("x",),
) -> tuple[np.ndarray, np.ndarray]:
    """Simulate the loop; returns the position (m) and the controller output (V) per tick.

    Parameters
    ----------
    plant : SisoTf or tuple (A, B, C, D)
        Input (V) to position (m), without the delay: a SISO transfer function for one axis, or
        a continuous state space with one input and one output per axis of ``axes``.
    controller : Controller
        Writes ``u.<axis>``; reads any of the loop's signals, reference preview included.
    ref : ndarray, shape (n, 3) or (n + P, n_axes, 3)
        Reference position (m), velocity (m/s) and acceleration (m/s^2) at each tick (one axis
        without preview, or per axis with the P rows of preview the controller reads).
    dt : float
        Control period (s), also the plant's sampling period.
    delay_s : float
        Transport delay (s), rounded to whole ticks.
    u_dist_V, plant_dist_V : ndarray, shape (n,) or (n, n_axes), optional
        Input disturbance added to the command before the drive's saturation and delay, and
        an equivalent voltage added at the plant input after the delay (a force on the table).
    saturation_V : float
        Drive saturation (V).
    axes : tuple of str
        Axis names, in the plant's input order.

    Returns
    -------
    pos, u : ndarray, shape (n,) for one axis given ``ref`` of shape (n, 3), else (n, n_axes)
    """
    axes = tuple(axes)
    single = np.ndim(ref) == 2
    ref = np.ascontiguousarray(np.asarray(ref, float).reshape(len(ref), len(axes), 3) if single else ref, float)
    A, B, C, D = tf_to_ss(plant) if isinstance(plant, SisoTf) else (np.atleast_2d(np.asarray(m, float)) for m in plant)
    Ad, Bd, Cd = (np.ascontiguousarray(m) for m in discretize(A, B, C, D, dt=dt, method="zoh")[:3])
    if Bd.shape[1] != len(axes) or Cd.shape[0] != len(axes):
        raise ValueError(f"the plant has {Bd.shape[1]} inputs and {Cd.shape[0]} outputs for axes {list(axes)}")
    preview = preview_ticks_needed(controller.inputs)
    program = BlockProgram([controller], standard_signals(axes, preview))
    if not program.compiled:
        raise ValueError(
            f"controller {controller.name!r} has Python blocks: the transfer-function loop runs compiled blocks only"
        )
    n = len(ref) - preview
    if n < 1:
        raise ValueError(f"the reference has {len(ref)} rows: the controller previews {preview} ticks")

    def per_axis(v):
        return np.zeros((n, len(axes))) if v is None else np.asarray(v, float).reshape(n, len(axes))

    n_axes = len(axes)
    axis, ones, zeros = np.arange(n_axes), np.ones(n_axes), np.zeros(n_axes)
    ideal = Sensor(  # unit gain, no quantization, no noise, the backward difference for velocity
        q_idx=axis,
        encoder_q_idx=axis,
        gains=ones,
        resolution=zeros,
        vel_q_idx=axis,
        vel_v_idx=axis,
        vel_gains=ones,
        vel_resolution=zeros,
        vel_noise=ones,
        tachometer=False,
        period_s=float(dt),
        runaway_m=np.inf,
        meas_prev=np.zeros(n_axes),
        preview=preview,
    )
    delay = round(delay_s / dt)
    drive = DriveState(
        u_idx=np.array([program.index(f"u.{a}") for a in axes], np.int64),
        act_idx=axis,
        limit=float(saturation_V),
        substeps=1,
        delay_steps=delay,
        delay_line=np.zeros((delay + 2, n_axes)),
        u=np.zeros(n_axes),
        ua=np.zeros(n_axes),
        u_sat=np.zeros(n_axes),
    )
    prog = ProgramArrays(
        ops=program.ops, io=program.io, par=program.par, state=program.state, scratch=program.scratch, bus=program.bus
    )
    chunk = Chunk(ref=ref, noise=np.zeros((n, n_axes)), u_dist=per_axis(u_dist_V))
    pos, u = np.zeros((n, n_axes)), np.zeros((n, n_axes))
    _ticks(Ad, Bd, Cd, prog, ideal, drive, chunk, per_axis(plant_dist_V), pos, u)
    return (pos[:, 0], u[:, 0]) if single else (pos, u)
