"""PID with a first-order filtered derivative, as a python-control transfer function."""

from __future__ import annotations

import control


def pid_tf(kp: float, ki: float = 0.0, kd: float = 0.0, tf_s: float = 0.0) -> control.TransferFunction:
    """C(s) = kp + ki/s + kd s/(tf_s s + 1).

    Parameters
    ----------
    kp : float
        Proportional gain, V/m.
    ki : float
        Integral gain, V/(m s).
    kd : float
        Derivative gain, V s/m.
    tf_s : float
        Derivative filter time constant (s); must be > 0 when ``kd`` is non-zero.
    """
    s = control.tf("s")
    c = kp + 0 * s
    if ki:
        c = c + ki / s
    if kd:
        if tf_s <= 0:
            raise ValueError(f"tf_s = {tf_s!r}: a derivative term needs a filter time constant > 0")
        c = c + kd * s / (tf_s * s + 1)
    return control.minreal(control.tf(c), verbose=False)
