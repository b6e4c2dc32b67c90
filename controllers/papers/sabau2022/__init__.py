"""Sabau (Morar) (2022), PhD abstract: the published numbers, and every design of
the thesis done here on its identified models.

Units: the thesis states none.  As the ``coupled_servo_xy`` machine, positions are taken in mm and the
input in V, so eq. (1) reads ``omega_x/u_x = 1054/(s + 40.85)`` mm/s per V.  Every design
below works in mm, V and s (gains in V/mm, V/(mm/s), ...); :data:`MM_PER_M` converts to the
loops' SI units.  The choices the abstract leaves open are constants here, each with its
reason:

- :data:`DT_S`: 1 ms control period (the MC206X's default servo period).
- :data:`RELAY_DELAY_S`: a plain 1 ms loop cannot give the thesis's ultimate gain (see
  :func:`implied_delay`); 10 ms of drive delay does, for both axes.  The relay test itself
  (bundled scenario ``sabau2022_relay``: 1 V, 0.005 mm hysteresis) runs at the 0.1 ms physics
  step: at 1 ms its switching instants, hence Pu, come in whole milliseconds, and the twin and
  the TF loop settled on limit cycles 4 ms apart.
- The targets of each design (poles, weights, regions) are listed with it.

Designs return gains only; :mod:`controllers.registry` (``sabau2022``) wires them on the bus.
"""

from __future__ import annotations

import math
from functools import cache, lru_cache

import numpy as np

from controllers.design.pid import pid_tf
from controllers.design.statefeedback import (
    CascadeGains,
    axis_model,
    energy_weights,
    integral_augmented,
    lqr,
    mimo_model,
    p_p_cascade,
    pi_p_cascade,
    place,
)
from controllers.design.tuning import detune, ziegler_nichols
from controllers.lti import step_from_rest

AXES = ("x", "y")
#: Eqs. (1), (3): omega/u = K/(s + a): K = K_M/T_M (mm/(V s^2)), a = 1/T_M (1/s); and (K_M, T_M).
MODEL = {"x": (1054.0, 40.85), "y": (2188.0, 87.81)}
GAIN_TIME_CONSTANT = {"x": (25.8017, 0.0245), "y": (24.9174, 0.0114)}
#: Eq. (6): H_wx_uy (u_y into X's acceleration), H_wy_ux (u_x into Y's), mm/(V s^2).
CROSS = (15.0, 24.5)
MM_PER_M = 1e3
DT_S = 1e-3

#: Table 1: controller -> axis -> (2 % settling time s, overshoot %).
TABLE1 = {
    "P": {"x": (0.18, 20.0), "y": (0.1, 8.0)},
    "modified P": {"x": (0.25, 1.0), "y": (0.18, 0.0)},
    "PI": {"x": (0.3, 28.0), "y": (0.12, 36.0)},
    "modified PI": {"x": (0.6, 20.0), "y": (0.5, 19.0)},
    "PID": {"x": (0.22, 28.0), "y": (0.17, 25.0)},
    "modified PID": {"x": (0.81, 20.0), "y": (0.6, 21.0)},
}
#: Table 1's rows by the registry's design name.
TABLE1_ROWS = {
    "p": "P",
    "modified_p": "modified P",
    "pi": "PI",
    "modified_pi": "modified PI",
    "pid": "PID",
    "modified_pid": "modified PID",
}
#: Which of Table 1's numbers our reproduction meets by construction ("fitted") and which are
#: independent checks ("check"), per row and metric.  The P rows' overshoot fixes kp, so Ku, and
#: so the 10 ms relay delay (:func:`implied_delay`, rounded to 10 ms); an underdamped P loop on
#: K/(s(s + a)) settles in 8/a whatever kp, so the P rows' settling checks the identified model;
#: the modified rows detune one gain to the paper's overshoot (:func:`ziegler_nichols_gains`); PI and
#: PID follow from ZN's rules on the fitted relay and are checks.
TABLE1_AGREEMENT = {
    "p": {"overshoot": "fitted", "settling": "check"},
    "modified_p": {"overshoot": "fitted", "settling": "check"},
    "pi": {"overshoot": "check", "settling": "check"},
    "modified_pi": {"overshoot": "fitted", "settling": "check"},
    "pid": {"overshoot": "check", "settling": "check"},
    "modified_pid": {"overshoot": "fitted", "settling": "check"},
}
#: Eq. (14): kp + ki s^-lambda per axis.
EQ14 = {"x": (0.2229, 5.9392, 0.7792), "y": (0.3949, 10.0, 0.9733)}
#: The text's eq. (14) step responses: (nominal, lowest, highest) over the +-10 % box (s).
EQ14_RISE_S = {"x": (0.248, 0.227, 0.281), "y": (0.211, 0.19, 0.235)}
EQ14_SETTLING_S = {"x": (0.558, 0.496, 0.664), "y": (0.405, 0.363, 0.454)}
#: Eqs. (15)-(16): position PI kp + ki/s and speed P, per axis.
EQ15_16 = {"x": (1.339, 0.0063, 0.1548), "y": (0.429, 0.00064, 0.9205)}
#: The text: fractional controllers settle about 0.1 s faster than eqs. (15)-(16).
FRACTIONAL_FASTER_S = 0.1
#: Parameter box of section 5.3 (relative).
BOX = 0.10
#: Table 2: trajectory -> experiment (1-3) -> (fit X %, fit Y %).
TABLE2 = {
    "square L 3 cm": ((79.0, 76.0), (80.0, 80.0), (85.0, 86.4)),
    "square L 5 cm": ((82.0, 84.1), (84.5, 86.0), (86.0, 87.3)),
    "circle R 1 cm": ((92.0, 92.7), (93.2, 96.0), (99.7, 99.6)),
    "circle R 5 cm": ((93.0, 97.0), (95.0, 98.0), (99.8, 99.7)),
}
#: The text's claim for SISO state feedback against PID and cascade.
STATE_FEEDBACK_GAIN_PCT = 20.0

