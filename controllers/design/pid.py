"""PID with a first-order filtered derivative, as a transfer function."""

from __future__ import annotations

from controllers.lti import SisoTf


def pid_tf(kp: float, ki: float = 0.0, kd: float = 0.0, tf_s: float = 0.0) -> SisoTf:
    """C(s) = kp + ki/s + kd s/(tf_s s + 1), over the common denominator without the factors
    a zero gain leaves out (``s`` without ``ki``, ``tf_s s + 1`` without ``kd``).

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
    if kd and not tf_s > 0:
        raise ValueError(f"tf_s = {tf_s!r}: a derivative term needs a filter time constant > 0")
    if kd:
        # (kp s (tf s + 1) + ki (tf s + 1) + kd s^2) / (s (tf s + 1)), or without ki: / (tf s + 1)
        if ki:
            return SisoTf((kp * tf_s + kd, kp + ki * tf_s, ki), (tf_s, 1.0, 0.0))
        return SisoTf((kp * tf_s + kd, kp), (tf_s, 1.0))
    if ki:
        return SisoTf((kp, ki), (1.0, 0.0))
    return SisoTf((kp,), (1.0,))
