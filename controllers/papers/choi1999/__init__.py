"""Choi, Hong, Kim, Kim (1999): the MIMO H-infinity loop-shaping controller, the SISO
PID it is compared with, and the uncertain model of its mu analysis, designed here.

- Design model: eq. (11)'s 4-state plant (:func:`cutting_coupled_plant`)
  at Table 1's nominal values, up milling ``k_il = -2500``, ``k_c = 2500`` N s/m, and the
  machine's input gain 98.2 N/V (assumed: the paper gives none).
- **Position unit of the design: mm** (assumption).  The paper gives no units; with the
  shaping weight ``Ws = diag(990, 660) (s + 110)/(s + 1500)`` the target loop crosses over at
  1.3 rad/s with positions in m, far beyond the 2 kHz sampling (7 kHz) in um, and at
  about 1000-1700 rad/s in mm, the only decade that gives a loop a 2 kHz controller can run.
  The controllers below are rescaled to SI (V per m of error).
- MIMO: :func:`controllers.design.ncf.loop_shaping` with ``gamma = 1.1 gamma_min``, order 8,
  balanced truncation (SLICOT AB09AD, square-root Schur method, through
  ``control.balred``) to 4, Tustin at 2 kHz.
- PID per axis (ours: the paper gives no PID gains): on the diagonal plant without the cross
  coupling (``k_c = 0``), by default the crossover and phase margin of the MIMO loop broken at
  that axis' input (:func:`controllers.design.pid.pid_for_crossover`, integral corner a decade
  below); or (``tuning = "mimo_diagonal"``) the crossover of the MIMO's diagonal loop with the
  MIMO controller's static gain as ``kp`` (:func:`controllers.design.pid.pid_for_crossover_with_kp`).
- Uncertainty (eqs. 10-12, Table 1): real ``delta`` on m_x, b_x, m_y, b_y, k_il (x and y
  equations) and k_c (x and y), the amplifier as input-multiplicative ``(s+600)/(s+2000)``,
  performance ``Wp = 2 (s + 100)/(s + 5)`` on the output sensitivity.  k_il and k_c enter
  both axes' equations with one delta each (a repeated real scalar); SLICOT AB13MD takes real
  blocks of size 1 only, so each appearance gets its own delta: the bound is then an upper
  bound for the paper's structure too (conservative).

Everything is computed on first use and cached: treat the results as read-only.
"""

from __future__ import annotations

import math
from functools import lru_cache
from typing import Any

import numpy as np

#: Table 1: nominal value and relative uncertainty (fraction).
TABLE1 = {
    "k_il": (-2500.0, 1.10),
    "k_c": (2500.0, 1.10),
    "m_x": (52.3, 0.30),
    "m_y": (17.0, 0.40),
    "b_x": (193.5, 0.20),
    "b_y": (36.0, 0.20),
}
INPUT_GAIN_N_PER_V = 98.2
#: Design model's position unit per metre (mm: see the module docstring).
POSITION_UNIT_PER_M = 1e3
WS_GAINS, WS_ZERO, WS_POLE = (990.0, 660.0), 110.0, 1500.0
AMPLIFIER_WEIGHT = ((1.0, 600.0), (1.0, 2000.0))  # (s + 600)/(s + 2000)
PERFORMANCE_WEIGHT = ((2.0, 200.0), (1.0, 5.0))  # 2 (s + 100)/(s + 5)
GAMMA_FACTOR, REDUCED_ORDER, DT_S = 1.1, 4, 5e-4
#: The paper's statements this reproduction compares with.
PAPER: dict[str, Any] = {
    "controller_order": 8,
    "reduced_order": 4,
    "k_il_range": (-5250.0, 250.0),
    "k_c_range": (-250.0, 5250.0),
    "air_cut_max_tracking_um": (6.0, 7.0),
    "cutting_max_contour_um": (36.0, 41.0),
    "robust_frequency_rad_s": 80.0,
    "performance_frequency_rad_s": 5.0,
}


def nominal_params() -> dict:
    """Table 1's nominal machine with the assumed input gain (SI)."""
    return {
        "m_x": TABLE1["m_x"][0],
        "m_y": TABLE1["m_y"][0],
        "b_x": TABLE1["b_x"][0],
        "b_y": TABLE1["b_y"][0],
        "k_x": INPUT_GAIN_N_PER_V,
        "k_y": INPUT_GAIN_N_PER_V,
    }


