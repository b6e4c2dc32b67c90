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
"""

from __future__ import annotations

import numpy as np
from numba import njit

from controllers.blocks import Program, standard_signals
from controllers.kernels import run_blocks
from controllers.lti import SisoTf, discretize, tf_to_ss


@njit(cache=True)
def _ticks(Ad, Bd, Cd, delay, ops, io, par, state, scratch, bus, sig, ref, u_dist, plant_dist, limit, dt,
           pos, u):  # pragma: no cover - compiled
    n = ref.shape[0]
    x = np.zeros(Ad.shape[0])
    line = np.zeros(delay + 1)
    y_prev = 0.0
    u_prev = 0.0
    for k in range(n):
        y = 0.0
        for i in range(x.shape[0]):
            y += Cd[0, i] * x[i]
        pos[k] = y
        bus[sig[0]] = k
        bus[sig[1]] = ref[k, 0]
        bus[sig[2]] = ref[k, 1]
        bus[sig[3]] = ref[k, 2]
        bus[sig[4]] = y
        bus[sig[5]] = (y - y_prev) / dt if k > 0 else 0.0
        bus[sig[6]] = ref[k, 0] - y
        bus[sig[7]] = u_prev
        run_blocks(0, ops.shape[0], ops, io, par, state, scratch, bus)
        command = bus[sig[8]]
        u[k] = command
        u_prev = min(max(command, -limit), limit)
        line[k % (delay + 1)] = min(max(command + u_dist[k], -limit), limit)
        applied = line[(k - delay) % (delay + 1)] if k >= delay else 0.0
        x[:] = Ad @ x + Bd[:, 0] * (applied + plant_dist[k])
        y_prev = y


def tf_loop(plant: SisoTf, controller, ref: np.ndarray, dt: float, delay_s: float = 0.0,
            u_dist_V: np.ndarray | None = None, plant_dist_V: np.ndarray | None = None,
            saturation_V: float = np.inf) -> tuple[np.ndarray, np.ndarray]:
    """Simulate the loop; returns the position (m) and the controller output (V) per tick.

    Parameters
    ----------
    plant : SisoTf
        Input (V) to position (m), without the delay.
    controller : Controller
        Writes ``u.x``; reads any of the loop's signals of axis ``x``.
    ref : ndarray, shape (n, 3)
        Reference position (m), velocity (m/s) and acceleration (m/s^2) at each tick.
    dt : float
        Control period (s), also the plant's sampling period.
    delay_s : float
        Transport delay (s), rounded to whole ticks.
    u_dist_V, plant_dist_V : ndarray, shape (n,), optional
        Input disturbance added to the command before the drive's saturation and delay, and
        an equivalent voltage added at the plant input after the delay (a force on the table).
    saturation_V : float
        Drive saturation (V).
    """
    n = len(ref)
    Ad, Bd, Cd = (np.ascontiguousarray(m) for m in discretize(*tf_to_ss(plant), dt, "zoh")[:3])
    program = Program([controller], standard_signals("x"))
    if not program.compiled:
        raise ValueError(f"controller {controller.name!r} has Python blocks: the transfer-function loop runs "
                         "compiled blocks only")
    names = ["tick", "ref.x", "ref_vel.x", "ref_acc.x", "pos.x", "vel.x", "error.x", "u_prev.x", "u.x"]
    sig = np.array([program.index(s) for s in names], np.int64)
    pos, u = np.zeros(n), np.zeros(n)
    zeros = np.zeros(n)
    _ticks(Ad, Bd, Cd, int(round(delay_s / dt)), program.ops, program.io, program.par, program.state,
           program.scratch, program.bus, sig, np.ascontiguousarray(ref, float),
           zeros if u_dist_V is None else np.asarray(u_dist_V, float),
           zeros if plant_dist_V is None else np.asarray(plant_dist_V, float), float(saturation_V), dt, pos, u)
    return pos, u
