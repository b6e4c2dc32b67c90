"""Published controllers of Yadav, Pathak, Gaur (2020), as printed in the paper.

These are the paper's constants so the runner has real controllers from day one; their design
procedures (Kharitonov GM/PM design, IMC, mixed-sensitivity H-infinity) are reproduced
separately.  All act on the position error (m) and output the control input u (V).
"""

from __future__ import annotations

from controllers.lti import SisoTf

#: Robust PI from worst-case GM 10 dB / PM 60 deg, eqs. (18)-(19): Kp = 38.33, Ki = 45.65.
ROBUST_PI = SisoTf([38.33, 45.65], [1.0, 0.0])

#: IMC controller, eq. (23): C(s) = (0.21 s + 2)/(s + 2) (mu = 1, lambda = 2).
IMC = SisoTf([0.21, 2.0], [1.0, 2.0])

#: Full-order mixed-sensitivity H-infinity controller, eq. (28).
HINF = SisoTf([20.12, 197.2, 19.52, 2.72e-13], [1.0, 14.23, 54.16, 5.879, 0.05339])

#: Reduced first-order H-infinity controller, eq. (29): 20.97/(s + 5.5).
HINF_REDUCED = SisoTf([20.97], [1.0, 5.5])
