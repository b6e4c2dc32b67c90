"""The closed loop compiled with numba, for linear controllers.

When every control block is linear (it offers ``discrete_state_space()``, as
:class:`controllers.lti.DiscreteLTI` does) and no disturbance needs Python before each
physics step, the runner hands the whole tick loop to :func:`tick_loop`: encoder, controller
(the same :func:`controllers.lti.ss_step` kernel the blocks use), drive and ``mj_step``,
which is called through ctypes from MuJoCo's own shared library on the ``MjModel`` and
``MjData`` of the Python bindings.  The arrays it reads and writes (``qpos``, ``ctrl``, ...)
are the bindings' views of that ``MjData``, so no struct layout is assumed except the
position of the BADQACC warning counter, which :func:`warning_counter` locates and verifies.
The arithmetic is the Python loop's, step for step; ``tests/test_runner.py`` checks that
both loops give identical series.
"""

from __future__ import annotations

import ctypes
from pathlib import Path

import mujoco
import numpy as np
from numba import njit
from scipy.linalg import block_diag

from controllers.lti import ss_step


def _load_mj_step():
    """``mj_step(const mjModel*, mjData*)`` from the libmujoco the bindings use."""
    libs = sorted(Path(mujoco.__file__).parent.glob("libmujoco.so*")) + \
        sorted(Path(mujoco.__file__).parent.glob("libmujoco*.dylib"))
    if not libs:
        return None
    fn = ctypes.CDLL(str(libs[0])).mj_step
    fn.argtypes = [ctypes.c_void_p, ctypes.c_void_p]
    fn.restype = None
    return fn


MJ_STEP = _load_mj_step()

#: Status codes returned by :func:`tick_loop`.
OK, RUNAWAY, BAD_QACC = 0, 1, 2


def available() -> bool:
    """Whether MuJoCo's shared library was found (the compiled loop can run)."""
    return MJ_STEP is not None


def warning_counter(data: mujoco.MjData) -> np.ndarray:
    """An int32 view, shape (1,), of ``data.warning[mjWARN_BADQACC].number``.

    The counter's offset in ``mjData`` is found by writing a sentinel through the bindings
    and reading the struct's bytes forward from its start; a hit counts only if a second
    sentinel written through the bindings then appears at the same address.

    Raises
    ------
    RuntimeError
        If the counter cannot be located unambiguously.
    """
    stat = data.warning[mujoco.mjtWarning.mjWARN_BADQACC]
    saved = stat.number
    first, second = 0x5A17C0DE, 0x2B0BCAFE
    chunk = 256  # read forward in small chunks so no read runs far past the counter
    offset = None
    try:
        for start in range(0, 1 << 24, chunk):
            stat.number = first
            raw = np.frombuffer(ctypes.string_at(data._address + start, chunk), dtype=np.int32)
            for hit in np.flatnonzero(raw == first):
                address = data._address + start + 4 * int(hit)
                stat.number = second
                if ctypes.c_int32.from_address(address).value == second:
                    offset = address - data._address
                    break
                stat.number = first
            if offset is not None:
                break
    finally:
        stat.number = saved
    if offset is None:
        raise RuntimeError("BADQACC counter not found in mjData")
    return np.ctypeslib.as_array((ctypes.c_int32 * 1).from_address(data._address + offset))


def combine(blocks) -> tuple[np.ndarray, ...]:
    """One block-diagonal state space ``(A, B, C, D, kv, ka)`` from linear blocks in axis order."""
    parts = [b.discrete_state_space() for b in blocks]
    A, B, C, D = (block_diag(*[p[i] for p in parts]) for i in range(4))
    kv, ka = (np.concatenate([p[i] for p in parts]) for i in (4, 5))
    return (np.ascontiguousarray(A), np.ascontiguousarray(B), np.ascontiguousarray(C),
            np.ascontiguousarray(D), kv, ka)


@njit(cache=True)
def tick_loop(k0, k1, mj_step, m_addr, d_addr, qpos, qvel, ctrl, actuator_force, xfrc, warn,  # pragma: no cover
              q_idx, wp, runaway_m, gains, resolution, noise, ref, u_dist, limit,
              substeps, delay_steps, A, B, C, D, kv, ka, x, xn,
              qpos_rec, qvel_rec, act_rec, wp_rec, meas_rec, u_rec, ua_rec):
    """Ticks ``k0 <= k < k1`` of the closed loop; returns ``(status, k)``.

    ``mj_step`` is :data:`MJ_STEP`, passed as an argument (not read as a global) so that
    numba can cache the compiled loop between processes.

    ``status`` is :data:`OK`, or :data:`RUNAWAY` (table beyond ``runaway_m`` or not finite
    at the start of tick k) or :data:`BAD_QACC` (MuJoCo's warning during tick k).  The
    ``*_rec`` arrays are filled in place, as in :func:`twin.runner.simulate`.
    """
    n_axes = q_idx.shape[0]
    pos = np.empty(n_axes)
    e = np.empty(n_axes)
    u = np.empty(n_axes)
    warn0 = warn[0]
    for k in range(k0, k1):
        for a in range(n_axes):
            pos[a] = qpos[q_idx[a]]
            if not abs(pos[a]) < runaway_m:
                return RUNAWAY, k
        qpos_rec[k, :] = qpos
        qvel_rec[k, :] = qvel
        act_rec[k, :] = actuator_force
        wp_rec[k, :] = xfrc[wp, :3]
        for a in range(n_axes):
            y = gains[a] * pos[a]
            if resolution[a] > 0:
                y = np.rint(y / resolution[a]) * resolution[a]
            meas_rec[k, a] = y + noise[k, a]
            e[a] = ref[k, a, 0] - meas_rec[k, a]
        ss_step(A, B, C, D, x, e, u, xn)
        for a in range(n_axes):
            u_rec[k, a] = u[a] + kv[a] * ref[k, a, 1] + ka[a] * ref[k, a, 2]
            ua_rec[k, a] = min(max(u_rec[k, a] + u_dist[k, a], -limit), limit)
        for s in range(substeps):
            j = k * substeps + s - delay_steps
            for a in range(n_axes):
                ctrl[a] = ua_rec[j // substeps, a] if j >= 0 else 0.0
            mj_step(m_addr, d_addr)
        if warn[0] != warn0:
            return BAD_QACC, k
    return OK, k1