#: The relay experiment's drive delay (s); the relay itself is the bundled ``sabau2022_relay``.
RELAY_DELAY_S = 0.01
#: ZN's derivative is filtered with Td/N, N = 10 (the usual choice; the ideal one is improper).
DERIVATIVE_FILTER_N = 10.0
#: Part 2's cascade rules: the speed loop's pole at SPEED_LOOP_FACTOR * a; position P for a
#: critically damped outer loop; PI corner a decade below it; PID derivative kd = kp/omega_v.
SPEED_LOOP_FACTOR = 5.0
#: Part 3: closed-loop poles of the SISO and MIMO state feedback (1/s): zeta ~ 1.01, 2 %
#: settling about 0.1 s; part 5 adds the integral state's pole.
POLES = (-50.0, -70.0)
INTEGRAL_POLE = -25.0
#: Part 8: settling <= 0.2 s (strip alpha = 4/0.2), damping >= 0.9 (overshoot < 0.2 %), |s| < 300.
LMI_SETTLING_S, LMI_DAMPING, LMI_RADIUS = 0.2, 0.9, 300.0
#: Part 6: Oustaloup band (rad/s) and order for eq. (14)'s s^-lambda: within 0.6 deg and 0.05 dB
#: of s^-lambda over 0.1-100 rad/s, where the loop's dynamics lie (crossover near 60 rad/s,
#: settling in 1-2 s); a band of 1e-2..1e3 rad/s was 4.4 deg off at its inner edges.
OUSTALOUP_BAND, OUSTALOUP_ORDER = (1e-3, 1e4), 5


def model(axis: str):
    """Eq. (5) of ``axis`` as ``(A, B, C)`` (mm, V)."""
    return axis_model(*MODEL[axis])


def plant_tf(axis: str):
    """``K/(s (s + a))`` in mm/V as a python-control transfer function."""
    import control

    K, a = MODEL[axis]
    return control.tf([K], [1.0, a, 0.0])


def implied_delay(axis: str) -> dict:
    """What Table 1's P row implies for the relay test, in closed form.

    ZN's P is ``0.5 Ku``; a P loop on ``K/(s(s + a))`` with overshoot OS has
    ``zeta = -ln(OS)/sqrt(pi^2 + ln(OS)^2)``, ``omega_n = a/(2 zeta)`` and ``kp = omega_n^2/K``.
    So ``Ku = 2 kp``; the loop ``Ku G e^(-s tau)`` oscillates where ``|G| = 1/Ku``, which gives
    the delay ``tau = (pi/2 - atan(omega_u/a))/omega_u`` and ``Pu = 2 pi/omega_u``.
    """
    K, a = MODEL[axis]
    ln_os = math.log(TABLE1["P"][axis][1] / 100.0)
    zeta = -ln_os / math.hypot(math.pi, ln_os)
    kp = (a / (2 * zeta)) ** 2 / K
    ku = 2 * kp
    w = math.sqrt((-a * a + math.sqrt(a**4 + 4 * (K * ku) ** 2)) / 2)
    return {
        "kp_V_per_mm": kp,
        "ku_V_per_mm": ku,
        "wu_rad_s": w,
        "pu_s": 2 * math.pi / w,
        "delay_s": (math.pi / 2 - math.atan(w / a)) / w,
    }


