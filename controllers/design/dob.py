"""Q-filter of an inverse-model disturbance observer, chosen for robust stability.

With the observer ``d_hat = Q P_n^-1 y - Q u`` around a plant ``P = P_n (1 + Delta)``, the
observer's inner loop stays stable for every model error of the stated size when
``sup_w |Q(jw)| |Delta(jw)| < 1`` (small-gain theorem).  The procedure takes
``Q = 1/(tau s + 1)^order`` and returns the largest round cutoff (1, 2 or 5 times a power of
ten, Hz) whose worst ``|Q Delta|`` stays below a bound (0.5 by default: a factor of two of
robustness margin).
"""

from __future__ import annotations

import math

import numpy as np

#: Round cutoffs tried (Hz).
CUTOFFS_HZ = tuple(m * 10.0**k for k in range(-1, 4) for m in (1.0, 2.0, 5.0))


def q_response(cutoff_hz: float, order: int, w: np.ndarray) -> np.ndarray:
    """Q(jw) = 1/(tau jw + 1)^order, tau = 1/(2 pi cutoff_hz)."""
    return 1.0 / (1j * np.asarray(w, float) / (2 * math.pi * cutoff_hz) + 1.0) ** order


def delay_and_gain_error(delay_s: float, gain_error: float):
    """|Delta(jw)|: the worst of ``(1 + delta) e^(-jw T) - 1`` over ``|delta| <= gain_error``
    (an unmodelled delay T and a gain error), attained at one of the two extremes."""

    def size(w):
        phasor = np.exp(-1j * np.asarray(w, float) * delay_s)
        return np.maximum(np.abs((1 + gain_error) * phasor - 1), np.abs((1 - gain_error) * phasor - 1))

    return size


def worst_q_delta(cutoff_hz: float, order: int, delta, w: np.ndarray | None = None) -> float:
    """sup_w |Q(jw)| |Delta(jw)| on a logarithmic grid (0.01 rad/s to 1e6 rad/s)."""
    w = np.logspace(-2, 6, 40_000) if w is None else w
    return float(np.max(np.abs(q_response(cutoff_hz, order, w)) * delta(w)))


def q_cutoff(order: int, delta, bound: float = 0.5) -> tuple[float, float]:
    """``(cutoff_hz, worst |Q Delta|)``: the largest round cutoff keeping ``|Q Delta| <= bound``.

    Raises
    ------
    ValueError
        Not even the lowest cutoff of :data:`CUTOFFS_HZ` meets the bound.
    """
    ok = [(f, worst_q_delta(f, order, delta)) for f in CUTOFFS_HZ]
    ok = [(f, v) for f, v in ok if v <= bound]
    if not ok:
        raise ValueError(f"no Q-filter cutoff of order {order} keeps |Q Delta| <= {bound}")
    return ok[-1]
