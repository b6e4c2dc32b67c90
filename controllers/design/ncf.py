"""H-infinity loop shaping by normalized coprime factors (Glover and McFarlane 1989), MIMO.

Neither python-control (0.10) nor slycot offers it, so it is written here from its two
Riccati equations (scipy's ``solve_continuous_are``) and the central controller.  For the
shaped plant ``Gs = G Ws = (A, B, C, 0)``, strictly proper:

- control ARE  ``A'X + XA - XBB'X + C'C = 0``, filter ARE ``AZ + ZA' - ZC'CZ + BB' = 0``;
- the optimal robustness ``gamma_min = sqrt(1 + rho(XZ))``, found without a gamma-iteration
  (Choi 1999 §3);
- for ``gamma > gamma_min``, with ``L = (1 - gamma^2) I + XZ``, the central controller
  (Skogestad and Postlethwaite, *Multivariable Feedback Control*, eq. 9.80, D = 0)
  ``A_K = A - BB'X + gamma^2 L'^-1 ZC'C``, ``B_K = gamma^2 L'^-1 ZC'``, ``C_K = B'X``
  for positive feedback ``u = K_inf y``.  Choi 1999's eq. (8) writes the same controller with
  ``(I + XZ - gamma^2 I)^-1``; its extraction is garbled, so the tests check this one by its
  defining property: ``||[K; I](I - Gs K)^-1 M^-1||_inf <= gamma``.

The final controller for the usual negative feedback ``u = K (r - y)`` is ``K = -Ws K_inf``.
:func:`ncf_generalized_plant` is the same problem as a generalized plant, for an independent
check of ``gamma_min`` with :func:`controllers.design.hinf.gamma_iteration` (SLICOT SB10AD).
"""

from __future__ import annotations

from dataclasses import dataclass

import control
import numpy as np
from scipy.linalg import solve_continuous_are


def ncf_riccati(A, B, C) -> tuple[np.ndarray, np.ndarray]:
    """The control and filter Riccati solutions ``X``, ``Z`` of a strictly proper plant."""
    A, B, C = (np.asarray(m, float) for m in (A, B, C))
    X = solve_continuous_are(A, B, C.T @ C, np.eye(B.shape[1]))
    Z = solve_continuous_are(A.T, C.T, B @ B.T, np.eye(C.shape[0]))
    return X, Z


def _gamma_min(X, Z) -> float:
    return float(np.sqrt(1.0 + np.max(np.linalg.eigvals(X @ Z).real)))


def gamma_min(A, B, C) -> float:
    """Optimal NCF robust-stabilization level ``sqrt(1 + rho(XZ))`` (dimensionless)."""
    return _gamma_min(*ncf_riccati(A, B, C))


def central_controller(A, B, C, gamma: float) -> control.StateSpace:
    """The central controller ``K_inf`` (positive feedback ``u = K_inf y``) for ``gamma``.

    Raises
    ------
    ValueError
        If ``gamma <= gamma_min``.
    """
    A, B, C = (np.asarray(m, float) for m in (A, B, C))
    X, Z = ncf_riccati(A, B, C)
    g_min = _gamma_min(X, Z)
    if not gamma > g_min:
        raise ValueError(f"gamma = {gamma:g}: must exceed gamma_min = {g_min:g}")
    L = (1.0 - gamma**2) * np.eye(A.shape[0]) + X @ Z
    H = gamma**2 * np.linalg.solve(L.T, Z @ C.T)
    return control.ss(A - B @ B.T @ X + H @ C, H, B.T @ X, np.zeros((B.shape[1], C.shape[0])))


def ncf_generalized_plant(A, B, C) -> control.StateSpace:
    """Generalized plant of the NCF robust-stabilization problem, inputs ``[w, u]``, outputs
    ``[u, y, y]``: ``y = Gs u + M^-1 w`` with ``M^-1 = (A, ZC', C, I)`` the inverse of the
    normalized left coprime denominator.  Its optimal H-infinity level (positive feedback
    ``u = K y``) is ``gamma_min``."""
    A, B, C = (np.asarray(m, float) for m in (A, B, C))
    _, Z = ncf_riccati(A, B, C)
    m, p, n = B.shape[1], C.shape[0], A.shape[0]
    Bw = np.hstack([Z @ C.T, B])
    Cz = np.vstack([np.zeros((m, n)), C, C])
    D = np.block([[np.zeros((m, p)), np.eye(m)], [np.eye(p), np.zeros((p, m))], [np.eye(p), np.zeros((p, m))]])
    return control.ss(A, Bw, Cz, D)


def ncf_robustness_norm(A, B, C, K_inf: control.StateSpace, *, omega) -> float:
    """``max over omega of sigma_max([K; I](I - Gs K)^-1 M^-1)``, positive feedback: the level
    that ``K_inf`` achieves (``gamma``), evaluated on the grid ``omega`` (rad/s)."""
    P = ncf_generalized_plant(A, B, C)
    m = B.shape[1]
    closed = P.lft(K_inf, nu=m, ny=C.shape[0])  # positive feedback, control's convention
    return float(max(np.linalg.svd(closed(1j * w), compute_uv=False)[0] for w in omega))


@dataclass
class LoopShapingDesign:
    """Result of :func:`loop_shaping`.

    Attributes
    ----------
    shaped : control.StateSpace
        ``Gs = G Ws`` (minimal).
    gamma_min, gamma : float
        Optimal and used level; the robustness margin is ``1/gamma``.
    K_inf : control.StateSpace
        Central controller of ``Gs`` (positive feedback).
    K : control.StateSpace
        Final controller ``-Ws K_inf`` for negative feedback ``u = K (r - y)``.
    """

    shaped: control.StateSpace
    gamma_min: float
    gamma: float
    K_inf: control.StateSpace
    K: control.StateSpace

    @property
    def margin(self) -> float:
        """Robustness margin ``epsilon = 1/gamma`` (NCF uncertainty it tolerates)."""
        return 1.0 / self.gamma


def loop_shaping(G: control.StateSpace, Ws: control.StateSpace, gamma_factor: float = 1.1) -> LoopShapingDesign:
    """Glover-McFarlane design: shape ``G`` with the precompensator ``Ws``, robustly stabilize.

    Parameters
    ----------
    G : control.StateSpace
        Plant, strictly proper.
    Ws : control.StateSpace
        Shaping precompensator (``G Ws`` is the target loop).
    gamma_factor : float
        ``gamma = gamma_factor * gamma_min``, > 1: slightly suboptimal (1.1 is Skogestad and
        Postlethwaite's usual choice, and Choi 1999's advice: it improves H2 performance and
        avoids a fast controller pole).
    """
    if not gamma_factor > 1.0:
        raise ValueError(f"gamma_factor = {gamma_factor!r}: must be > 1 (the optimal controller is singular)")
    shaped = control.minreal(control.series(control.ss(Ws), control.ss(G)), verbose=False)
    if np.any(shaped.D):
        raise ValueError("the shaped plant G Ws must be strictly proper")
    A, B, C = shaped.A, shaped.B, shaped.C
    g_min = gamma_min(A, B, C)
    K_inf = central_controller(A, B, C, gamma_factor * g_min)
    K = control.series(K_inf, control.ss(Ws)) * -1.0
    return LoopShapingDesign(shaped, g_min, gamma_factor * g_min, K_inf, K)
