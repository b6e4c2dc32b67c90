"""State feedback for the servo axis of Sabau 2022 and its mapping to the cascade a drive allows.

The axis model is eq. (5) of Sabau (2022): states ``x = [omega, theta]`` (speed, position),
``omega' = -omega/T + (K/T) u``, ``theta' = omega``, ``y = theta``.  A state feedback
``u = -k_omega omega - k_theta theta + k_theta r`` is exactly the P-P cascade
``u = k_omega (kp (r - theta) - omega)`` with ``kp = k_theta/k_omega``: that is how a drive that
only allows a P speed loop (the MC206X) runs it.  Augmented with the integral of the position
error (eq. 10, ``z' = theta - r``), ``u = -k_omega omega - k_theta theta - k_z z`` is the PI-P
cascade ``u = k_omega (kp e + ki integral(e) - omega) - k_theta r`` with ``kp = k_theta/k_omega``,
``ki = k_z/k_omega``: the last term is the feedforward that removes the cascade's transmission
zero at ``s = -ki/kp``.  Gains come from python-control's ``place``/``acker`` and ``lqr``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


def axis_model(gain: float, pole: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Eq. (5) as ``(A, B, C)`` for ``omega/u = gain/(s + pole)``, ``theta = omega/s``.

    Parameters
    ----------
    gain : float
        K/T (position unit per V s^2, for example mm/(V s^2)).
    pole : float
        1/T (1/s).
    """
    return np.array([[-pole, 0.0], [1.0, 0.0]]), np.array([[gain], [0.0]]), np.array([[0.0, 1.0]])


def mimo_model(gains, poles, cross) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Eq. (6): states ``[omega_x, theta_x, omega_y, theta_y]``, inputs ``[u_x, u_y]``.

    ``cross = (H_wx_uy, H_wy_ux)``: u_y's acceleration of X and u_x's of Y (as ``gains``).
    """
    (kx, ky), (ax, ay), (hxy, hyx) = gains, poles, cross
    A = np.zeros((4, 4))
    A[0, 0], A[1, 0], A[2, 2], A[3, 2] = -ax, 1.0, -ay, 1.0
    B = np.array([[kx, hxy], [0.0, 0.0], [hyx, ky], [0.0, 0.0]])
    C = np.array([[0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0]])
    return A, B, C


def integral_augmented(A: np.ndarray, B: np.ndarray, C: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Eq. (10): the model with the integral of each output, ``z' = y`` (``- r`` in the servo)."""
    n, m = A.shape[0], C.shape[0]
    Aa = np.block([[A, np.zeros((n, m))], [C, np.zeros((m, m))]])
    return Aa, np.vstack([B, np.zeros((m, B.shape[1]))])


def place(A: np.ndarray, B: np.ndarray, poles) -> np.ndarray:
    """Gain K with ``eig(A - B K) = poles`` (python-control: ``acker`` for one input, which
    allows repeated poles, else ``place``)."""
    import control

    poles = np.asarray(poles)
    K = control.acker(A, B, poles) if B.shape[1] == 1 else control.place(A, B, poles)
    return np.atleast_2d(np.asarray(K, float))


def lqr(A: np.ndarray, B: np.ndarray, Q, R) -> np.ndarray:
    """LQR gain minimizing ``integral(x' Q x + u' R u)`` (python-control ``lqr``)."""
    import control

    K, _, _ = control.lqr(A, B, np.atleast_2d(Q), np.atleast_2d(R))
    return np.atleast_2d(np.asarray(K, float))


def energy_weights(inertia: float, stiffness: float) -> np.ndarray:
    """Eqs. (7)-(9): ``Q = diag(J, k)``, so that ``x' Q x = 2 E`` with
    ``E = (J omega^2 + k theta^2)/2`` for the states ``[omega, theta]``."""
    return np.diag([inertia, stiffness])


@dataclass
class CascadeGains:
    """A cascade equal to a state feedback on one axis: position ``kp`` (1/s), ``ki`` (1/s^2),
    speed ``kv`` (V per speed unit) and the reference feedforward ``kr`` (V per position
    unit, added to u): ``u = kv (kp e + ki integral(e) - omega) + kr r``."""

    kp: float
    ki: float
    kv: float
    kr: float


def p_p_cascade(K) -> CascadeGains:
    """The P-P cascade of ``u = -k_omega omega - k_theta theta + k_theta r`` (``K = [k_omega, k_theta]``):
    ``kp = k_theta/k_omega``, ``kv = k_omega``, no feedforward."""
    k_omega, k_theta = np.ravel(K)[:2]
    return CascadeGains(float(k_theta / k_omega), 0.0, float(k_omega), 0.0)


def pi_p_cascade(K) -> CascadeGains:
    """The PI-P cascade of the integral-augmented feedback ``K = [k_omega, k_theta, k_z]``
    (``u = -K [omega, theta, z]``, ``z' = theta - r``): ``kp = k_theta/k_omega``,
    ``ki = k_z/k_omega``, ``kv = k_omega`` and the feedforward ``kr = -k_theta``."""
    k_omega, k_theta, k_z = np.ravel(K)[:3]
    return CascadeGains(float(k_theta / k_omega), float(k_z / k_omega), float(k_omega), float(-k_theta))
