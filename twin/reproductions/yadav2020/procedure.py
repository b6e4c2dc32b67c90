"""``twin reproduce yadav2020``: Yadav 2020's design procedures and Table 2, three ways.

Source: Yadav, Pathak, Gaur (2020).  Everything here is
computed: the interval model from Table 1's box, Kharitonov and SM (eqs. 3-5, 30-35), the
robust PI from GM/PM (eqs. 6-19), IMC (eqs. 20-23, Table 3), the H-infinity synthesis and its
reduction (eqs. 24-29), Table 2 on the transfer functions and on the MuJoCo twin, and the
disturbance/noise runs of Figs. 11-13.  The paper's numbers (``PAPER``) are printed beside
ours, never used to compute them.

Interval model.  With D = p^2 m + n^2 Im and a = K1 K2 n / D (rad/(V s^2) of screw angle;
a p is in m/(V s^2)), the plant is G = a p / (s (s + a H2)) and the closed loop with
C = N/Dc has the characteristic polynomial s^2 Dc(s) + a (H2 s Dc(s) + p N(s)): every coefficient
is affine in a.  a is increasing in K1 and K2 and decreasing in m and Im (p, n, H2 fixed), so over
the box its extremes sit at two vertices and each coefficient's interval is exact at a_min or
a_max (monotonicity, not interval arithmetic).  ``tests/test_yadav2020.py`` checks this against all
16 vertices and random samples.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from dataclasses import dataclass
from functools import lru_cache
from typing import Any

import control
import numpy as np
from tqdm import tqdm

from controllers.blocks import error_feedback
from controllers.design.hinf import (
    central_controller,
    gamma_iteration,
    mixed_sensitivity_plant,
    reduce_balanced,
    shift_integrators,
)
from controllers.design.imc import imc_controller
from controllers.design.kharitonov import kharitonov_polynomials, robustly_stable, stability_margin_third_order
from controllers.design.robust_pi import design_robust_pi, worst_case_margins
from controllers.papers import yadav2020
from twin.disturbances.drive_input import VoltageStep
from twin.machines import build, get_machine
from twin.machines.cncmt import leadscrew_tf
from twin.metrics import step_metrics
from twin.references import Step
from twin.sim.drive import Encoder
from twin.sim.runner import simulate

#: The paper's published numbers, for side-by-side tables only.
PAPER: dict[str, Any] = {
    "pi": {"kp": 38.33, "ki": 45.65, "kp_per_ki": 0.84},
    "pi_interval": {"alpha1": 7.5, "alpha2": 115.0, "beta3": 273.9, "sm": 588.6},  # eq. (31)
    "imc_interval": {"alpha1": 9.5, "alpha2": 16.575, "beta3": 12.0, "sm": 145.46},  # eq. (33)
    "hinf_interval": {"alpha1": 13.0, "alpha2": 41.25, "beta3": 125.82, "sm": 410.43},  # eq. (35)
    "eq17": {"alpha1": 7.5, "c2_min": 3.0, "c3_max": 6.0},  # eq. (17): s^3 + 7.5 s^2 + 3 Kp s + 6 Ki
    "hinf_theta": 1.3794e-2,
    "table2": {  # Table 2: nominal (os %, st s, rt s) and uncertain bands (low, high)
        "robust_pi": {"nominal": (41.2, 0.88, 0.14), "band": ((32.8, 45.3), (0.77, 1.33), (0.123, 0.27))},
        "imc": {"nominal": (0.57, 5.84, 3.36), "band": ((0.12, 1.27), (4.1, 7.08), (2.56, 3.98))},
        "hinf": {"nominal": (6.3, 2.09, 1.12), "band": ((0.598, 10.9), (1.34, 2.32), (1.02, 1.74))},
    },
    "table3": [
        (0.1, 1.0, 10.0, -10.0, 0.4, 0.0),
        (1.0, 1.0, 1.0, -1.0, 4.0, 0.0),
        (10.0, 1.0, 0.1, -0.1, 40.0, 0.0),
    ],  # mu, xi, wn, pole, ST = 4/(xi wn), OS
}

#: The three controllers of Table 2, as published (Table 2's H-infinity row is the reduced eq. 29:
#: its nominal 6.3 % overshoot is the reduced controller's; the full eq. 28 gives about 4 %).
#: The paper's controllers as python-control models: eq. (28) and eq. (29).
HINF_EQ28, HINF_EQ29 = yadav2020.HINF.to_control(), yadav2020.HINF_REDUCED.to_control()
TABLE2_CONTROLLERS = {
    "robust_pi": yadav2020.ROBUST_PI.to_control(),
    "imc": yadav2020.IMC.to_control(),
    "hinf": HINF_EQ29,
}
BOX_SYMBOLS = ("K1", "K2", "m", "Im")
#: Step-response horizon (s) and sample period (s) of Table 2's runs.
HORIZON_S, DT_S = 12.0, 1e-4
#: Twin-vs-transfer-function tolerance: relative, with an absolute floor of 0.1 percentage point
#: on overshoot (sub-percent overshoots are set by the last digits of the response).
TWIN_TOL_REL, TWIN_TOL_OS_PP = 0.02, 0.1


# ---------------------------------------------------------------- interval model, Kharitonov


def plant_gain(params: dict[str, float]) -> float:
    """a = K1 K2 n / (p^2 m + n^2 Im) (1/(V s^2) on the screw angle; a p is in m/(V s^2))."""
    return (
        params["K1"] * params["K2"] * params["n"] / (params["p"] ** 2 * params["m"] + params["n"] ** 2 * params["Im"])
    )


def box_vertices(params: dict[str, float]) -> list[dict[str, float]]:
    """The 16 vertices of Table 1's box (K1, K2, m, Im), other parameters nominal."""
    boxes = get_machine("cncmt").parameters
    ranges: list[tuple[float, float]] = []
    for s in BOX_SYMBOLS:
        box = boxes[s].box
        if box is None:
            raise ValueError(f"cncmt's {s} has no uncertainty box")
        ranges.append(box)
    out = []
    for corner in itertools.product(*ranges):
        out.append({**params, **dict(zip(BOX_SYMBOLS, corner))})
    return out


