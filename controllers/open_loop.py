"""Open-loop block: plays a precomputed input sequence, ignoring the measurement."""

from __future__ import annotations

import numpy as np


class OpenLoop:
    """Control block returning ``u[k]`` at tick k (V), zero after the sequence ends.

    Parameters
    ----------
    u : ndarray, shape (n_ticks, n_axes)
        Input sequence (V).
    dt : float
        Control period (s).
    """

    def __init__(self, u: np.ndarray, dt: float):
        self.u = np.atleast_2d(np.asarray(u, float))
        self.dt = float(dt)
        self.n_axes = self.u.shape[1]
        self.name = "open_loop"
        self._k = 0

    def reset(self) -> None:
        self._k = 0

    def step(self, ref: np.ndarray, meas: np.ndarray) -> np.ndarray:
        k = self._k
        self._k += 1
        return self.u[k] if k < len(self.u) else np.zeros(self.n_axes)
