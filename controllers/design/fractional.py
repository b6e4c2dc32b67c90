"""Fractional-order operators: the Oustaloup approximation of ``s^alpha`` and the exact
step response of a fractional loop by numerical inverse Laplace transform.

Written here, small: no maintained Python package offers them in this environment (the
``fotf`` toolbox port pins an old numba, python-control has no fractional operators).

- Oustaloup, Levron, Mathieu, Nanot, *Frequency-band complex noninteger differentiator:
  characterization and synthesis*, IEEE TCS-I 47(1), 2000: in the band ``[wb, wh]``,
  ``s^alpha ~ wh^alpha prod_{k=-N}^{N} (s + w'_k)/(s + w_k)`` with
  ``w'_k = wb (wh/wb)^((k + N + (1 - alpha)/2)/(2N + 1))`` and
  ``w_k = wb (wh/wb)^((k + N + (1 + alpha)/2)/(2N + 1))``.
- Durbin, *Numerical inversion of Laplace transforms: an efficient improvement to Dubner and
  Abate's method*, The Computer Journal 17(4), 1974: the Fourier-series inversion of the
  Bromwich integral.  (A fixed Talbot contour was tried first: in double precision it cannot
  enclose the lightly damped poles of eq. (14)'s loop and returned a response without its
  oscillation after 0.3 s.)
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
        raise ValueError(
            f"oustaloup: needs -1 < alpha < 1, 0 < wb < wh and a whole order >= 1, got "
            f"alpha = {alpha}, band = [{wb}, {wh}], order = {order}"
        )
    k = np.arange(-order, order + 1)
    span = wh / wb
    zeros = wb * span ** ((k + order + 0.5 * (1 - alpha)) / (2 * order + 1))
    poles = wb * span ** ((k + order + 0.5 * (1 + alpha)) / (2 * order + 1))
    return Oustaloup(float(wh**alpha), zeros, poles)


def fractional_pi(
    kp: float, ki: float, lam: float, *, wb: float, wh: float, order: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``kp + ki s^-lam`` (eq. 14's form) as ``(A, B, C, D)``, ``s^-lam`` by :func:`oustaloup`."""
    A, B, C, D = oustaloup(-lam, wb, wh, order).state_space()
    return A, B, ki * C, ki * D + kp


def bromwich_inverse(F, t_max_s: float, n: int = 2**17, digits: float = 10.0) -> tuple[np.ndarray, np.ndarray]:
    """``f(t)`` on ``[0, t_max_s]`` from its Laplace transform ``F(s)``: the Bromwich integral on
    ``Re s = c`` by the trapezoidal rule, all times at once by FFT (Durbin's Fourier-series
    method).

    With period ``2 T``, ``T = t_max_s``: ``f(t) ~ e^(c t)/T [F(c)/2 + sum_k Re(F(c + i k pi/T)
    e^(i k pi t/T))]``; ``c = digits ln(10)/(2 T)`` puts the aliasing error near
    ``10^-digits``.  Unlike contour methods (Talbot) it needs no knowledge of where the
    singularities are, so lightly damped poles far from the real axis are handled (tested on
    an underdamped second-order step: 4e-9).

    Parameters
    ----------
    F : callable
        ``F(s)`` for an ndarray of complex ``s`` on the line; ``F`` should decay at least as
        ``1/s^2`` (a step response of a strictly proper loop) for the series to converge fast.
    t_max_s : float
        Last time (s).
    n : int
        Terms of the series (also the number of time samples over ``[0, 2 T)``).

    Returns
    -------
    t_s, f : ndarray
        Uniform times on ``[0, t_max_s]`` (spacing ``2 T/n``) and ``f`` there.
    """
    if not (t_max_s > 0 and n >= 16):
        raise ValueError(f"bromwich_inverse: needs t_max_s > 0 and n >= 16, got {t_max_s}, {n}")
    T = float(t_max_s)
    c = digits * np.log(10.0) / (2.0 * T)
    values = np.asarray(F(c + 1j * np.pi * np.arange(n) / T), complex)
    values[0] *= 0.5
    t = np.arange(n) * 2.0 * T / n
    f = np.exp(c * t) / T * (n * np.fft.ifft(values)).real
    keep = t <= T
    return t[keep], f[keep]


def step_response(closed_loop, t_max_s: float) -> tuple[np.ndarray, np.ndarray]:
    """``(t_s, y)``: step response of a closed loop given as ``T(s)`` (callable on complex
    arrays), by :func:`bromwich_inverse` of ``T(s)/s``."""
    return bromwich_inverse(lambda s: closed_loop(s) / s, t_max_s)