def nominal_params() -> dict[str, float]:
    """Table 1's nominal values (with p = 0.05 m/rad, as eq. 2 needs)."""
    return get_machine("cncmt").resolve()


def gain_range(params: dict[str, float] | None = None) -> tuple[float, float]:
    """(a_min, a_max) over the box: a is monotone in each parameter, so two vertices bound it."""
    params = params or nominal_params()
    a = [plant_gain(v) for v in box_vertices(params)]
    return min(a), max(a)


def characteristic_coefficients(controller: control.TransferFunction, a: float, params: dict[str, float]) -> np.ndarray:
    """Closed-loop characteristic polynomial s^2 Dc + a (H2 s Dc + p N), highest power first."""
    num, den = (np.atleast_1d(np.squeeze(c)) for c in control.tfdata(controller))
    num, den = num / den[0], den / den[0]
    s2dc = np.polymul([1.0, 0.0, 0.0], den)
    rest = np.polyadd(np.polymul([params["H2"], 0.0], den), params["p"] * num)
    return np.polyadd(s2dc, a * rest)


def coefficient_interval(controller, params=None) -> tuple[np.ndarray, np.ndarray]:
    """Exact (lower, upper) bounds of the characteristic coefficients over the box."""
    params = params or nominal_params()
    ends = np.stack([characteristic_coefficients(controller, a, params) for a in gain_range(params)])
    return ends.min(axis=0), ends.max(axis=0)


def family_stable(controller, params=None, n: int = 2001) -> bool:
    """Whether every member of the actual one-parameter family (a over its range) is stable."""
    params = params or nominal_params()
    lo, hi = gain_range(params)
    return all(
        np.roots(characteristic_coefficients(controller, a, params)).real.max() < 0 for a in np.linspace(lo, hi, n)
    )


