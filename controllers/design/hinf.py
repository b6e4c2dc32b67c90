"""Mixed-sensitivity H-infinity synthesis with a gamma-iteration, and controller reduction.

Source: Yadav, Pathak, Gaur (2020), eqs. (24)-(29).  The generalized plant stacks
W1 S, W2 C S and W3 T (``control.augw``); the controller is the central (Glover-Doyle)
controller of SLICOT SB10AD (via slycot) for a given gamma, and the gamma-iteration is a
bisection on gamma that keeps the largest gamma for which no admissible controller exists
below.  The paper's MATLAB ``hinfopt`` reports the scaling theta of ||theta M|| <= 1, i.e.
theta = 1/gamma.

A plant pole at the origin violates the synthesis' imaginary-axis rank condition (the
(A - j w I, B1; C2, D21) pencil loses rank at w = 0).  :func:`shift_integrators` moves such poles
to -eps (a small stable shift, the usual fix); the shift is a parameter of the design.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import control
import numpy as np
import slycot


def shift_integrators(plant: control.TransferFunction, eps: float) -> control.TransferFunction:
    """Replace the plant's poles at the origin by poles at -eps (1/s).

    Parameters
    ----------
    plant : control.TransferFunction
        SISO plant.
    eps : float
        Shift (1/s), > 0 and small against the bandwidth.
    """
    if eps <= 0:
        raise ValueError(f"eps = {eps}: the integrator shift must be > 0")
    num, den = (np.atleast_1d(np.squeeze(c)) for c in control.tfdata(plant))
    poles = np.roots(den)
    at_origin = np.abs(poles) < 1e-12
    poles[at_origin] = -eps
    return control.tf(num, den[0] * np.real(np.poly(poles)))


def mixed_sensitivity_plant(plant, w1, w2, w3) -> control.StateSpace:
    """Generalized plant of eq. (24): outputs W1 e, W2 u, W3 y and e; inputs r and u."""
    with warnings.catch_warnings():  # python-control 0.10's augw calls its own deprecated connect()
        warnings.filterwarnings("ignore", message=r"connect\(\) is deprecated", category=FutureWarning)
        return control.ss(control.augw(plant, w1, w2, w3))


def central_controller(P: control.StateSpace, gamma: float, ncon: int = 1, nmeas: int = 1) -> control.StateSpace:
    """The central H-infinity controller achieving ||M||_inf < gamma (SB10AD, suboptimal).

    ``ncon`` and ``nmeas`` are the numbers of control inputs and measurements, the last
    inputs and outputs of ``P``.

    Raises
    ------
    ValueError
        If no admissible controller exists for this gamma (SB10AD's error), or it does not
        stabilize the generalized plant.
    """
    n, m, p = P.nstates, P.ninputs, P.noutputs
    try:
        out = slycot.sb10ad(n, m, p, ncon, nmeas, gamma, P.A, P.B, P.C, P.D, job=4)
    except (ValueError, ArithmeticError, slycot.exceptions.SlycotError) as exc:
        raise ValueError(f"gamma = {gamma:g}: no admissible controller ({exc})") from None
    _, Ak, Bk, Ck, Dk, Ac = out[:6]
    if np.linalg.eigvals(Ac).real.max() >= 0:
        raise ValueError(f"gamma = {gamma:g}: the central controller does not stabilize the loop")
    return control.ss(Ak, Bk, Ck, Dk)


@dataclass
class GammaIteration:
    """Result of :func:`gamma_iteration`.

    Attributes
    ----------
    gamma : float
        Smallest gamma found admissible (within ``tol``, relative).
    controller : control.StateSpace
        Central controller at ``gamma``.
    iterations : int
        Bisection steps taken.
    """

    gamma: float
    controller: control.StateSpace
    iterations: int

    @property
    def theta(self) -> float:
        """The paper's scaling factor theta = 1/gamma (eq. 26)."""
        return 1.0 / self.gamma


def gamma_iteration(
    P: control.StateSpace,
    *,
    gamma_max: float = 1e4,
    gamma_min: float = 1e-3,
    tol: float = 1e-3,
    ncon: int = 1,
    nmeas: int = 1,
) -> GammaIteration:
    """Bisect (geometrically) on gamma for the smallest admissible one (``ncon`` control
    inputs and ``nmeas`` measurements, as for :func:`central_controller`).

    Raises
    ------
    ValueError
        If ``gamma_max`` is not admissible.
    """
    hi = gamma_max
    best = central_controller(P, hi, ncon, nmeas)
    lo, iterations = gamma_min, 0
    while hi / lo > 1.0 + tol:
        mid = np.sqrt(lo * hi)
        iterations += 1
        try:
            best, hi = central_controller(P, mid, ncon, nmeas), mid
        except ValueError:
            lo = mid
    return GammaIteration(gamma=hi, controller=best, iterations=iterations)


def reduce_balanced(controller: control.LTI, order: int) -> control.TransferFunction:
    """Balanced truncation to ``order`` (``control.balred``, method 'truncate')."""
    return control.tf(control.balred(control.ss(controller), order, method="truncate"))
