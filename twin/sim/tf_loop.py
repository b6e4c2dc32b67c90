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

from controllers.blocks import Program, preview_ticks_needed, standard_signals
from controllers.kernels import run_blocks
from controllers.lti import SisoTf, discretize, tf_to_ss
from twin.numba_cache import configure as configure_numba_cache

configure_numba_cache()  # before the first @njit(cache=True): see twin.numba_cache


@njit(cache=True)
def _ticks(
    Ad, Bd, Cd, delay, ops, io, par, state, scratch, bus, sig, preview_at, ref, u_dist, plant_dist, limit, dt, pos, u
):  # pragma: no cover - compiled
    n, n_axes = pos.shape
    n_preview = preview_at.shape[1]
    x = np.zeros(Ad.shape[0])
    line = np.zeros((delay + 1, n_axes))
    y = np.zeros(n_axes)
    y_prev = np.zeros(n_axes)
    u_prev = np.zeros(n_axes)
    applied = np.zeros(n_axes)
    for k in range(n):
        bus[sig[0, 0]] = k
        for a in range(n_axes):
            y[a] = 0.0
            for i in range(x.shape[0]):
                y[a] += Cd[a, i] * x[i]
            pos[k, a] = y[a]
            bus[sig[a, 1]] = ref[k, a, 0]
            bus[sig[a, 2]] = ref[k, a, 1]
            bus[sig[a, 3]] = ref[k, a, 2]
            bus[sig[a, 4]] = y[a]
            bus[sig[a, 5]] = (y[a] - y_prev[a]) / dt if k > 0 else 0.0
            bus[sig[a, 6]] = ref[k, a, 0] - y[a]
            bus[sig[a, 7]] = u_prev[a]
            for i in range(n_preview):
                bus[preview_at[a, i]] = ref[k + 1 + i, a, 0]
        run_blocks(0, ops.shape[0], ops, io, par, state, scratch, bus)
        for a in range(n_axes):
            command = bus[sig[a, 8]]
            u[k, a] = command
            u_prev[a] = min(max(command, -limit), limit)
            line[k % (delay + 1), a] = min(max(command + u_dist[k, a], -limit), limit)
            applied[a] = (line[(k - delay) % (delay + 1), a] if k >= delay else 0.0) + plant_dist[k, a]
        x[:] = Ad @ x + Bd @ applied
        y_prev[:] = y


def tf_loop(
    plant,
    controller,
    ref: np.ndarray,
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
    Ad, Bd, Cd = (np.ascontiguousarray(m) for m in discretize(A, B, C, D, dt, "zoh")[:3])
    if Bd.shape[1] != len(axes) or Cd.shape[0] != len(axes):
        raise ValueError(f"the plant has {Bd.shape[1]} inputs and {Cd.shape[0]} outputs for axes {list(axes)}")
    preview = preview_ticks_needed(controller.inputs)
    program = Program([controller], standard_signals(axes, preview))
    if not program.compiled:
        raise ValueError(
            f"controller {controller.name!r} has Python blocks: the transfer-function loop runs compiled blocks only"
        )
    n = len(ref) - preview
    if n < 1:
        raise ValueError(f"the reference has {len(ref)} rows: the controller previews {preview} ticks")
    names = ("ref", "ref_vel", "ref_acc", "pos", "vel", "error", "u_prev", "u")
    sig = np.array([[program.index("tick")] + [program.index(f"{s}.{a}") for s in names] for a in axes], np.int64)
    preview_at = np.array(
        [[program.index(f"preview.{a}.{i}") for i in range(1, preview + 1)] for a in axes], np.int64
    ).reshape(len(axes), preview)

    def per_axis(v):
        return np.zeros((n, len(axes))) if v is None else np.asarray(v, float).reshape(n, len(axes))

    pos, u = np.zeros((n, len(axes))), np.zeros((n, len(axes)))
    _ticks(
        Ad,
        Bd,
        Cd,
        round(delay_s / dt),
        program.ops,
        program.io,
        program.par,
        program.state,
        program.scratch,
        program.bus,
        sig,
        preview_at,
        ref,
        per_axis(u_dist_V),
        per_axis(plant_dist_V),
        float(saturation_V),
        dt,
        pos,
        u,
    )
    return (pos[:, 0], u[:, 0]) if single else (pos, u)