def interval_table() -> list[dict]:
    """Parts 1-2: alpha/beta of eqs. (31), (33), (35) from the box, SM, Kharitonov verdict."""
    rows = []
    for name, ctrl in {**TABLE2_CONTROLLERS, **our_controllers()}.items():
        lo, hi = coefficient_interval(ctrl)
        row: dict[str, Any] = {
            "controller": name,
            "lower": lo.tolist(),
            "upper": hi.tolist(),
            "kharitonov_stable": robustly_stable(lo, hi),
            "family_stable": family_stable(ctrl),
            "kharitonov": {k: v.tolist() for k, v in kharitonov_polynomials(lo, hi).items()},
        }
        if len(lo) == 4:
            row.update(alpha1=lo[1], alpha2=lo[2], beta3=hi[3], sm=stability_margin_third_order(lo, hi))
        published = OURS_BESIDE.get(name, name)
        row["source"] = "ours" if name in OURS_BESIDE else "paper"
        row["paper"] = PAPER[f"{'pi' if published == 'robust_pi' else published}_interval"]
        rows.append(row)
    return rows


# ---------------------------------------------------------------- designs


def robust_pi_designs() -> dict:
    """Part 3: eqs. (18)-(19) solved on the paper's eq. (17) coefficients and on the box's."""
    p = nominal_params()
    lo_a, hi_a = gain_range(p)
    eq17 = PAPER["eq17"]
    out: dict[str, Any] = {}
    for label, (a1, c2, c3) in {
        "eq17_coefficients": (eq17["alpha1"], eq17["c2_min"], eq17["c3_max"]),
        "box_coefficients": (lo_a * p["H2"], lo_a * p["p"], hi_a * p["p"]),
    }.items():
        d = design_robust_pi(a1, c2, c3, gm_db=10.0, pm_deg=60.0)
        # the true margins of the designed PI on the nominal plant (eq. 14 is empirical)
        gm, pm, _, _ = control.margin(_plant(p) * control.tf([d.kp, d.ki], [1.0, 0.0]))
        out[label] = {
            "alpha1": a1,
            "c2_min": c2,
            "c3_max": c3,
            "kp": d.kp,
            "ki": d.ki,
            "kp_per_ki": d.kp_per_ki,
            "eq11_15_margins": worst_case_margins(a1, c2 * d.kp, c3 * d.ki),
            "nominal_gm_db": float(20 * np.log10(gm)) if np.isfinite(gm) else float("inf"),
            "nominal_pm_deg": float(pm),
        }
    out["paper"] = PAPER["pi"]
    return out


def imc_design() -> dict:
    """Part 4: eq. (23) from mu = 1, lambda = 2 on eq. (2), and Table 3."""
    G = _plant(nominal_params())
    C = imc_controller(G, 1.0, 2)
    num, den = (np.squeeze(c) for c in control.tfdata(C))
    num, den = num / den[0], den / den[0]
    table3 = []
    for mu in (0.1, 1.0, 10.0):
        T = control.minreal(control.feedback(G * imc_controller(G, mu, 2), 1), verbose=False)
        wn, zeta, poles = control.damp(T, doprint=False)
        t = np.linspace(0.0, 20.0 * mu, 20001)
        m = step_metrics(t, control.step_response(T, T=t).outputs, final=1.0)
        table3.append(
            {
                "mu_s": mu,
                "damping": float(zeta[0]),
                "wn_rad_s": float(wn[0]),
                "pole": float(poles[0].real),
                "st_4_over_xi_wn_s": float(4.0 / (zeta[0] * wn[0])),
                "st_2pct_s": m["settling_time_s"],
                "overshoot_pct": m["overshoot_pct"],
            }
        )
    return {
        "num": num.tolist(),
        "den": den.tolist(),
        "paper_num": [0.21, 2.0],
        "paper_den": [1.0, 2.0],
        "reduction": "C = G^-1/((s+1)^2 - 1) = s(s+9.7)/(4.85 s(s+2)): the s at the origin cancels "
        "and 1/4.85 = 0.2062 is printed as 0.21",
        "table3": table3,
        "paper_table3": PAPER["table3"],
    }


