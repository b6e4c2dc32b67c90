"""Any python-control LTI controller as a discrete-time control block.

The continuous controller C(s) (SISO or MIMO, proper) acts on the position error
e = r - y; it is converted to state space and discretized at the control period with
Tustin (bilinear, default) or zero-order hold (``control.c2d``).  Optional velocity and
acceleration feedforward adds ``kv * r' + ka * r''`` per axis.
"""

from __future__ import annotations

import control
import numpy as np
from numba import njit


@njit(cache=True)
def _affine(P, Q, x, e, out):  # pragma: no cover - compiled
    """out = P x + Q e (in place)."""
    for i in range(P.shape[0]):
        acc = 0.0
        for j in range(P.shape[1]):
            acc += P[i, j] * x[j]
        for j in range(Q.shape[1]):
            acc += Q[i, j] * e[j]
        out[i] = acc


@njit(cache=True)
def ss_step(A, B, C, D, x, e, u, xn):  # pragma: no cover - compiled
    """u = C x + D e; x <- A x + B e (in place; ``xn`` is scratch of x's size)."""
    _affine(C, D, x, e, u)
    _affine(A, B, x, e, xn)
    x[:] = xn


class DiscreteLTI:
    """Error-feedback controller from a python-control LTI model.

    Parameters
    ----------
    sys : control.LTI
        Continuous-time controller C(s) from position error (m) to control input (V), or a
        discrete-time one whose ``dt`` equals ``dt``.  Square: as many inputs as outputs.
    dt : float
        Control period (s).
    method : {"tustin", "zoh"}
        Discretization of a continuous ``sys``.
    velocity_ff, acceleration_ff : float or array_like
        Feedforward gains, V/(m/s) and V/(m/s^2), per axis.
    name : str
        Label for tables and recordings.
    """

    def __init__(self, sys, dt: float, method: str = "tustin", velocity_ff=0.0,
                 acceleration_ff=0.0, name: str = ""):
        if dt <= 0:
            raise ValueError(f"dt = {dt!r}: control period must be > 0")
        if method not in ("tustin", "zoh"):
            raise ValueError(f"method = {method!r}: use 'tustin' or 'zoh'")
        if sys.ninputs != sys.noutputs:
            raise ValueError(f"controller has {sys.ninputs} inputs and {sys.noutputs} outputs: "
                             "an error-feedback block must be square")
        ss = control.ss(sys)
        if ss.isctime():
            ss = control.c2d(ss, dt, method=method)
        elif not np.isclose(ss.dt, dt):
            raise ValueError(f"discrete controller dt = {ss.dt} differs from control period {dt}")
        self.sys = sys
        self.dt = float(dt)
        self.method = method
        self.name = name
        self.n_axes = sys.ninputs
        self.A = np.ascontiguousarray(ss.A, dtype=float)
        self.B = np.ascontiguousarray(ss.B, dtype=float)
        self.C = np.ascontiguousarray(ss.C, dtype=float)
        self.D = np.ascontiguousarray(ss.D, dtype=float)
        self.kv = np.broadcast_to(np.asarray(velocity_ff, dtype=float), (self.n_axes,)).copy()
        self.ka = np.broadcast_to(np.asarray(acceleration_ff, dtype=float), (self.n_axes,)).copy()
        self._feedforward = bool(self.kv.any() or self.ka.any())
        self.x = np.zeros(self.A.shape[0])
        self._xn = np.zeros(self.A.shape[0])
        self._e = np.zeros(self.n_axes)
        self._u = np.zeros(self.n_axes)

    def reset(self) -> None:
        """Zero the controller state."""
        self.x[:] = 0.0

    def step(self, ref: np.ndarray, meas: np.ndarray) -> np.ndarray:
        """One control tick; see :mod:`controllers.base` for shapes and units."""
        np.subtract(ref[:, 0], meas[:, 0], out=self._e)
        ss_step(self.A, self.B, self.C, self.D, self.x, self._e, self._u, self._xn)
        if self._feedforward:
            return self._u + self.kv * ref[:, 1] + self.ka * ref[:, 2]
        return self._u.copy()

    def discrete_state_space(self) -> tuple[np.ndarray, ...]:
        """``(A, B, C, D, kv, ka, x)``: the discrete matrices, feedforward gains and state.

        Blocks that offer this are linear; the runner then runs the whole loop compiled
        (:mod:`twin.compiled_loop`) with the same arithmetic as :meth:`step`.
        """
        return self.A, self.B, self.C, self.D, self.kv, self.ka, self.x

    def __repr__(self) -> str:
        return f"DiscreteLTI({self.name or 'C(s)'}, dt={self.dt}, {self.method}, order={len(self.x)})"
