"""PID with a first-order filtered derivative, as a transfer function."""

from __future__ import annotations

import numpy as np

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


def _pid_parts(w_c: float, integral_ratio: float, filter_ratio: float) -> tuple[float, float, complex, complex]:
    """The loop-shaping rule's integral corner ``w_i`` (rad/s) and filter time ``tf_s`` (s), and
    at ``j w_c`` the factors of ``C = kp p_part + kd d_part``: ``1 + w_i/(j w_c)`` and
    ``j w_c/(1 + j w_c tf_s)``."""
    w_i, tf_s = integral_ratio * w_c, 1.0 / (filter_ratio * w_c)
    return w_i, tf_s, 1.0 + w_i / (1j * w_c), 1j * w_c / (1.0 + 1j * w_c * tf_s)


def _response(plant, w: float) -> complex:
    """The plant's frequency response at one angular frequency ``w`` (rad/s)."""
    return complex(np.asarray(plant(np.array([w])))[0])


def pid_for_crossover(
    plant, w_c: float, pm_deg: float, *, integral_ratio: float = 0.1, filter_ratio: float = 10.0
) -> tuple[float, float, float, float]:
    """PID whose loop ``C P`` crosses over at ``w_c`` with phase margin ``pm_deg``: the
    conventional loop-shaping rule (integral corner ``integral_ratio * w_c``, derivative filter
    corner ``filter_ratio * w_c``), solved for ``kp`` and ``kd`` from ``C(j w_c) P(j w_c) =
    exp(j (pm - 180 deg))``.

    Parameters
    ----------
    plant : callable
        ``plant(w)``: the plant's frequency response at angular frequencies ``w`` (rad/s).
    w_c : float
        Gain crossover (rad/s).
    pm_deg : float
        Phase margin at ``w_c`` (deg).

    Returns
    -------
    kp, ki, kd, tf_s : float
        Gains in the plant's units (for a plant in m/V: V/m, V/(m s), V s/m) and the filter
        time constant (s), as :func:`pid_tf` takes them.

    Raises
    ------
    ValueError
        If the phase needed at ``w_c`` cannot be reached with positive ``kp`` and ``kd``.
    """
    w_i, tf_s, p_part, d_part = _pid_parts(w_c, integral_ratio, filter_ratio)
    target = np.exp(1j * np.radians(pm_deg - 180.0)) / _response(plant, w_c)
    kp, kd = np.linalg.solve([[p_part.real, d_part.real], [p_part.imag, d_part.imag]], [target.real, target.imag])
    if not (kp > 0 and kd >= 0):
        raise ValueError(f"no PID with kp, kd > 0 gives {pm_deg:g} deg at {w_c:g} rad/s (kp {kp:.3g}, kd {kd:.3g})")
    return float(kp), float(kp * w_i), float(kd), tf_s


def pid_for_crossover_with_kp(
    plant, w_c: float, kp: float, *, integral_ratio: float = 0.1, filter_ratio: float = 10.0
) -> tuple[float, float, float, float]:
    """PID with a given proportional gain ``kp`` whose loop ``C P`` crosses over at ``w_c``:
    integral corner ``integral_ratio * w_c``, derivative filter corner ``filter_ratio * w_c``,
    and the ``kd >= 0`` that makes ``|C(j w_c) P(j w_c)| = 1`` (the phase margin follows).

    Parameters
    ----------
    plant : callable
        ``plant(w)``: the plant's frequency response at angular frequencies ``w`` (rad/s).
    w_c : float
        Gain crossover (rad/s).
    kp : float
        Proportional gain, in the plant's inverse units (V/m for a plant in m/V).

    Returns
    -------
    kp, ki, kd, tf_s : float
        As :func:`pid_for_crossover` returns them.

    Raises
    ------
    ValueError
        If ``kp`` with its integral term alone already exceeds unit loop gain at ``w_c`` (no
        ``kd >= 0`` brings the crossover there).
    """
    w_i, tf_s, p_part, b = _pid_parts(w_c, integral_ratio, filter_ratio)
    need = 1.0 / abs(_response(plant, w_c))  # |C(j w_c)| for crossover
    a = kp * p_part
    # |a + kd b|^2 = need^2: |b|^2 kd^2 + 2 Re(a conj b) kd + |a|^2 - need^2 = 0
    qa, qb, qc = abs(b) ** 2, 2.0 * (a * b.conjugate()).real, abs(a) ** 2 - need**2
    if qc > 0:
        raise ValueError(
            f"kp = {kp:.4g} alone gives a loop gain of {abs(a) / need:.3g} at {w_c:g} rad/s: "
            "no kd >= 0 puts the crossover there"
        )
    kd = (-qb + np.sqrt(qb * qb - 4.0 * qa * qc)) / (2.0 * qa)
    return float(kp), float(kp * w_i), float(kd), tf_s