def hinf_design(eps: float = 1e-6) -> dict:
    """Part 5: mixsyn with W1 = 20/(s+0.01), W2 = 1, W3 = 1/(s+0.1) on eq. (2), integrator shifted."""
    shifted, w3, opt, at_paper = _hinf_problem(eps)
    ours = our_controllers()
    # gamma cannot go below |W3 T| at s = 0, where the loop's T is 1 (integral action)
    loop_dc = shifted(0) * control.tf(opt.controller)(0)
    t_dc = loop_dc / (1 + loop_dc)
    reduced_at_paper = ours["hinf_ours_paper_gamma_reduced"]
    reduced_opt = ours["hinf_ours_optimal_reduced"]
    reduced_eq28 = reduce_balanced(HINF_EQ28, 1)
    w = np.logspace(-3, 3, 600)

    def sv_gap_db(full, red, w=w):
        """Largest |gain difference| (dB) between two SISO controllers over w, and where."""
        a = np.abs(control.frequency_response(full, w).magnitude).ravel()
        b = np.abs(control.frequency_response(red, w).magnitude).ravel()
        gap = np.abs(20 * np.log10(a / b))
        return float(gap.max()), float(w[gap.argmax()])

    def coeffs(tf):
        num, den = (np.squeeze(c) for c in control.tfdata(tf))
        return {"num": (num / den[0]).tolist(), "den": (den / den[0]).tolist()}

    gap_db, gap_at_rad_s = sv_gap_db(HINF_EQ28, HINF_EQ29)
    return {
        "integrator_shift_eps": eps,
        "gamma_opt": opt.gamma,
        "theta_opt": opt.theta,
        "iterations": opt.iterations,
        "gamma_bracket": [GAMMA_LO, GAMMA_HI],
        "gamma_rel_tol": GAMMA_TOL,
        "paper_theta": PAPER["hinf_theta"],
        "gamma_floor_W3T_at_dc": float(abs(w3(0) * t_dc)),
        "controller_opt": coeffs(control.tf(opt.controller)),
        "controller_at_paper_gamma": coeffs(at_paper),
        "paper_eq28": coeffs(HINF_EQ28),
        "reduced_opt": coeffs(reduced_opt),
        "reduced_at_paper_gamma": coeffs(reduced_at_paper),
        "reduced_eq28": coeffs(reduced_eq28),
        "paper_eq29": coeffs(HINF_EQ29),
        "sv_gap_eq28_vs_eq29_db": gap_db,
        "sv_gap_eq28_vs_eq29_at_rad_s": gap_at_rad_s,
        "sv_gap_eq28_vs_eq29_above_0p1_db": sv_gap_db(HINF_EQ28, HINF_EQ29, np.logspace(-1, 3, 400))[0],
        "sv_gap_opt_vs_reduced_db": sv_gap_db(control.tf(opt.controller), reduced_opt)[0],
    }


# ---------------------------------------------------------------- our designs as controllers

#: The gamma iteration's bracket and relative tolerance: the bisection count follows from them
#: (ceil(log2(ln(GAMMA_HI / GAMMA_LO) / ln(1 + GAMMA_TOL))) = 14), not from the paper's text.
GAMMA_HI, GAMMA_LO, GAMMA_TOL = 1e4, 1e-3, 1e-3
#: Which published controller each of ours stands beside in Table 2.
OURS_BESIDE = {
    "robust_pi_ours": "robust_pi",
    "imc_ours": "imc",
    "hinf_ours_paper_gamma": "hinf",
    "hinf_ours_paper_gamma_reduced": "hinf",
    "hinf_ours_optimal": "hinf",
    "hinf_ours_optimal_reduced": "hinf",
}


