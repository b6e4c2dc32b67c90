"""State feedback with the closed-loop poles in an LMI region (cvxpy, Clarabel).

Written here: neither python-control nor slycot offers pole-region synthesis.  The regions
are those of Chilali and Gahinet, *H-infinity design with pole placement constraints: an LMI
approach*, IEEE TAC 41(3), 1996: with ``P > 0``, ``Y = K P`` and ``M = A P - B Y`` (the
closed loop ``A - B K`` times ``P``),

- vertical strip ``Re(s) < -alpha``: ``M + M' + 2 alpha P < 0`` (2 % settling about
  ``4/alpha``);
- cone of half-angle ``theta`` around the negative real axis (damping ``zeta >= cos theta``):
  ``[[sin(theta) (M + M'), cos(theta) (M - M')], [cos(theta) (M' - M), sin(theta) (M + M')]] < 0``;
- disc ``|s| < radius`` (bounds the gains): ``[[-radius P, M], [M', -radius P]] < 0``.

Then ``K = Y P^-1`` places every eigenvalue of ``A - B K`` in the intersection.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import numpy as np


@dataclass
class PoleRegion:
    """``alpha`` (1/s): poles left of ``-alpha``; ``damping``: inside the cone
    ``zeta >= damping``; ``radius`` (rad/s): inside the disc ``|s| < radius``."""

    alpha: float
    damping: float
    radius: float

    def contains(self, poles, tol: float = 1e-9) -> bool:
        """Whether every pole lies in the region (``tol`` relative)."""
        p = np.asarray(poles, complex)
        zeta = -p.real / np.abs(p)
        return bool(
            np.all(p.real <= -self.alpha * (1 - tol))
            and np.all(zeta >= self.damping * (1 - tol))
            and np.all(np.abs(p) <= self.radius * (1 + tol))
        )


def region_state_feedback(A: np.ndarray, B: np.ndarray, region: PoleRegion, margin: float = 1e-3) -> np.ndarray:
    """A gain ``K`` with every eigenvalue of ``A - B K`` in ``region``.

    Minimizes ``||Y||_F + 0.1 trace(P)`` under the region's LMIs (strict inequalities as
    ``<= -margin I``) with ``P >= I`` fixing the scale, so ``||K|| <= ||Y||``: small gains that
    reach the region rather than the fastest poles (the trace term keeps the optimum off the
    region's edge, where Clarabel reported inaccurate solutions); solved by Clarabel.

    Raises
    ------
    ValueError
        When the LMIs are infeasible (the solver's status is given).
    """
    import cvxpy as cp

    n, m = B.shape
    P = cp.Variable((n, n), symmetric=True)
    Y = cp.Variable((m, n))
    M = A @ P - B @ Y
    s, c = math.sin(math.acos(region.damping)), region.damping
    eye, eye2 = np.eye(n), np.eye(2 * n)
    cons = [
        P >> eye,
        M + M.T + 2 * region.alpha * P << -margin * eye,
        cp.bmat([[s * (M + M.T), c * (M - M.T)], [c * (M.T - M), s * (M + M.T)]]) << -margin * eye2,
        cp.bmat([[-region.radius * P, M], [M.T, -region.radius * P]]) << -margin * eye2,
    ]
    problem = cp.Problem(cp.Minimize(cp.norm(Y, "fro") + 0.1 * cp.trace(P)), cons)
    with warnings.catch_warnings():  # an inaccurate solution is accepted only if its poles check out, below
        warnings.filterwarnings("ignore", message="Solution may be inaccurate", category=UserWarning)
        problem.solve(solver=cp.CLARABEL)
    if problem.status not in ("optimal", "optimal_inaccurate"):
        raise ValueError(f"pole region {region}: the LMIs are {problem.status}")
    if Y.value is None or P.value is None:
        raise ValueError(f"pole region {region}: the solver returned no solution ({problem.status})")
    K = np.asarray(Y.value @ np.linalg.inv(P.value), float)
    if not region.contains(np.linalg.eigvals(A - B @ K), tol=1e-6):
        raise ValueError(f"pole region {region}: the solver's gain misses the region")
    return K