def cutting_coupled_plant(params: dict[str, float], k_il_N_s_per_m: float, k_c_N_s_per_m: float):
    """Choi 1999's coupled 4-state model with the average cutting force, eq. (11), as continuous
    state-space matrices ``(A, B, C, D)``.

    State ``[y_x, v_x, y_y, v_y]`` (m, m/s), inputs ``u_x, u_y`` (V), outputs the positions (m);
    A is eq. (11)'s (rows 2 and 4: ``(k_il - b_i)/m_i`` and ``-+k_c/m_i``), B takes the
    ``k_i/m_i`` input columns of eq. (11)'s B (the uncertainty channels are left out).
    """
    mx, my, bx, by = params["m_x"], params["m_y"], params["b_x"], params["b_y"]
    k_il, k_c = k_il_N_s_per_m, k_c_N_s_per_m
    A = [
        [0.0, 1.0, 0.0, 0.0],
        [0.0, (k_il - bx) / mx, 0.0, -k_c / mx],
        [0.0, 0.0, 0.0, 1.0],
        [0.0, k_c / my, 0.0, (k_il - by) / my],
    ]
    B = [[0.0, 0.0], [params["k_x"] / mx, 0.0], [0.0, 0.0], [0.0, params["k_y"] / my]]
    C = [[1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0]]
    return np.array(A), np.array(B), np.array(C), np.zeros((2, 2))


def design_plant(k_il: float = TABLE1["k_il"][0], k_c: float = TABLE1["k_c"][0], params: dict | None = None):
    """Eq. (11)'s plant, inputs V, outputs mm (the design unit)."""
    import control

    A, B, C, D = cutting_coupled_plant(params or nominal_params(), k_il, k_c)
    return control.ss(A, B, C * POSITION_UNIT_PER_M, D)


def plant_si(k_il: float = TABLE1["k_il"][0], k_c: float = TABLE1["k_c"][0], params: dict | None = None):
    """Eq. (11)'s plant, inputs V, outputs m: :func:`design_plant` scaled back to SI."""
    return design_plant(k_il, k_c, params) * (1.0 / POSITION_UNIT_PER_M)


def shaping_weight():
    """``Ws = diag(990, 660) (s + 110)/(s + 1500)``."""
    import control

    return control.append(*(control.tf([g, g * WS_ZERO], [1.0, WS_POLE]) for g in WS_GAINS))


@lru_cache(maxsize=1)
def mimo_design() -> dict:
    """The loop-shaping design and its reduction.

    Returns
    -------
    dict
        ``design`` (:class:`~controllers.design.ncf.LoopShapingDesign`, mm units), ``full`` and
        ``reduced`` controllers in SI (V/m, continuous), ``hankel`` (the full controller's
        Hankel singular values, V/mm) and ``dropped`` (those truncated).
    """
    import control

    from controllers.design.ncf import loop_shaping

    design = loop_shaping(design_plant(), shaping_weight(), GAMMA_FACTOR)
    full = control.ss(design.K)
    hankel = control.hsvd(full)
    reduced = control.balred(full, REDUCED_ORDER, method="truncate")
    return {
        "design": design,
        "full": full * POSITION_UNIT_PER_M,
        "reduced": reduced * POSITION_UNIT_PER_M,
        "hankel": np.asarray(hankel),
        "dropped": np.asarray(hankel[REDUCED_ORDER:]),
    }


def loop_margins_at_inputs(controller_si, k_il: float = TABLE1["k_il"][0], k_c: float = TABLE1["k_c"][0]) -> list:
    """Loop-at-a-time margins of ``K G`` broken at each plant input (the other loop closed),
    :class:`~controllers.design.loop_analysis.LoopMargins` per axis."""
    from controllers.design.loop_analysis import loop_margins
    from controllers.design.mimo import frequency_response, loop_at_input

    plant = plant_si(k_il, k_c)

    def broken(axis):
        return lambda w: loop_at_input(frequency_response(controller_si, w) @ frequency_response(plant, w), axis)

    return [loop_margins(broken(i), 1e-1, 1e5, 30_000) for i in range(2)]


