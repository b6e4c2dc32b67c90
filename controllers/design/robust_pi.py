"""Robust PI from worst-case gain and phase margins on a Kharitonov polynomial.

Source: Yadav, Pathak, Gaur (2020), eqs. (6)-(19).  The closed loop of the lead-screw
axis with C(s) = Kp + Ki/s has the characteristic polynomial

    p(s) = s^3 + a1 s^2 + c2 Kp s + c3 Ki                       (eq. 17 form)

and the paper designs on its worst Kharitonov polynomial p3(s) = beta0 s^3 + alpha1 s^2 +
alpha2 s + beta3 (eq. 8), with alpha1 = min a1, alpha2 = min(c2) Kp, beta3 = max(c3) Ki and
beta0 = 1.  The margins come from the Routh array (eqs. 9-13) and the paper's empirical
gain-crossover formula (eq. 14):

    GM = alpha1 alpha2 / beta3                                     (eq. 11, as a ratio)
    PM = 90 deg - atan( sqrt(alpha1^3 beta3) / (alpha1 alpha2 - beta3) )   (eq. 15)

Given GM and PM these two equations are solved in closed form for Kp and Ki.
"""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class RobustPIDesign:
    """Result of :func:`design_robust_pi`.

    Attributes
    ----------
    kp : float
        Proportional gain (V/m).
    ki : float
        Integral gain (V/(m s)).
    kp_per_ki : float
        Ratio fixed by the GM equation (eq. 18: the paper rounds it to 0.84).
    """

    kp: float
    ki: float
    kp_per_ki: float


def worst_case_margins(alpha1: float, alpha2: float, beta3: float) -> tuple[float, float]:
    """GM (dB) and PM (deg) of p3(s) = s^3 + alpha1 s^2 + alpha2 s + beta3 by eqs. (11), (15)."""
    gm_db = 20.0 * math.log10(alpha1 * alpha2 / beta3)
    pm_deg = 90.0 - math.degrees(math.atan2(math.sqrt(alpha1**3 * beta3), alpha1 * alpha2 - beta3))
    return gm_db, pm_deg


def design_robust_pi(
    alpha1: float, c2_min: float, c3_max: float, *, gm_db: float = 10.0, pm_deg: float = 60.0
) -> RobustPIDesign:
    """Solve eqs. (11) and (15) for Kp and Ki.

    Parameters
    ----------
    alpha1 : float
        Lower bound of the s^2 coefficient (1/s).
    c2_min, c3_max : float
        Lower bound of the s^1 coefficient per unit Kp and upper bound of the s^0 coefficient per
        unit Ki (both the plant's K1 K2 n p / (p^2 m + n^2 Im) over the box, 1/s^2 per V/m).
    gm_db, pm_deg : float
        Worst-case gain margin (dB, > 0) and phase margin (deg, in (0, 90)).

    Returns
    -------
    RobustPIDesign

    Raises
    ------
    ValueError
        Targets outside the ranges above.
    """
    if gm_db <= 0:
        raise ValueError(f"gm_db = {gm_db}: the gain margin must be > 0 dB")
    if not 0 < pm_deg < 90:
        raise ValueError(f"pm_deg = {pm_deg}: eq. (15) needs 0 < PM < 90 deg")
    g = 10.0 ** (gm_db / 20.0)
    # eq. (11): alpha1 c2 Kp = g c3 Ki  ->  Kp = r Ki
    r = g * c3_max / (alpha1 * c2_min)
    # eq. (15): tan(90 - PM) = sqrt(alpha1^3 c3 Ki) / (c3 (g - 1) Ki)
    t = math.tan(math.radians(90.0 - pm_deg))
    ki = alpha1**3 / (c3_max * (g - 1.0) ** 2 * t**2)
    return RobustPIDesign(kp=r * ki, ki=ki, kp_per_ki=r)
