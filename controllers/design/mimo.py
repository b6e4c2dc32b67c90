"""Frequency responses and loop-at-a-time margins of MIMO state-space loops (numpy, batched)."""

from __future__ import annotations

import numpy as np


def frequency_response(sys, omega) -> np.ndarray:
    """``C (j w I - A)^-1 B + D`` at each angular frequency (rad/s), shape (len(omega), p, m).

    ``sys`` is any object with ``A, B, C, D`` (a python-control StateSpace).
    """
    A, B, C, D = (np.asarray(m, float) for m in (sys.A, sys.B, sys.C, sys.D))
    w = np.atleast_1d(np.asarray(omega, float))
    n = A.shape[0]
    if n == 0:
        return np.broadcast_to(D.astype(complex), (len(w), *D.shape)).copy()
    pencil = 1j * w[:, None, None] * np.eye(n) - A
    return C @ np.linalg.solve(pencil, np.broadcast_to(B.astype(complex), (len(w), *B.shape))) + D


def loop_at_input(loop_response: np.ndarray, channel: int) -> np.ndarray:
    """Loop gain seen when a 2x2 negative-feedback loop ``L = K G`` (at the plant input) is
    broken at ``channel`` with the other channel closed: ``L_ii - L_ij L_ji / (1 + L_jj)``.

    Parameters
    ----------
    loop_response : ndarray, shape (n, 2, 2)
        ``K(jw) G(jw)`` on a frequency grid.
    channel : int
        0 or 1.
    """
    i, j = channel, 1 - channel
    L = loop_response
    return L[:, i, i] - L[:, i, j] * L[:, j, i] / (1.0 + L[:, j, j])