@lru_cache(maxsize=1)
def _hinf_problem(eps: float = 1e-6):
    """The mixed-sensitivity plant (W1 = 20/(s+0.01), W2 = 1, W3 = 1/(s+0.1), integrator shifted
    to -eps), its gamma iteration and the central controller at the paper's gamma."""
    s = control.tf("s")
    shifted = shift_integrators(_plant(nominal_params()), eps)
    w3 = 1 / (s + 0.1)
    P = mixed_sensitivity_plant(shifted, 20 / (s + 0.01), control.tf(1, 1), w3)
    opt = gamma_iteration(P, gamma_max=GAMMA_HI, gamma_min=GAMMA_LO, tol=GAMMA_TOL)
    at_paper = control.tf(central_controller(P, 1.0 / PAPER["hinf_theta"]))
    return shifted, w3, opt, at_paper


@lru_cache(maxsize=1)
def our_controllers() -> dict:
    """Table 2's controllers as our procedures compute them (python-control models): the robust
    PI of eqs. (18)-(19) on eq. (17)'s coefficients, unrounded; IMC from eq. (23) (mu = 1,
    lambda = 2); the H-infinity central controller at the paper's gamma and at the optimal one,
    each also balanced-truncated to first order as eq. (29) is."""
    eq17 = PAPER["eq17"]
    pi = design_robust_pi(eq17["alpha1"], eq17["c2_min"], eq17["c3_max"], gm_db=10.0, pm_deg=60.0)
    _, _, opt, at_paper = _hinf_problem()
    optimal = control.tf(opt.controller)
    return {
        "robust_pi_ours": control.tf([pi.kp, pi.ki], [1.0, 0.0]),
        "imc_ours": control.tf(imc_controller(_plant(nominal_params()), 1.0, 2)),
        "hinf_ours_paper_gamma": at_paper,
        "hinf_ours_paper_gamma_reduced": reduce_balanced(at_paper, 1),
        "hinf_ours_optimal": optimal,
        "hinf_ours_optimal_reduced": reduce_balanced(optimal, 1),
    }


# ---------------------------------------------------------------- Table 2


def _plant(params: dict[str, float]) -> control.TransferFunction:
    """Eq. (1) without the delay, as the cncmt machine builds it."""
    return leadscrew_tf(**{k: params[k] for k in ("K1", "K2", "m", "Im", "p", "n", "H2")}).to_control()


def _loop(controller, params: dict[str, float], delay_s: float):
    """Closed loop in state space (plant and controller each realized, then connected, so no
    high-order polynomial is formed), sampled at ``DT_S`` (exact for a step: ZOH), or at 1 ms
    with a z^-N delay."""
    G = _plant(params)
    if delay_s == 0.0:
        loop = control.feedback(control.ss(G) * control.ss(controller), 1)
        return control.c2d(loop, DT_S, "zoh"), DT_S, HORIZON_S
    dt = 1e-3
    delay = control.ss(control.tf([1.0], [1.0] + [0.0] * round(delay_s / dt), dt))
    open_loop = control.c2d(control.ss(G), dt, "zoh") * delay * control.c2d(control.ss(controller), dt, "tustin")
    return control.feedback(open_loop, 1), dt, 4 * HORIZON_S