def ultimate_point(axis: str, delay_s: float = RELAY_DELAY_S, dt: float = DT_S) -> tuple[float, float]:
    """Exact ``(Ku V/mm, Pu s)`` of the sampled loop the relay test runs: the plant's ZOH
    discretization at ``dt`` and ``delay_s`` of drive delay, at the first frequency where the
    loop's phase reaches -180 deg (bracketed on a grid, refined with scipy's ``brentq``)."""
    import control
    from scipy.optimize import brentq

    G = control.c2d(plant_tf(axis), dt, "zoh")
    n = round(delay_s / dt)

    def loop(w):
        return G(np.exp(1j * w * dt)) * np.exp(-1j * w * n * dt)

    w = np.linspace(1e-3, math.pi / dt * (1 - 1e-6), 20000)
    phase = np.unwrap(np.angle(loop(w)))
    i = int(np.argmax(phase <= -math.pi))
    wu = brentq(lambda v: loop(v).imag, w[i - 1], w[i], xtol=1e-12)
    return float(1.0 / abs(loop(wu))), float(2 * math.pi / wu)


def derivative_filter_s(kp: float, kd: float) -> float:
    """The derivative filter's time constant Td/N (s), ``Td = kd/kp``; 0 without a derivative."""
    return kd / kp / DERIVATIVE_FILTER_N if kd else 0.0


def continuous_step(closed_loop, horizon_s: float = 3.0, n: int = 6001) -> tuple[np.ndarray, np.ndarray]:
    """``(t_s, y)`` of the unit step response of a continuous python-control model
    (:func:`controllers.lti.step_from_rest`)."""
    t = np.linspace(0.0, horizon_s, n)
    return t, step_from_rest(closed_loop, dt=t[1], n=n)


def overshoot_pct(closed_loop, horizon_s: float = 3.0) -> float:
    """Overshoot (%) of a unit step response over ``horizon_s``."""
    _, y = continuous_step(closed_loop, horizon_s)
    return max(0.0, (float(y.max()) - 1.0) * 100.0)


@cache
def ziegler_nichols_gains(axis: str, ku: float, pu_s: float) -> dict:
    """Table 1's three ZN controllers and their "modified" versions (V/mm, V/(mm s), V s/mm).

    The modification keeps the structure and detunes one gain until the overshoot on the
    model (eqs. 1-2, continuous) reaches the thesis's modified row: kp for P, ki for PI and PID
    (a longer integral time; lowering kp of a PI on an integrating plant raises its overshoot).
    The thesis's modified overshoots are used as targets here; its settling times are what
    the comparison checks.
    """
    import control

    G = plant_tf(axis)
    out = {}
    for kind in ("P", "PI", "PID"):
        kp, ki, kd = ziegler_nichols(ku, pu_s, kind)
        out[kind] = (kp, ki, kd)
        target = TABLE1[f"modified {kind}"][axis][1]
        if kind == "P":
            c = detune(lambda f, kp=kp: overshoot_pct(control.feedback(f * kp * G, 1)), max(target, 0.05))
            out[f"modified {kind}"] = (c * kp, 0.0, 0.0)
        else:
            c = detune(
                lambda f, kp=kp, ki=ki, kd=kd: overshoot_pct(
                    control.feedback(pid_tf(kp, f * ki, kd, derivative_filter_s(kp, kd)).to_control() * G, 1), 6.0
                ),
                target,
            )
            out[f"modified {kind}"] = (kp, c * ki, kd)
    return out


def cascade_rules(axis: str) -> dict:
    """Part 2's cascades with a P speed loop (gains per the rules of :data:`SPEED_LOOP_FACTOR`).

    Returns
    -------
    dict
        ``"P-P"``, ``"PI-P"``, ``"P-PID"`` -> ``(kp 1/s, ki 1/s^2, kd -, kv V/(mm/s))``.
    """
    K, a = MODEL[axis]
    w_v = SPEED_LOOP_FACTOR * a
    kv = (w_v - a) / K
    kp = w_v / 4.0
    ki = kp * kp / 10.0
    return {"P-P": (kp, 0.0, 0.0, kv), "PI-P": (kp, ki, 0.0, kv), "P-PID": (kp, ki, kp / w_v, kv)}