#: The PID tunings (ours; the paper gives no PID gains): ``loop_at_input``, the crossover and
#: phase margin of the reduced MIMO loop broken at that axis' input; ``mimo_diagonal``, the
#: crossover of the MIMO controller's diagonal loop ``K_ii G_ii`` with ``kp = K_ii(0)``, the
#: MIMO controller's static gain (the paper's likely intent: a PID of "similar loop shape").
PID_TUNINGS = ("loop_at_input", "mimo_diagonal")


def _diagonal_plant(axis: str):
    """``G_ii(w)`` without the cross coupling (k_c = 0): k/(s (m s + b - k_il)), m/V."""
    p, k_il = nominal_params(), TABLE1["k_il"][0]

    def plant(w):
        s = 1j * np.asarray(w, float)
        return p[f"k_{axis}"] / (s * (p[f"m_{axis}"] * s + p[f"b_{axis}"] - k_il))

    return plant


def mimo_static_gain_V_per_m(order: str = "reduced") -> np.ndarray:
    """K(0) of the MIMO controller (2 x 2, V/m): finite, since Ws has no integrator."""
    import control

    return np.asarray(control.dcgain(mimo_design()[order]), float)


def mimo_diagonal_margins(order: str = "reduced") -> list:
    """Margins of each diagonal loop ``K_ii G_ii`` of the MIMO controller on the diagonal plant."""
    from controllers.design.loop_analysis import loop_margins
    from controllers.design.mimo import frequency_response

    K = mimo_design()[order]
    out = []
    for i, a in enumerate("xy"):
        plant = _diagonal_plant(a)
        out.append(
            loop_margins(
                lambda w, i=i, plant=plant: frequency_response(K, np.asarray(w, float))[:, i, i] * plant(w),
                1e-1,
                1e5,
                30_000,
            )
        )
    return out


def check_pid_tuning(tuning, ki_scale) -> None:
    """Raise ``ValueError`` unless ``tuning`` is one of :data:`PID_TUNINGS` and ``ki_scale`` a
    number from 0 to 1000."""
    if not (isinstance(tuning, str) and tuning in PID_TUNINGS):
        raise ValueError(f"tuning = {tuning!r}: use one of {', '.join(PID_TUNINGS)}")
    if not (isinstance(ki_scale, (int, float)) and not isinstance(ki_scale, bool) and 0 <= ki_scale <= 1e3):
        raise ValueError(f"ki_scale = {ki_scale!r}: must be a number from 0 to 1000")


@lru_cache(maxsize=4)
def pid_design(tuning: str = "loop_at_input", ki_scale: float = 1.0) -> dict:
    """Choi 1999's SISO comparison, designed here: one PID per axis on the diagonal plant (k_c = 0).

    Parameters
    ----------
    tuning : str
        One of :data:`PID_TUNINGS`.
    ki_scale : float
        Factor on the designed integral gain (1: as designed).

    Returns
    -------
    dict
        ``gains``: per axis ``(kp V/m, ki V/(m s), kd V s/m, tf_s s)``; ``targets``: the MIMO
        loop margins the tuning takes its crossover from; ``margins``: the PID loops' own.
    """
    from controllers.design.loop_analysis import loop_margins
    from controllers.design.pid import pid_for_crossover, pid_for_crossover_with_kp, pid_tf

    check_pid_tuning(tuning, ki_scale)
    if tuning == "loop_at_input":
        targets = loop_margins_at_inputs(mimo_design()["reduced"])
    else:
        targets = mimo_diagonal_margins()
        static = np.diag(mimo_static_gain_V_per_m())
    gains, margins = [], []
    for i, a in enumerate("xy"):
        plant = _diagonal_plant(a)
        if tuning == "loop_at_input":
            kp, ki, kd, tf_s = pid_for_crossover(plant, targets[i].w_pm, targets[i].pm_deg)
        else:
            kp, ki, kd, tf_s = pid_for_crossover_with_kp(plant, targets[i].w_pm, float(static[i]))
        gains.append((kp, ki * ki_scale, kd, tf_s))
        C = pid_tf(*gains[-1])
        margins.append(loop_margins(lambda w, C=C, plant=plant: C(1j * np.asarray(w)) * plant(w), 1e-1, 1e5, 30_000))
    return {"gains": gains, "targets": targets, "margins": margins}