def tf_step_series(controller, params: dict[str, float], delay_s: float = 0.0) -> tuple[np.ndarray, np.ndarray] | None:
    """Unit-step response ``(t_s, y_m)`` of the transfer-function loop; None when unstable.

    Without delay the continuous loop is sampled exactly every ``DT_S`` (ZOH of a step input is
    exact); with a delay it is the sampled-data loop at 1 ms (ZOH plant, Tustin controller,
    z^-N delay), in state space.  Stability without delay is read from the roots of the
    continuous characteristic polynomial: sampled at 0.1 ms, a closed-loop pole at -1e-6 rad/s
    (an H-infinity controller's zero beside the shifted integrator) sits within rounding of
    |z| = 1.
    """
    if delay_s == 0.0 and np.roots(characteristic_coefficients(controller, plant_gain(params), params)).real.max() >= 0:
        return None
    loop, dt, horizon = _loop(controller, params, delay_s)
    ss = control.ss(loop)
    if delay_s > 0.0 and np.abs(np.linalg.eigvals(ss.A)).max() >= 1.0:
        return None
    t = np.arange(round(horizon / dt)) * dt
    return t, sampled_step_response(ss.A, ss.B, ss.C, ss.D, n=len(t))


def sampled_step_response(A, B, C, D, *, n: int, block: int = 1024) -> np.ndarray:
    """Unit-step response of ``x[k+1] = A x[k] + B u[k], y = C x + D u`` (SISO), ``n`` samples
    from rest, in state space: the powers ``A^m`` of one block (``m < block``, by doubling) give
    its free response ``C A^m`` and its forced one ``C sum_{j<m} A^j B + D``; each block then
    starts from the state the last one left.  The transfer-function polynomial of a high-order
    loop sampled fast (poles clustered near z = 1, as with the H-infinity controllers) is too
    ill-conditioned to filter with."""
    A, B, C, D = (np.atleast_2d(np.asarray(m, float)) for m in (A, B, C, D))
    nx = A.shape[0]
    powers = np.eye(nx)[None]  # A^0 .. A^(k-1), doubled until a block is covered
    while len(powers) < block:
        powers = np.concatenate([powers, powers @ powers[-1] @ A])
    powers = powers[:block]
    free = (C @ powers)[:, 0, :]  # (block, nx): C A^m
    impulse = (free @ B)[:, 0]  # C A^m B
    forced = np.concatenate([[0.0], np.cumsum(impulse)[:-1]]) + D[0, 0]  # C sum_{j<m} A^j B + D
    step_block = powers[-1] @ A  # A^block
    carried = (powers @ B).sum(axis=0)  # sum_{j<block} A^j B
    y, x = np.empty(n), np.zeros((nx, 1))
    for start in range(0, n, block):
        stop = min(start + block, n)
        y[start:stop] = free[: stop - start] @ x[:, 0] + forced[: stop - start]
        x = step_block @ x + carried
    return y


def tf_step(controller, params: dict[str, float], delay_s: float = 0.0) -> dict | None:
    """Step metrics of :func:`tf_step_series`; None when unstable."""
    series = tf_step_series(controller, params, delay_s)
    return None if series is None else step_metrics(*series, final=1.0)


def twin_step_result(controller, params: dict[str, float]):
    """The MuJoCo cncmt twin closed by the controller at 10 kHz (Tustin), unit step."""
    return _twin_step(build("cncmt", {k: params[k] for k in BOX_SYMBOLS}), controller)


def _twin_step(machine, controller, **options):
    """``machine`` closed by ``controller`` at 10 kHz (Tustin), a unit step over
    :data:`HORIZON_S`, every tick recorded; ``options`` go to :func:`simulate` (disturbances,
    an encoder)."""
    return simulate(
        machine,
        error_feedback(controller, DT_S),
        Step(1.0),
        duration_s=HORIZON_S,
        control_period_s=DT_S,
        progress=False,
        record_every=1,
        **options,
    )


def twin_step(controller, params: dict[str, float]) -> dict:
    """Step metrics of :func:`twin_step_result`."""
    res = twin_step_result(controller, params)
    return step_metrics(res.t_s, res.table_position_m()[:, 0], final=1.0)


def _box_plan(spec: str, samples: int, seed: int = 0):
    """A :class:`twin.sampling.SamplePlan` varying K1, K2, m and Im of cncmt by ``spec``."""
    from twin.sampling import SamplePlan, parse_variation

    params = get_machine("cncmt").parameters
    return SamplePlan([parse_variation(f"overrides.{s}={spec}", params) for s in BOX_SYMBOLS], samples, seed)


