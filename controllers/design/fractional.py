"""Fractional-order operators: the Oustaloup approximation of ``s^alpha`` and the exact
step response of a fractional loop by numerical inverse Laplace transform.

Written here, small: no maintained Python package offers them in this environment (the
``fotf`` toolbox port pins an old numba, python-control has no fractional operators).

- Oustaloup, Levron, Mathieu, Nanot, *Frequency-band complex noninteger differentiator:
  characterization and synthesis*, IEEE TCS-I 47(1), 2000: in the band ``[wb, wh]``,
  ``s^alpha ~ wh^alpha prod_{k=-N}^{N} (s + w'_k)/(s + w_k)`` with
  ``w'_k = wb (wh/wb)^((k + N + (1 - alpha)/2)/(2N + 1))`` and
  ``w_k = wb (wh/wb)^((k + N + (1 + alpha)/2)/(2N + 1))``.
- Abate and Valko, *Multi-precision Laplace transform inversion*, IJNME 60, 2004: the fixed
  Talbot contour, accurate to about 1e-12 in double precision with ``M = 24`` on smooth
  responses (tested against a known transform).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Oustaloup:
    """``gain prod_k (s + zeros_k)/(s + poles_k)``, the approximation of ``s^alpha``
    (see :func:`oustaloup`); zeros and poles in rad/s (as positive numbers)."""

    gain: float
    zeros: np.ndarray
    poles: np.ndarray

    def response(self, w_rad_s) -> np.ndarray:
        """Frequency response at ``w_rad_s`` (complex)."""
        s = 1j * np.asarray(w_rad_s, float)[..., None]
        return self.gain * np.prod((s + self.zeros) / (s + self.poles), axis=-1)

    def state_space(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """``(A, B, C, D)`` as a series of first-order sections ``1 + (z - p)/(s + p)`` (a
        companion form of the product would be ill-conditioned over a wide band)."""
        n = len(self.poles)
        A, B = np.diag(-self.poles), np.zeros((n, 1))
        C, D = np.zeros((1, n)), np.ones((1, 1))
        B[0, 0] = 1.0
        for k in range(n):
            # section k's input is section k-1's output: y_{k-1} = (z - p)_{k-1} x_{k-1} + y_{k-2}
            if k + 1 < n:
                A[k + 1, : k + 1] = C[0, : k + 1] + np.eye(1, k + 1, k)[0] * (self.zeros[k] - self.poles[k])
                B[k + 1, 0] = 1.0
            C[0, k] += self.zeros[k] - self.poles[k]
        return A, B, self.gain * C, self.gain * D


def oustaloup(alpha: float, wb: float, wh: float, order: int) -> Oustaloup:
    """Oustaloup's rational approximation of ``s^alpha`` over ``[wb, wh]`` rad/s.

    Parameters
    ----------
    alpha : float
        Fractional order, ``-1 < alpha < 1`` (negative: a fractional integrator).
    wb, wh : float
        Band edges (rad/s), ``0 < wb < wh``.
    order : int
        N: ``2 N + 1`` zeros and poles.
    """
    if not (-1.0 < alpha < 1.0 and 0 < wb < wh and int(order) == order >= 1):
        raise ValueError(f"oustaloup: needs -1 < alpha < 1, 0 < wb < wh and a whole order >= 1, got "
                         f"alpha = {alpha}, band = [{wb}, {wh}], order = {order}")
    k = np.arange(-order, order + 1)
    span = wh / wb
    zeros = wb * span ** ((k + order + 0.5 * (1 - alpha)) / (2 * order + 1))
    poles = wb * span ** ((k + order + 0.5 * (1 + alpha)) / (2 * order + 1))
    return Oustaloup(float(wh ** alpha), zeros, poles)


def fractional_pi(kp: float, ki: float, lam: float, wb: float, wh: float,
                  order: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``kp + ki s^-lam`` (eq. 14's form) as ``(A, B, C, D)``, ``s^-lam`` by :func:`oustaloup`."""
    A, B, C, D = oustaloup(-lam, wb, wh, order).state_space()
    return A, B, ki * C, ki * D + kp


def talbot_inverse(F, t_s, M: int = 24) -> np.ndarray:
    """``f(t)`` from its Laplace transform ``F(s)`` (vectorized over complex ``s``), fixed Talbot.

    Parameters
    ----------
    F : callable
        ``F(s)`` for an ndarray of complex ``s``; analytic right of its singularities.
    t_s : array_like
        Times (s), > 0.
    M : int
        Contour points.
    """
    t = np.atleast_1d(np.asarray(t_s, float))
    if not (t > 0).all():
        raise ValueError("talbot_inverse: times must be > 0")
    th = np.arange(1, M) * np.pi / M
    cot = 1.0 / np.tan(th)
    sigma = th + (th * cot - 1.0) * cot
    r = 2.0 * M / (5.0 * t)                      # (n,)
    s = r[:, None] * th[None, :] * (cot[None, :] + 1j)    # (n, M-1)
    first = 0.5 * np.exp(r * t) * F(r.astype(complex)).real
    rest = (np.exp(t[:, None] * s) * F(s) * (1.0 + 1j * sigma[None, :])).real.sum(axis=1)
    return r / M * (first + rest)


def step_response(closed_loop, t_s) -> np.ndarray:
    """Step response of a closed loop given as ``T(s)`` (callable on complex arrays), by
    :func:`talbot_inverse` of ``T(s)/s``."""
    return talbot_inverse(lambda s: closed_loop(s) / s, t_s)
