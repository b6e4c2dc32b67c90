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
    Im L = 0); the gain crossover where |L| first passes 1: the first crossings, as the papers
    report them.  A loop that crosses again (a resonance above the crossover) needs
    :func:`crossing_margins`, every crossing's.
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


#: A grid's last point this near -180 deg (mod 360, deg) is a phase crossing: a sampled loop's
#: response is real at Nyquist, where its grid ends.
END_CROSSING_DEG = 1e-6


@dataclass(frozen=True)
class CrossingMargins:
    """A loop's margins over every crossing on a grid (None where there is no crossing: the
    margin is infinite).  Of each kind the crossing nearest to instability is reported, as
    ``control.stability_margins`` chooses: the smallest ``|phase margin|`` over every gain
    crossover and the smallest ``|gain margin|`` (dB) over every -180 deg crossing (mod 360),
    negative where the loop goes unstable when its gain falls by that much.

    Attributes
    ----------
    pm_deg, f_pm_hz : float or None
        Phase margin, 180 deg + arg L in [-180, 180) (deg), and its gain crossover (Hz).
    gm_db, f_gm_hz : float or None
        Gain margin, -20 log10 |L| (dB), and its phase crossover (Hz).
    """

    pm_deg: float | None
    f_pm_hz: float | None
    gm_db: float | None
    f_gm_hz: float | None

    def as_dict(self) -> dict:
        """``phase_margin_deg``, ``phase_margin_hz``, ``gain_margin_db``, ``gain_margin_hz``;
        an infinite margin is None with a ``..._note`` saying why (strict JSON)."""
        out: dict = {
            "phase_margin_deg": _rounded(self.pm_deg),
            "phase_margin_hz": _rounded(self.f_pm_hz),
            "gain_margin_db": _rounded(self.gm_db),
            "gain_margin_hz": _rounded(self.f_gm_hz),
        }
        if self.pm_deg is None:
            out["phase_margin_note"] = "infinite: |L| does not cross 1 on the grid"
        if self.gm_db is None:
            out["gain_margin_note"] = "infinite: the phase does not reach -180 deg (mod 360) on the grid"
        return out


def _rounded(value: float | None) -> float | None:
    return None if value is None else round(value, 4)


def crossing_margins(freqs_hz: np.ndarray, response: np.ndarray) -> CrossingMargins:
    """:class:`CrossingMargins` of a loop's frequency ``response`` on an increasing grid
    ``freqs_hz``: each crossing between two grid points is placed by linear interpolation of
    log |L| and of the unwrapped phase in log f (points where L is 0 are left out)."""
    nonzero = np.abs(response) > 0.0  # a zero on the grid (a ZOH's at Nyquist) has no phase
    f = np.asarray(freqs_hz, float)[nonzero]
    response = np.asarray(response)[nonzero]
    log_f = np.log(f)
    log_mag = np.log(np.abs(response))
    phase = np.degrees(np.unwrap(np.angle(response)))

    def between(i: int, frac: float, values: np.ndarray) -> float:
        return float(values[i] + frac * (values[i + 1] - values[i]))

    pm: list[tuple[float, float]] = []
    for i in np.flatnonzero(np.sign(log_mag[:-1]) * np.sign(log_mag[1:]) < 0).tolist():
        frac = log_mag[i] / (log_mag[i] - log_mag[i + 1])
        margin = between(i, frac, phase) % 360.0 - 180.0
        pm.append((margin, math.exp(between(i, frac, log_f))))
    best_pm = min(pm, key=lambda m: abs(m[0]), default=(None, None))
    best_gm = min(phase_crossings(f, response), key=lambda m: abs(m[0]), default=(None, None))
    return CrossingMargins(best_pm[0], best_pm[1], best_gm[0], best_gm[1])


def phase_crossings(freqs_hz: np.ndarray, response: np.ndarray) -> list[tuple[float, float]]:
    """Every -180 deg (mod 360) crossing of a loop's frequency ``response`` on an increasing
    grid ``freqs_hz``, as (gain margin, dB: -20 log10 |L| there; frequency, Hz), placed as
    :func:`crossing_margins` places them (a phase within :data:`END_CROSSING_DEG` of -180 deg at
    the grid's end counts).  For a stable closed loop the smallest positive margin is the gain
    increase it takes to go unstable, the negative margin nearest 0 the decrease."""
    nonzero = np.abs(response) > 0.0
    f = np.asarray(freqs_hz, float)[nonzero]
    response = np.asarray(response)[nonzero]
    log_f = np.log(f)
    log_mag = np.log(np.abs(response))
    phase = np.degrees(np.unwrap(np.angle(response)))
    gm: list[tuple[float, float]] = []
    turn = np.floor((phase + 180.0) / 360.0)  # the -180 deg (mod 360) lines passed
    for i in np.flatnonzero(turn[:-1] != turn[1:]).tolist():
        target = 360.0 * max(turn[i], turn[i + 1]) - 180.0
        frac = float((target - phase[i]) / (phase[i + 1] - phase[i]))
        magnitude = log_mag[i] + frac * (log_mag[i + 1] - log_mag[i])
        gm.append((float(-20.0 * magnitude / math.log(10.0)), math.exp(log_f[i] + frac * (log_f[i + 1] - log_f[i]))))
    if abs((phase[-1] % 360.0) - 180.0) < END_CROSSING_DEG:
        gm.append((-20.0 * float(log_mag[-1]) / math.log(10.0), float(f[-1])))
    return gm


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