@cache
def state_feedback(axis: str, design: str) -> CascadeGains:
    """Parts 3-5 and 8 on one axis: the state feedback and the cascade equal to it.

    ``design``: ``pole_placement`` (:data:`POLES`), ``lqr_classical`` (Q = C'C = diag(0, 1),
    R = 1), ``lqr_energy`` (eqs. 7-9, see :func:`energy_inertia_stiffness`, R = 1), ``lmi``
    (:func:`lmi_region`); with the integral state of eq. (10): ``pi_p_pole_placement``
    (:data:`POLES` + :data:`INTEGRAL_POLE`), ``pi_p_lqr`` (the energy weights, the integral
    state weighted as ``k (omega_n/5)^2``), ``pi_p_lmi``.
    """
    A, B, C = model(axis)
    Aa, Ba = integral_augmented(A, B, C)
    if design == "pole_placement":
        return p_p_cascade(place(A, B, POLES))
    if design == "lqr_classical":
        return p_p_cascade(lqr(A, B, C.T @ C, 1.0))
    if design == "lqr_energy":
        return p_p_cascade(lqr(A, B, energy_weights(*energy_inertia_stiffness(axis)), 1.0))
    if design == "lmi":
        return p_p_cascade(_lmi(A, B))
    if design == "pi_p_pole_placement":
        return pi_p_cascade(place(Aa, Ba, (*POLES, INTEGRAL_POLE)))
    if design == "pi_p_lqr":
        J, k = energy_inertia_stiffness(axis)
        wn = math.sqrt(POLES[0] * POLES[1])
        return pi_p_cascade(lqr(Aa, Ba, np.diag([J, k, k * (wn / 5.0) ** 2]), 1.0))
    if design == "pi_p_lmi":
        return pi_p_cascade(_lmi(Aa, Ba))
    raise ValueError(f"design = {design!r}: not a state-feedback design")


def energy_inertia_stiffness(axis: str) -> tuple[float, float]:
    """``(J, k)`` of eqs. (7)-(9) for the identified model (the text does not say).

    Eq. (1) written as a mechanism driven by u: ``J omega' + b omega = u`` with
    ``J = T_M/K_M`` (V per mm/s^2) and ``b = 1/K_M``.  The model has no spring; ``k`` is taken
    as the stiffness that puts the natural frequency ``sqrt(k/J)`` at the state feedback's
    bandwidth ``omega_n = sqrt(50 * 70)`` rad/s (:data:`POLES`), ``k = J omega_n^2`` (V/mm), so
    kinetic and potential energy weigh equally at that frequency.
    """
    K, _a = MODEL[axis]
    J = 1.0 / K  # T_M/K_M = (1/a)/(K/a) = 1/K
    return J, J * POLES[0] * POLES[1]


def lmi_region():
    """Part 8's region: strip for :data:`LMI_SETTLING_S`, cone :data:`LMI_DAMPING`, disc."""
    from controllers.design.lmi import PoleRegion

    return PoleRegion(4.0 / LMI_SETTLING_S, LMI_DAMPING, LMI_RADIUS)


def _lmi(A, B):
    from controllers.design.lmi import region_state_feedback

    return region_state_feedback(A, B, lmi_region())


@lru_cache(maxsize=1)
def mimo_pole_placement() -> tuple[np.ndarray, np.ndarray]:
    """Part 3, MIMO: ``K`` (2 x 4, V per mm/s and mm) placing eq. (6)'s poles at
    :data:`POLES` on both axes, and the reference gain ``N = -(C (A - B K)^-1 B)^-1`` for unit
    static gain: ``u = N r - K x``."""
    (kx, ax), (ky, ay) = MODEL["x"], MODEL["y"]
    A, B, C = mimo_model((kx, ky), (ax, ay), CROSS)
    K = place(A, B, POLES + POLES)
    N = -np.linalg.inv(C @ np.linalg.solve(A - B @ K, B))
    return K, N


def fractional_pi_state_space(axis: str):
    """Eq. (14) on ``axis`` realized by Oustaloup (:data:`OUSTALOUP_BAND`, order
    :data:`OUSTALOUP_ORDER`), V/mm, as ``(A, B, C, D)``."""
    from controllers.design.fractional import fractional_pi

    kp, ki, lam = EQ14[axis]
    wb, wh = OUSTALOUP_BAND
    return fractional_pi(kp, ki, lam, wb=wb, wh=wh, order=OUSTALOUP_ORDER)


