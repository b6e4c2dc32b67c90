"""Kharitonov's theorem for interval polynomials and the third-order stability margin.

Source: Yadav, Pathak, Gaur (2020), eqs. (3)-(5).  Coefficients are ordered from the
highest power down, as the paper writes them: P(s) = a0 s^n + a1 s^(n-1) + ... + an, with
alpha_i <= a_i <= beta_i.
"""

from __future__ import annotations

import numpy as np

#: Kharitonov's four patterns of (lower=0 / upper=1) picks, repeating every four coefficients,
#: for the coefficients of s^0, s^1, s^2, s^3 (lowest power first).
_PATTERNS = {
    "K1": (0, 0, 1, 1),
    "K2": (1, 1, 0, 0),
    "K3": (0, 1, 1, 0),
    "K4": (1, 0, 0, 1),
}


def kharitonov_polynomials(lower, upper) -> dict[str, np.ndarray]:
    """The four Kharitonov polynomials of an interval polynomial of any degree.

    Parameters
    ----------
    lower, upper : array_like, shape (n + 1,)
        Coefficient bounds alpha_i, beta_i, highest power first.

    Returns
    -------
    dict of str to ndarray
        ``K1..K4``, coefficients highest power first.

    Raises
    ------
    ValueError
        If the bounds have different lengths or lower > upper anywhere.
    """
    lo, hi = np.asarray(lower, float), np.asarray(upper, float)
    if lo.shape != hi.shape or lo.ndim != 1:
        raise ValueError(f"bounds of shapes {lo.shape} and {hi.shape}: need equal 1-D arrays")
    if (lo > hi).any():
        raise ValueError(f"lower bound above upper bound at coefficient {int(np.argmax(lo > hi))}")
    bounds = np.stack([lo[::-1], hi[::-1]])  # lowest power first
    out = {}
    for name, pattern in _PATTERNS.items():
        picks = np.array([pattern[i % 4] for i in range(len(lo))])
        out[name] = bounds[picks, np.arange(len(lo))][::-1].copy()
    return out


def is_hurwitz(coeffs) -> bool:
    """Whether all roots of a real polynomial lie in the open left half plane (Routh array).

    Parameters
    ----------
    coeffs : array_like
        Coefficients, highest power first; the leading one must be non-zero.
    """
    c = np.asarray(coeffs, float)
    c = c / c[0]
    n = len(c) - 1
    if n == 0:
        return True
    if (c <= 0).any():  # necessary condition
        return False
    rows = [c[0::2].copy(), c[1::2].copy()]
    width = len(rows[0])
    rows = [np.pad(r, (0, width - len(r))) for r in rows]
    for _ in range(n - 1):
        a, b = rows[-2], rows[-1]
        if b[0] <= 0:
            return False
        nxt = np.zeros(width)
        nxt[:-1] = (b[0] * a[1:] - a[0] * b[1:]) / b[0]
        rows.append(nxt)
    return all(r[0] > 0 for r in rows)


def robustly_stable(lower, upper) -> bool:
    """Kharitonov: the interval polynomial is Hurwitz for every member iff K1..K4 are.

    The leading coefficient's interval must exclude zero (degree invariance).
    """
    lo, hi = np.asarray(lower, float), np.asarray(upper, float)
    if lo[0] <= 0 <= hi[0]:
        raise ValueError(f"leading coefficient interval [{lo[0]}, {hi[0]}] contains 0")
    return all(is_hurwitz(k) for k in kharitonov_polynomials(lo, hi).values())


def stability_margin_third_order(lower, upper) -> float:
    """Eq. (5): SM = alpha1 alpha2 - beta0 beta3 of a third-order interval polynomial.

    With every coefficient positive, positive SM means robustly stable (Hote et al., the
    paper's ref. [14]); this is the Routh condition of the worst Kharitonov polynomial,
    a0 s^3 + a1 s^2 + a2 s + a3 with the lower a1, a2 and the upper a0, a3.  A negative lower
    bound makes the family unstable whatever the SM says.

    Raises
    ------
    ValueError
        If the polynomial is not of degree 3.
    """
    lo, hi = np.asarray(lower, float), np.asarray(upper, float)
    if len(lo) != 4:
        raise ValueError(f"SM of eq. (5) is for degree 3; got degree {len(lo) - 1}")
    return float(lo[1] * lo[2] - hi[0] * hi[3])