def pid_controller_si(tuning: str = "loop_at_input", ki_scale: float = 1.0):
    """The two PIDs as one diagonal python-control model (V/m)."""
    import control

    from controllers.design.pid import pid_tf

    return control.append(*(pid_tf(*g).to_control() for g in pid_design(tuning, ki_scale)["gains"]))


def _first_order(coefficients) -> tuple[float, float, float, float]:
    """``(n1 s + n0)/(s + d0)`` as the scalar realization ``(a, b, c, d)``."""
    (n1, n0), (d1, d0) = coefficients
    n1, n0, d0 = n1 / d1, n0 / d1, d0 / d1
    return -d0, 1.0, n0 - n1 * d0, n1


def uncertain_plant(performance: bool):
    """Generalized plant of the mu analysis (eqs. 10-12, Figs. 4 and 5), positions in mm.

    Inputs ``[w (10), w_p (2, if performance), u (2, V)]``, outputs ``[z (10), z_p (2, if
    performance), e (2, mm)]`` with ``e = w_p - y`` the controller's input, so that the loop
    is ``P.lft(K)`` (positive feedback ``u = K e``).  The perturbation channels, each for
    ``|delta| <= 1``: ``m_x, b_x, k_il (x), k_c (x), m_y, b_y, k_il (y), k_c (y)`` (real) and the
    amplifiers ``a_x, a_y`` (complex, input multiplicative ``(s + 600)/(s + 2000)``); ``z_p``
    is ``Wp e``.  States: ``p_x, v_x, p_y, v_y`` (m, m/s), then the weights'.
    """
    import control

    p = nominal_params()
    (k_il, a_il), (k_c, a_c) = TABLE1["k_il"], TABLE1["k_c"]
    n_p = 2 if performance else 0
    n_x, n_w, n_u = 4 + 2 + n_p, 10, 2
    n_in, n_out = n_w + n_p + n_u, n_w + n_p + 2
    A, B = np.zeros((n_x, n_x)), np.zeros((n_x, n_in))
    C, D = np.zeros((n_out, n_x)), np.zeros((n_out, n_in))
    u0 = n_w + n_p  # first control input
    a_a, b_a, c_a, d_a = _first_order(AMPLIFIER_WEIGHT)
    for i, ax in enumerate("xy"):
        pos, vel, other = 2 * i, 2 * i + 1, 3 - 2 * i
        w_m, w_b, w_il, w_cc, w_amp = 4 * i, 4 * i + 1, 4 * i + 2, 4 * i + 3, 8 + i
        m, b, k, alpha_m = p[f"m_{ax}"], p[f"b_{ax}"], p[f"k_{ax}"], TABLE1[f"m_{ax}"][1]
        sign_c = -1.0 if ax == "x" else 1.0  # F_x has -k_c v_y, F_y has +k_c v_x
        # force before the mass LFT: F = (k_il - b) v +- k_c v_other - w_b + w_il +- w_c + k (u + w_a)
        F_x = {vel: k_il - b, other: sign_c * k_c}
        F_in = {w_b: -1.0, w_il: 1.0, w_cc: sign_c, w_amp: k, u0 + i: k}
        # mass LFT (eq. 10): z_m = F - alpha w_m, v' = z_m / m
        A[pos, vel] = 1.0
        for j, v in F_x.items():
            A[vel, j] = v / m
            C[w_m, j] = v
        for j, v in F_in.items():
            B[vel, j] = v / m
            D[w_m, j] = v
        B[vel, w_m], D[w_m, w_m] = -alpha_m / m, -alpha_m
        C[w_b, vel] = TABLE1[f"b_{ax}"][1] * b
        C[w_il, vel] = a_il * k_il
        C[w_cc, other] = a_c * k_c
        # amplifier weight: z_a = Wa u
        s_a = 4 + i
        A[s_a, s_a], B[s_a, u0 + i], C[w_amp, s_a], D[w_amp, u0 + i] = a_a, b_a, c_a, d_a
        # e = w_p - y (mm) and z_p = Wp e
        e_row = n_w + n_p + i
        C[e_row, pos] = -POSITION_UNIT_PER_M
        if performance:
            a_p, b_p, c_p, d_p = _first_order(PERFORMANCE_WEIGHT)
            s_p, w_p = 6 + i, n_w + i
            D[e_row, w_p] = 1.0
            A[s_p, pos], A[s_p, s_p], B[s_p, w_p] = -b_p * POSITION_UNIT_PER_M, a_p, b_p
            C[n_w + i, s_p], C[n_w + i, pos], D[n_w + i, w_p] = c_p, -d_p * POSITION_UNIT_PER_M, d_p
    return control.ss(A, B, C, D)


