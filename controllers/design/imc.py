"""Internal model control (IMC): Q(s) = G(s)^-1 / (mu s + 1)^lambda, C = Q / (1 - G0 Q).

Source: Yadav, Pathak, Gaur (2020), eqs. (20)-(23) and Appendix B (eqs. 56-59,
Table 3).  With G0 = G the closed loop is T(s) = 1/(mu s + 1)^lambda, a critically damped
(xi = 1) response with natural frequency 1/mu when lambda = 2.
"""

from __future__ import annotations

import control
import numpy as np


def imc_controller(plant: control.TransferFunction, mu_s: float, lam: int) -> control.TransferFunction:
    """The equivalent feedback controller C = Q / (1 - G Q) of IMC with model G0 = G.

    C = G^-1 / ((mu s + 1)^lambda - 1); the common roots (the plant's integrator cancels the
    origin root of (mu s + 1)^lambda - 1) are removed with ``control.minreal``.

    Parameters
    ----------
    plant : control.TransferFunction
        SISO, minimum phase, no delay.
    mu_s : float
        Filter time constant mu (s), > 0.
    lam : int
        Filter order lambda, at least the plant's relative degree (so Q is proper).

    Raises
    ------
    ValueError
        Non-positive mu, or lambda below the relative degree.
    """
    if mu_s <= 0:
        raise ValueError(f"mu_s = {mu_s}: the IMC filter time constant must be > 0")
    num, den = (np.atleast_1d(np.squeeze(c)) for c in control.tfdata(plant))
    num = np.trim_zeros(num, "f")
    relative_degree = len(den) - len(num)
    if lam < relative_degree:
        raise ValueError(
            f"lam = {lam}: Q(s) is improper unless lambda >= the plant's relative degree {relative_degree}"
        )
    filt = np.array([1.0])
    for _ in range(lam):
        filt = np.polymul(filt, [mu_s, 1.0])
    filt[-1] -= 1.0  # (mu s + 1)^lambda - 1
    return control.minreal(control.tf(den, np.polymul(num, filt)), verbose=False)
