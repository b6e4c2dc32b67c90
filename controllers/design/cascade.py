"""Cascade P/PI by loop shaping: a velocity PI that meets a gain and a phase margin, and a
position gain that meets a phase margin around the closed velocity loop.

Frequency responses are functions of w (rad/s), so delays and measurement filters enter
exactly (see :mod:`controllers.design.loop_analysis`).  Units follow the plant: for a plant
in mm/V the velocity PI is in V/(mm/s) and V/mm, the position gain in 1/s.
"""

from __future__ import annotations

import warnings

import numpy as np
from scipy.optimize import brentq, fsolve

from controllers.design.loop_analysis import LoopMargins, loop_margins


def pi_loop(kp: float, ki: float, plant):
    """L(w) = (kp + ki/(jw)) plant(w)."""
    return lambda w: (kp + ki / (1j * np.asarray(w, float))) * plant(w)


def pi_for_margins(plant, gm_db: float, pm_deg: float, guess: tuple[float, float]) -> tuple[float, float, LoopMargins]:
    """``(kp, ki, margins)`` of the PI whose loop with ``plant`` has both margins.

    Solved in the logarithms of the gains from ``guess`` (Newton-type, scipy's ``fsolve``).

    Raises
    ------
    ValueError
        No PI reaches both margins from the guess (within 0.01 dB and 0.01 deg).
    """

    def residual(x):
        m = loop_margins(pi_loop(*np.exp(x), plant), n=20_000)
        return [m.gm_db - gm_db, m.pm_deg - pm_deg]

    with warnings.catch_warnings():  # a poor convergence is reported below, as an error
        warnings.simplefilter("ignore", RuntimeWarning)
        x = fsolve(residual, np.log(guess))
    kp, ki = (float(v) for v in np.exp(x))
    m = loop_margins(pi_loop(kp, ki, plant))
    if not (abs(m.gm_db - gm_db) < 0.01 and abs(m.pm_deg - pm_deg) < 0.01):
        closest = (
            f"closest: {m.gm_db:.3g} dB, {m.pm_deg:.3g} deg"
            if np.isfinite([m.gm_db, m.pm_deg]).all()
            else "the search found no loop with finite margins"
        )
        raise ValueError(f"no PI gives GM {gm_db} dB and PM {pm_deg} deg ({closest})")
    return kp, ki, m


def closed_loop(L):
    """T(w) = L/(1 + L)."""
    return lambda w: L(w) / (1 + L(w))


def gain_for_phase_margin(plant, pm_deg: float, lo: float, hi: float) -> tuple[float, LoopMargins]:
    """``(k, margins)`` of the proportional gain whose loop ``k plant`` has phase margin
    ``pm_deg``, searched in ``[lo, hi]``."""
    k = brentq(lambda g: loop_margins(lambda w: g * plant(w), n=20_000).pm_deg - pm_deg, lo, hi, rtol=1e-10)
    return k, loop_margins(lambda w: k * plant(w))


def backward_difference(dt: float):
    """Velocity measured as (y_k - y_k-1)/dt, relative to the true derivative: (1 - e^(-jw dt))/(jw dt)."""

    def M(w):
        w = np.asarray(w, float)
        return (1 - np.exp(-1j * w * dt)) / (1j * w * dt)

    return M