def _plan_points(plan) -> list[dict[str, float]]:
    p = nominal_params()
    return [{**p, **{k.removeprefix("overrides."): v for k, v in plan.values(i).items()}} for i in range(len(plan))]


def paper_samples(n: int = 10) -> list[dict[str, float]]:
    """The paper's "10 uncertain samples between the lower and upper limit via nominal".

    Read as: all four parameters move together from their lower to their upper limit in n
    equal steps (nominal lies on that segment); the sweep machinery's ``line(n)`` spec.  The
    paper does not say more.
    """
    return _plan_points(_box_plan(f"line({n})", 1))


def random_samples(n: int, seed: int) -> list[dict[str, float]]:
    """n uniform samples of the box, seeded: the sweep machinery's ``box`` spec (each sample
    drawn from the seed and its index); none for n = 0."""
    return _plan_points(_box_plan("box", n, seed)) if n else []


KEYS = ("overshoot_pct", "settling_time_s", "rise_time_10_90_s", "rise_time_0_100_s")


def band(metrics: Sequence[dict | None]) -> dict:
    """(min, max) of each metric over samples (NaN where never reached); unstable count."""
    stable = [m for m in metrics if m is not None]
    out: dict[str, Any] = {}
    for k in KEYS:
        vals = np.array([m[k] for m in stable], float)
        out[k] = (float(np.nanmin(vals)), float(np.nanmax(vals))) if np.isfinite(vals).any() else None
    out["unstable"] = len(metrics) - len(stable)
    return out


@dataclass
class Table2:
    """Table 2 three ways: paper, transfer function, twin (nominal and bands)."""

    rows: dict
    mismatches: list[str]


def table2(mc_samples: int = 1000, twin_random: int = 20, seed: int = 0, progress: bool = True) -> Table2:
    """Part 6: nominal metrics and uncertain bands, on the TFs and on the twin, for the paper's
    printed controllers and for ours (:func:`our_controllers`).

    The paper's controllers run on the twin at nominal, the paper's 10 samples and
    ``twin_random`` random ones; ours at nominal (their bands come from the transfer functions).

    Parameters
    ----------
    mc_samples : int
        Dense Monte Carlo samples on the transfer functions.
    twin_random : int
        Random box samples run on the twin in addition to the paper's 10.
    seed : int
        Seed of both random sample sets.
    """
    nominal = nominal_params()
    paper_pts = paper_samples()
    mc = random_samples(mc_samples, seed)
    twin_pts = paper_pts + random_samples(twin_random, seed + 1)
    controllers = {**TABLE2_CONTROLLERS, **our_controllers()}
    rows, mismatches = {}, []
    total = len(TABLE2_CONTROLLERS) * (len(twin_pts) + 1) + len(controllers) - len(TABLE2_CONTROLLERS)
    with tqdm(total=total, desc="yadav2020 twin runs", unit="run", disable=not progress, leave=False) as bar:
        for name, ctrl in controllers.items():
            ours = name in OURS_BESIDE
            tf_nom, tf_delay = tf_step(ctrl, nominal), tf_step(ctrl, nominal, delay_s=0.1)
            twin_nom = None if tf_nom is None else twin_step(ctrl, nominal)  # an unstable loop: not run
            bar.update()
            tf_pts = [tf_step(ctrl, p) for p in (paper_pts if ours else twin_pts)]
            tw_pts = []
            for p in () if ours else twin_pts:
                tw_pts.append(twin_step(ctrl, p))
                bar.update()
            for label, a, b in [("nominal", tf_nom, twin_nom)] + [
                (f"sample {i}", x, y) for i, (x, y) in enumerate(zip(tf_pts, tw_pts))
            ]:
                if a is not None and b is not None:  # the twin is not run where the TF loop is unstable
                    mismatches += _twin_vs_tf_step(f"{name} {label}", b, a)
            rows[name] = {
                "source": "ours" if ours else "paper",
                "beside": OURS_BESIDE.get(name, name),
                "paper": PAPER["table2"][OURS_BESIDE.get(name, name)],
                "tf_nominal": tf_nom,
                "twin_nominal": twin_nom,
                "tf_nominal_with_0.1s_delay": tf_delay,
                "tf_paper_samples": band(tf_pts[: len(paper_pts)]),
                "twin_paper_samples": None if ours else band(tw_pts[: len(paper_pts)]),
                "tf_monte_carlo": band([tf_step(ctrl, p) for p in mc]),
                "twin_random_samples": band(tw_pts[len(paper_pts) :]) if twin_random and not ours else None,
                "mc_samples": mc_samples,
                "twin_random": 0 if ours else twin_random,
            }
    return Table2(rows, mismatches)


