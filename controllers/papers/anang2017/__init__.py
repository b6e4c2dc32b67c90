"""Published PID of Anang et al. (2017), eq. (6), for the Googol XY table.

Eq. (6): TF_PID = 0.8998 + 0.005155 s + 0.0006077/s, with G(s) in mm/V, so the gains are in
V/mm, V s/mm and V/(mm s); here they are converted to V/m (x 1000).  The paper's derivative
is ideal; the twin needs a proper controller, so the derivative gets a first-order filter
(``tf_s``, default 0.1 ms: well above the 44.4 Hz bandwidth the paper reports).
"""

from __future__ import annotations

from controllers.design.pid import pid_tf

KP_V_PER_M = 0.8998e3
KD_V_S_PER_M = 0.005155e3
KI_V_PER_M_S = 0.0006077e3
#: Eqs. (7)-(8): Ke(e) = cosh(KO e) with e clipped at e_max.  The paper does not state the unit
#: of e; its plant (eq. 1) is in mm/V, so e is read in mm here (the Anang 2017 issue studies it).
KO_PER_MM = 6.0
E_MAX_MM = 0.3


def pid(tf_s: float = 1e-4):
    """Eq. (6) PID in V/m with derivative filter time constant ``tf_s`` (s)."""
    return pid_tf(KP_V_PER_M, KI_V_PER_M_S, KD_V_S_PER_M, tf_s)