def robust_stability_structure() -> tuple[list, list]:
    """``nblock, itype`` of AB13MD for robust stability: 8 real scalars, 2 complex."""
    return [1] * 10, [1] * 8 + [2, 2]


def robust_performance_structure() -> tuple[list, list]:
    """Robust stability's structure plus the 2 x 2 complex performance block."""
    nblock, itype = robust_stability_structure()
    return [*nblock, 2], [*itype, 2]


def stable_range_claim() -> dict:
    """The paper's stated range of cutting-force gains (N s/m) and Table 1's box they come from."""
    (k_il, a1), (k_c, a2) = TABLE1["k_il"], TABLE1["k_c"]
    box = {
        "k_il": tuple(sorted((k_il * (1 - a1), k_il * (1 + a1)))),
        "k_c": tuple(sorted((k_c * (1 - a2), k_c * (1 + a2)))),
    }
    return {
        "paper": {"k_il": PAPER["k_il_range"], "k_c": PAPER["k_c_range"]},
        "table1_box": box,
        "agree": all(math.isclose(a, b) for key in box for a, b in zip(box[key], PAPER[f"{key}_range"])),
    }


def controller_si(kind: str, order: str = "reduced", tuning: str = "loop_at_input", ki_scale: float = 1.0):
    """The feedback controller ``kind`` (``"mimo"`` or ``"pid"``), continuous, V/m; the MIMO
    one ``order`` ``"reduced"`` (4 states) or ``"full"`` (8); the PID pair of ``tuning`` with
    ``ki_scale`` on its integral gains (:func:`pid_design`)."""
    if kind == "mimo":
        return mimo_design()[order]
    if kind == "pid":
        return pid_controller_si(tuning, ki_scale)
    raise ValueError(f"controller kind = {kind!r}: use 'mimo' or 'pid'")


def closed_loop_discrete(controller, k_il: float = 0.0, k_c: float = 0.0, dt: float = DT_S):
    """Reference (m) to position (m) of the sampled loop: eq. (11)'s plant (cutting gains
    ``k_il``, ``k_c``; 0 for an air cut) held by a ZOH, the controller by Tustin, at ``dt``."""
    import control

    plant = plant_si(k_il, k_c)
    loop = control.c2d(control.ss(plant), dt, "zoh") * control.c2d(control.ss(controller), dt, "tustin")
    return control.feedback(loop, np.eye(2))


@lru_cache(maxsize=8)
def zpetc_filters(kind: str, order: str = "reduced", tuning: str = "loop_at_input", ki_scale: float = 1.0) -> tuple:
    """The ZPETC of each axis' diagonal closed loop ``T_ii`` (air cut, k_il = k_c = 0): the
    reference is a motion command, the cutting force a disturbance the feedback rejects.

    Returns
    -------
    tuple of (Zpetc, (num, den))
        Per axis the filter and the loop it inverts (ascending powers of ``z^-1``).
    """
    import control

    from controllers.design.zpetc import zpetc

    T = closed_loop_discrete(controller_si(kind, order, tuning, ki_scale))
    out = []
    for i in range(2):
        tf = control.ss2tf(control.minreal(T[i, i], verbose=False))
        num, den = (np.atleast_1d(np.squeeze(c)) for c in (tf.num[0][0], tf.den[0][0]))
        num = np.concatenate([np.zeros(len(den) - len(num)), num])  # same length: ascending in z^-1
        out.append((zpetc(num / den[0], den / den[0]), (num / den[0], den / den[0])))
    return tuple(out)