def _twin_vs_tf_step(label: str, twin: dict, tf: dict) -> list[str]:
    """Step metrics of the twin more than :data:`TWIN_TOL_REL` from the transfer function's
    (overshoot: :data:`TWIN_TOL_OS_PP` floor)."""
    out = []
    for k in KEYS:
        if k == "rise_time_0_100_s" and tf["overshoot_pct"] < TWIN_TOL_OS_PP:
            continue  # reaching 1.0 without overshoot is ill-conditioned (creeps in)
        tol = max(TWIN_TOL_REL * abs(tf[k]), TWIN_TOL_OS_PP if k == "overshoot_pct" else 0.0)
        both_never = np.isnan(tf[k]) and np.isnan(twin[k])  # e.g. 0-100 % rise never reached
        if not (both_never or abs(twin[k] - tf[k]) <= tol):
            out.append(f"{label} {k}: twin {twin[k]:.4g} vs tf {tf[k]:.4g}")
    return out


# ---------------------------------------------------------------- disturbance, noise, effort

#: Figs. 11-13 (pictures lost in the extraction): the twin's choices, stated in the README.
DISTURBANCE_V, DISTURBANCE_START_S, NOISE_STD_M, NOISE_SEED = 0.5, 6.0, 1e-3, 0


def disturbance_and_noise() -> dict:
    """Part 7 on the nominal twin: control effort of the step (Fig. 11), rejection of a
    ``DISTURBANCE_V`` input step at ``DISTURBANCE_START_S`` and of encoder noise of
    ``NOISE_STD_M`` (Figs. 12-13), as RMS and peak deviation from the clean run.
    """
    machine = build("cncmt")
    out: dict[str, Any] = {}
    for name, ctrl in TABLE2_CONTROLLERS.items():
        clean = _twin_step(machine, ctrl)
        dist = _twin_step(machine, ctrl, disturbances=[VoltageStep(DISTURBANCE_V, DISTURBANCE_START_S)])
        noisy = _twin_step(machine, ctrl, encoder=Encoder(np.zeros(1), np.full(1, NOISE_STD_M), np.ones(1), NOISE_SEED))
        y0 = clean.table_position_m()[:, 0]
        after = clean.t_s >= DISTURBANCE_START_S
        dev_d = dist.table_position_m()[:, 0] - y0
        dev_n = noisy.table_position_m()[:, 0] - y0
        out[name] = {
            "u_peak_V": float(np.abs(clean.u_V).max()),
            "u_rms_V": float(np.sqrt(np.mean(clean.u_V**2))),
            "disturbance_dev_rms_m": float(np.sqrt(np.mean(dev_d[after] ** 2))),
            "disturbance_dev_peak_m": float(np.abs(dev_d[after]).max()),
            "disturbance_dev_final_m": float(dev_d[-1]),
            "noise_dev_rms_m": float(np.sqrt(np.mean(dev_n**2))),
            "noise_u_rms_V": float(np.sqrt(np.mean((noisy.u_V - clean.u_V) ** 2))),
        }
    return out
