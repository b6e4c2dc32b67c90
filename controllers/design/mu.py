"""Structured singular value: the upper bound over frequency, and sampled perturbations.

python-control has no mu analysis; slycot wraps SLICOT AB13MD, the mixed real/complex upper
bound with D-G scalings (Fan, Tits and Doyle 1991) for one constant matrix.  :func:`mu_upper_bound`
calls it at each frequency of a grid.  A bound on a grid can miss a sharp peak between points,
so :func:`destabilizing_scale` gives the sampled side: the smallest scaling of a constant real
perturbation that destabilizes the loop, whose inverse is a lower bound on the peak of mu for
every structure containing those real perturbations.

``N`` is the loop seen by the perturbation: ``z = N w``, ``w = Delta z`` (the upper LFT).
"""

from __future__ import annotations

import numpy as np
import slycot

from controllers.design.mimo import frequency_response


def mu_upper_bound(N, omega, nblock, itype) -> np.ndarray:
    """AB13MD's upper bound of mu(N(j w)) at each ``omega`` (rad/s).

    Parameters
    ----------
    N : control.StateSpace
        Square, the perturbation's channels.
    nblock, itype : sequence of int
        Block sizes and types (1 real, size 1 only; 2 complex), summing to N's size.
    """
    responses = frequency_response(N, omega)
    nblock, itype = np.asarray(nblock, np.int64), np.asarray(itype, np.int64)
    # cold starts: AB13MD warm-started from the previous frequency's scalings hung here
    return np.array([slycot.ab13md(M, nblock, itype)[0] for M in responses])


def constant_upper_lft(N, delta) -> tuple[np.ndarray, ...] | None:
    """``(A, B, C, D)`` of the upper LFT of ``N`` with the constant diagonal ``delta`` closing
    its first ``len(delta)`` inputs and outputs (``w = delta z``), or None where the loop is
    ill-posed (``I - D11 delta`` singular).  The rest of ``N``'s channels stay open."""
    A, B, C, D = (np.asarray(m, float) for m in (N.A, N.B, N.C, N.D))
    n = len(delta)
    delta = np.diag(np.asarray(delta, float))
    closing = np.eye(n) - D[:n, :n] @ delta
    if abs(np.linalg.det(closing)) < 1e-12:
        return None
    gain = delta @ np.linalg.solve(closing, np.eye(n))  # delta (I - D11 delta)^-1
    return (
        A + B[:, :n] @ gain @ C[:n],
        B[:, n:] + B[:, :n] @ gain @ D[:n, n:],
        C[n:] + D[n:, :n] @ gain @ C[:n],
        D[n:, n:] + D[n:, :n] @ gain @ D[:n, n:],
    )


def is_stable(N, delta) -> bool:
    """Whether the upper LFT of ``N`` with the constant diagonal ``delta`` is well posed and
    has all poles in the open left half plane."""
    closed = constant_upper_lft(N, delta)
    return closed is not None and bool(np.max(np.linalg.eigvals(closed[0]).real) < 0.0)


def destabilizing_scale(N, direction, k_max: float = 10.0, tol: float = 1e-3) -> float:
    """Smallest ``k`` in (0, ``k_max``] with ``k * direction`` destabilizing (bisection on the
    first instability along the ray, assuming stability at 0), or ``inf`` if none up to
    ``k_max`` on a grid of 200 points."""
    grid = np.linspace(0.0, k_max, 201)[1:]
    first = next((k for k in grid if not is_stable(N, k * np.asarray(direction))), None)
    if first is None:
        return float("inf")
    lo, hi = first - grid[0], first
    while hi - lo > tol * hi:
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if not is_stable(N, mid * np.asarray(direction)) else (mid, hi)
    return hi
