"""Frequency-domain analysis of a loop gain L(jw): stability margins, sensitivity peak and
bandwidth, and the Popov plot's real-axis crossing.

The loop gain is any function ``L(w)`` of the angular frequency (rad/s) returning complex
values, so a transport delay enters exactly as ``exp(-j w T)`` (no Pade approximation).
Crossings are bracketed on a dense logarithmic grid and refined by root finding.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

#: Default bracketing grid: 1e-2 to 1e5 rad/s, 10 000 points per decade.
W_MIN, W_MAX, N_GRID = 1e-2, 1e5, 70_000


@dataclass(frozen=True)
class LoopMargins:
    """Margins of a loop gain (NaN where a crossing does not exist).

    Attributes
    ----------
    gm_db : float
        Gain margin, -20 log10 |L| at the first phase crossing of -180 deg (dB).
    w_gm : float
        That phase-crossover frequency (rad/s).
    pm_deg : float
        Phase margin, 180 deg + arg L at the first gain crossover |L| = 1 (deg).
    w_pm : float
        The gain-crossover frequency (rad/s).
    ms_db : float
        Peak sensitivity max |1/(1 + L)| (dB), and ``w_ms`` where it occurs (rad/s).
    w_bw : float
        Bandwidth: the first frequency where |S| rises through -3 dB (rad/s).
    """

    gm_db: float
    w_gm: float
    pm_deg: float
    w_pm: float
    ms_db: float
    w_ms: float
    w_bw: float


def _grid(w_min: float, w_max: float, n: int) -> np.ndarray:
    return np.logspace(math.log10(w_min), math.log10(w_max), n)


def _at(L, x: float) -> complex:
    return complex(np.asarray(L(np.array([x])), complex)[0])


def _bracket(values: np.ndarray) -> int | None:
    """Index of the first grid interval where ``values`` changes sign, or None."""
    idx = np.flatnonzero(np.sign(values[:-1]) * np.sign(values[1:]) < 0)
    return int(idx[0]) if len(idx) else None


def _refine(f, w: np.ndarray, i: int) -> float:
    return brentq(f, w[i], w[i + 1], xtol=1e-12 * w[i], rtol=1e-14)


def loop_margins(L, w_min: float = W_MIN, w_max: float = W_MAX, n: int = N_GRID) -> LoopMargins:
    """Gain and phase margins, peak sensitivity and sensitivity bandwidth of ``L(w)``.

    The phase crossover is where the unwrapped phase first passes -180 deg (refined where
    Im L = 0); the gain crossover where |L| first passes 1.
    """
    w = _grid(w_min, w_max, n)
    Lw = np.asarray(L(w), complex)
    phase = np.unwrap(np.angle(Lw))
    i = _bracket(phase + np.pi)
    w_gm = _refine(lambda x: _at(L, x).imag, w, i) if i is not None else math.nan
    gm = -20 * math.log10(abs(_at(L, w_gm))) if i is not None else math.nan
    i = _bracket(np.abs(Lw) - 1.0)
    if i is None:
        w_pm = pm = math.nan
    else:
        w_pm = _refine(lambda x: abs(_at(L, x)) - 1.0, w, i)
        angle = np.angle(_at(L, w_pm))
        pm = (math.degrees(angle) + 360.0) % 360.0 - 180.0  # in [-180, 180)
    S_db = -20 * np.log10(np.abs(1 + Lw))
    k = int(np.argmax(S_db))
    i = _bracket(S_db + 3.0)
    w_bw = _refine(lambda x: -20 * math.log10(abs(1 + _at(L, x))) + 3.0, w, i) if i is not None else math.nan
    return LoopMargins(gm, w_gm, pm, w_pm, float(S_db[k]), float(w[k]), w_bw)


def popov_crossing(L, w_min: float = W_MIN, w_max: float = W_MAX, n: int = N_GRID) -> tuple[float, float]:
    """The Popov plot's first crossing of the negative real axis: ``(Re L, w)``.

    The Popov plot is ``(Re L(jw), w Im L(jw))``; for w > 0 it meets the real axis where
    ``Im L = 0``, the same frequency as the Nyquist plot's.  The largest gain of a sector
    nonlinearity in front of L that keeps the crossing right of -1 is ``1/|Re L|``.
    """
    w = _grid(w_min, w_max, n)
    Lw = np.asarray(L(w), complex)
    candidates = np.flatnonzero((np.sign(Lw.imag[:-1]) * np.sign(Lw.imag[1:]) < 0) & (Lw.real[:-1] < 0))
    if not len(candidates):
        return math.nan, math.nan
    wc = _refine(lambda x: _at(L, x).imag, w, int(candidates[0]))
    return _at(L, wc).real, wc