#: Designs the ``sabau2022`` registry entry builds, with what each is.
DESIGNS = {
    "p": "Ziegler-Nichols P from the ultimate point (Table 1)",
    "pi": "Ziegler-Nichols PI",
    "pid": "Ziegler-Nichols PID (derivative filter Td/10)",
    "modified_p": "ZN P detuned to Table 1's modified overshoot",
    "modified_pi": "ZN PI, ki detuned likewise",
    "modified_pid": "ZN PID, ki detuned likewise",
    "p_p": "cascade P position / P speed (part 2's rules)",
    "pi_p": "cascade PI position / P speed",
    "p_pid": "cascade PID position / P speed",
    "pole_placement": "state feedback, poles -50 and -70 rad/s, run as the P-P cascade",
    "lqr_classical": "LQR Q = diag(0, 1), R = 1, as the P-P cascade",
    "lqr_energy": "LQR Q = diag(J, k) of eqs. (7)-(9), R = 1, as the P-P cascade",
    "lmi": "state feedback in the LMI region (settling <= 0.2 s, damping >= 0.9), as the P-P cascade",
    "pi_p_pole_placement": "integral state feedback (eq. 10), poles -50, -70, -25, as PI-P + feedforward",
    "pi_p_lqr": "integral state feedback by LQR, as PI-P + feedforward",
    "pi_p_lmi": "integral state feedback in the LMI region, as PI-P + feedforward",
    "fo_pi": "eq. (14) fractional PI on the error, Oustaloup 1e-3..1e4 rad/s, order 5",
    "mu_cascade": "eqs. (15)-(16): position PI / speed P from structured mu",
    "state_feedback_mimo": "MIMO state feedback on eq. (6), poles -50, -70 on each axis (both axes)",
}


@cache
def design_gains(axis: str, design: str, ku: float | None = None, pu_s: float | None = None) -> dict:
    """The gains of a per-axis ``design`` (a key of :data:`DESIGNS`, not the MIMO one), mm units.

    Returns
    -------
    dict
        ``form``: ``"pid"`` with ``kp, ki, kd`` (V/mm, V/(mm s), V s/mm) on the error;
        ``"cascade"`` with ``kp, ki, kd`` of the position controller (1/s, 1/s^2, -), ``kv``
        (V/(mm/s)) and ``position_ref_ff`` (1/s); both with ``tf_s``, the derivative filter
        (:func:`derivative_filter_s`); ``"fo_pi"`` (eq. 14, see
        :func:`fractional_pi_state_space`).  ``ku``, ``pu_s`` (V/mm, s) feed the ZN designs;
        default :func:`ultimate_point`.
    """
    if design in TABLE1_ROWS:
        if ku is None or pu_s is None:
            ku, pu_s = ultimate_point(axis)
        kp, ki, kd = ziegler_nichols_gains(axis, ku, pu_s)[TABLE1_ROWS[design]]
        return {"form": "pid", "kp": kp, "ki": ki, "kd": kd, "tf_s": derivative_filter_s(kp, kd)}
    if design in ("p_p", "pi_p", "p_pid"):
        kp, ki, kd, kv = cascade_rules(axis)[design.upper().replace("_", "-")]
        return {
            "form": "cascade",
            "kp": kp,
            "ki": ki,
            "kd": kd,
            "kv": kv,
            "position_ref_ff": 0.0,
            "tf_s": derivative_filter_s(kp, kd),
        }
    if design == "mu_cascade":
        kp, ki, kv = EQ15_16[axis]
        return {"form": "cascade", "kp": kp, "ki": ki, "kd": 0.0, "kv": kv, "position_ref_ff": 0.0, "tf_s": 0.0}
    if design == "fo_pi":
        return {"form": "fo_pi"}
    if design in DESIGNS and design != "state_feedback_mimo":
        g = state_feedback(axis, design)
        return {
            "form": "cascade",
            "kp": g.kp,
            "ki": g.ki,
            "kd": 0.0,
            "kv": g.kv,
            "position_ref_ff": g.kr / g.kv,
            "tf_s": 0.0,
        }
    raise ValueError(f"design = {design!r}: use one of {', '.join(DESIGNS)}")
