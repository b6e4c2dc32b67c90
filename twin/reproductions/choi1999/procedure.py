"""Choi, Hong, Kim, Kim (1999): the MIMO loop-shaping design, its reduction, the PID
comparison, the mu analysis beside sampled plants, ZPETC, and the circle tests.

Designs: :mod:`controllers.papers.choi1999` (positions in mm in the design, SI in the loops).
Transfer-function loops: :func:`twin.sim.tf_loop.tf_loop` on eq. (11)'s plant, the twin's
timing.  Twin runs: the bundled ``choi1999_{mimo,pid}_{air_cut,cutting}`` scenarios and
variants of them (average-force model; no friction and ideal encoders for the twin-vs-TF
comparison, where both models are the same linear loop).
"""

from __future__ import annotations

import copy
import itertools
import math
import tomllib
from functools import lru_cache
from typing import Any

import control
import numpy as np

from controllers import make_controller
from controllers.blocks import preview_ticks_needed
from controllers.design.hinf import gamma_iteration
from controllers.design.mimo import frequency_response
from controllers.design.mu import constant_upper_lft, destabilizing_scale, is_stable, mu_upper_bound
from controllers.design.ncf import ncf_generalized_plant, ncf_robustness_norm
from controllers.papers import choi1999 as s4
from controllers.papers.choi1999 import cutting_coupled_plant
from twin.metrics import contour_error
from twin.references import Circle
from twin.reproductions.base import twin_vs_tf

KINDS = ("mimo", "pid")
OMEGA = np.logspace(-1, 4, 121)  # rad/s, the mu plots' grid (Figs. 6-7)
SETTLED_S = 0.1  # the circle starts with a velocity step: errors also reported after it
REVERSAL_WINDOW_S = 0.05  # an axis' reversal error: the largest within 50 ms of its velocity's sign change
#: The controllers compared on the same circles: name -> (kind, registry parameters).  Every PID
#: is ours (the paper gives no gains): "loop at input" is the bundled choi1999_pid.
CONTROLLER_VARIANTS: dict[str, Any] = {
    "MIMO, order 4 (reduced)": ("mimo", {}),
    "MIMO, order 8 (full)": ("mimo", {"order": "full"}),
    "PID, loop at input": ("pid", {}),
    "PID, loop at input, ki / 100": ("pid", {"ki_scale": 0.01}),
    "PID, MIMO diagonal, kp = K(0)": ("pid", {"tuning": "mimo_diagonal"}),
    "PD, MIMO diagonal, kp = K(0)": ("pid", {"tuning": "mimo_diagonal", "ki_scale": 0.0}),
}
TWIN_TOL_REL = 0.02
#: average-force gains for the circle cuts: the paper's estimate |k| = 1800 N s/m, up milling
AVERAGE_FORCE: dict[str, Any] = {
    "type": "average_force",
    "k_il_N_s_per_m": -1800.0,
    "k_c_N_s_per_m": 1800.0,
    "harmonic_fraction": 0.2,
    "spindle_rpm": 10000.0,
    "n_flutes": 2,
}


def _controller_mm(kind: str):
    """The controller with the design's units (V/mm), continuous."""
    return control.ss(s4.controller_si(kind)) * (1.0 / s4.POSITION_UNIT_PER_M)


def design() -> dict:
    """Part 1 and 2: gamma_min two ways, the controller orders, the reduction and its effect."""
    d = s4.mimo_design()
    lsd = d["design"]
    A, B, C = lsd.shaped.A, lsd.shaped.B, lsd.shaped.C
    independent = gamma_iteration(
        ncf_generalized_plant(A, B, C), gamma_max=100.0, gamma_min=1.0 + 1e-6, tol=1e-7, ncon=2, nmeas=2
    ).gamma
    full, reduced = d["full"], d["reduced"]
    w = np.logspace(0, 4, 200)
    F, R = frequency_response(full, w), frequency_response(reduced, w)
    rel = max(np.linalg.norm(f - r, 2) / np.linalg.norm(f, 2) for f, r in zip(F, R))
    loops = {}
    theta = w * s4.DT_S
    for name, k in (("full", full), ("reduced", reduced)):
        cl = s4.closed_loop_discrete(k, s4.TABLE1["k_il"][0], s4.TABLE1["k_c"][0])
        # S = I - T for the unit feedback of the sampled loop
        peak = max(np.linalg.norm(np.eye(2) - cl(np.exp(1j * t)), 2) for t in theta[theta < math.pi])
        loops[name] = {
            "max_pole_abs": float(np.max(np.abs(cl.poles()))),
            "sensitivity_peak": float(peak),
            "order": int(control.ss(k).nstates),
        }
    margins = s4.loop_margins_at_inputs(reduced)
    return {
        "gamma_min": lsd.gamma_min,
        "gamma_min_sb10ad": independent,
        "gamma_min_rel_diff": abs(independent - lsd.gamma_min) / lsd.gamma_min,
        "gamma": lsd.gamma,
        "gamma_factor": s4.GAMMA_FACTOR,
        "margin": lsd.margin,
        "achieved_norm": ncf_robustness_norm(A, B, C, lsd.K_inf, omega=np.logspace(-1, 5, 600)),
        "shaped_order": int(lsd.shaped.nstates),
        "k_inf_order": int(lsd.K_inf.nstates),
        "order": loops["full"]["order"],
        "reduced_order": loops["reduced"]["order"],
        "hankel_V_per_mm": d["hankel"].tolist(),
        "dropped_V_per_mm": d["dropped"].tolist(),
        "truncation_bound_V_per_mm": float(2 * d["dropped"].sum()),
        "reduction_rel_error_1_to_1e4_rad_s": float(rel),
        "loops": loops,
        "loop_at_input": [{"pm_deg": m.pm_deg, "w_pm": m.w_pm, "gm_db": m.gm_db} for m in margins],
    }


def pid() -> dict:
    """Part 3: the PID pair, its targets and its own margins."""
    p = s4.pid_design()
    return {
        "gains": [dict(zip(("kp", "ki", "kd", "tf_s"), g)) for g in p["gains"]],
        "targets": [{"pm_deg": m.pm_deg, "w_pm": m.w_pm} for m in p["targets"]],
        "margins": [{"pm_deg": m.pm_deg, "w_pm": m.w_pm, "gm_db": m.gm_db} for m in p["margins"]],
    }


def _peak(values: np.ndarray, mask=None) -> dict:
    v = values if mask is None else np.where(mask, values, -np.inf)
    i = int(np.argmax(v))
    return {"value": float(values[i]), "w_rad_s": float(OMEGA[i])}


def _performance_norm(N_rp, delta, omega) -> float:
    """max over omega of sigma_max(Wp S) of the loop with the real perturbation ``delta``
    (the first 10 channels closed by constant ``delta``, the performance channel left)."""
    closed = constant_upper_lft(N_rp, delta)
    if closed is None:
        raise ValueError(f"the loop with delta = {delta} is ill-posed")
    sys = control.ss(*closed)
    return float(max(np.linalg.norm(m, 2) for m in frequency_response(sys, omega)))


def perturbation_loops(kind: str):
    """The loops the perturbations see with controller ``kind``: robust stability and robust
    performance (the uncertain plant closed by the controller, mm units)."""
    K = _controller_mm(kind)
    return (s4.uncertain_plant(False).lft(K, nu=2, ny=2), s4.uncertain_plant(True).lft(K, nu=2, ny=2))


@lru_cache(maxsize=2)
def mu_curves(kind: str) -> tuple[np.ndarray, np.ndarray]:
    """AB13MD upper bounds over :data:`OMEGA` for robust stability and robust performance."""
    N_rs, N_rp = perturbation_loops(kind)
    return (
        mu_upper_bound(N_rs, OMEGA, *s4.robust_stability_structure()),
        mu_upper_bound(N_rp, OMEGA, *s4.robust_performance_structure()),
    )


def mu_analysis(samples: int, seed: int) -> dict:
    """Part 4: mu upper bounds (RS, RP) over OMEGA, and sampled plants in the same box."""
    rng = np.random.default_rng(seed)
    corners = np.array(list(itertools.product((-1.0, 1.0), repeat=10)))
    randoms = rng.uniform(-1.0, 1.0, (samples, 10))
    coarse = np.logspace(-1, 4, 60)
    out: dict[str, Any] = {}
    for kind in KINDS:
        N_rs, N_rp = perturbation_loops(kind)
        rs, rp = mu_curves(kind)
        stable_corners = [is_stable(N_rs, c) for c in corners]
        stable_random = [is_stable(N_rs, d) for d in randoms]
        points = np.vstack([corners, randoms])
        stable = np.array(stable_corners + stable_random)
        worst_wps = max((_performance_norm(N_rp, d, coarse) for d in points[stable]), default=math.nan)
        directions = np.vstack([corners, randoms / np.max(np.abs(randoms), axis=1, keepdims=True)])
        scales = [destabilizing_scale(N_rs, d, 3.0) for d in directions]
        k_min = float(min(scales))
        nominal_wps = _performance_norm(N_rp, np.zeros(10), coarse)
        out[kind] = {
            "rs": rs.tolist(),
            "rp": rp.tolist(),
            "rs_peak": _peak(rs),
            "rs_peak_below_80": _peak(rs, s4.PAPER["robust_frequency_rad_s"] >= OMEGA),
            "rp_peak": _peak(rp),
            "rp_peak_below_5": _peak(rp, s4.PAPER["performance_frequency_rad_s"] >= OMEGA),
            "corners": len(corners),
            "corners_stable": int(sum(stable_corners)),
            "unstable_corners": [c.tolist() for c, ok in zip(corners, stable_corners) if not ok][:5],
            "random": samples,
            "random_stable": int(sum(stable_random)),
            "worst_wps_sampled": worst_wps,
            "nominal_wps": nominal_wps,
            "min_destabilizing_scale": k_min,
            "mu_lower_from_samples": 1.0 / k_min if k_min > 0 else math.inf,
        }
    out["omega_rad_s"] = OMEGA.tolist()
    out["claim"] = s4.stable_range_claim()
    out["claim_grid"] = _claim_grid()
    return out


def _claim_grid(n: int = 11) -> dict:
    """The paper's range claim on an n x n grid of (k_il, k_c) with every corner of m and b,
    nominal amplifier: stable everywhere? (reduced MIMO and PID, the TF models)."""
    box = s4.stable_range_claim()["table1_box"]
    out: dict[str, Any] = {}
    for kind in KINDS:
        K = s4.controller_si(kind)
        unstable = []
        (il_lo, il_hi), (c_lo, c_hi) = box["k_il"], box["k_c"]
        for k_il, k_c in itertools.product(np.linspace(il_lo, il_hi, n), np.linspace(c_lo, c_hi, n)):
            for signs in itertools.product((-1.0, 1.0), repeat=4):
                p = s4.nominal_params()
                for key, sg in zip(("m_x", "m_y", "b_x", "b_y"), signs):
                    p[key] *= 1.0 + sg * s4.TABLE1[key][1]
                cl = control.feedback(s4.plant_si(k_il, k_c, p) * control.ss(K), np.eye(2))
                if np.max(cl.poles().real) >= 0:
                    unstable.append((float(k_il), float(k_c), signs))
        out[kind] = {"points": n * n * 16, "unstable": len(unstable), "first_unstable": unstable[:3]}
    return out


def circle_reference(radius_mm: float, feed_mm_per_min: float, duration_s: float, preview: int) -> np.ndarray:
    """The circle sampled at the control period, ``preview`` rows beyond the run."""
    n = round(duration_s / s4.DT_S)
    return Circle(radius_mm, feed_mm_per_min).sample(np.arange(n + preview) * s4.DT_S)


def _errors(t_s, ref_xy, pos_xy, *, u_V, ref_vel_xy=None) -> dict:
    """Max tracking error per axis (all, and after SETTLED_S), contour errors to the path and to
    the reference point of the same instant, max |u| per axis (um, V); with the reference
    velocity, also the largest tracking error per axis within :data:`REVERSAL_WINDOW_S` of that
    axis' reversals after SETTLED_S (the quadrant glitch; um, nan without a reversal)."""
    err = np.abs(ref_xy - pos_xy)
    late = t_s >= SETTLED_S
    path = contour_error(pos_xy, ref_xy)
    point = np.linalg.norm(ref_xy - pos_xy, axis=1)
    out: dict[str, Any] = {
        "max_tracking_um": (err.max(axis=0) * 1e6).tolist(),
        "max_tracking_settled_um": (err[late].max(axis=0) * 1e6).tolist(),
        "max_contour_path_um": float(path[late].max() * 1e6),
        "max_contour_point_um": float(point[late].max() * 1e6),
        "max_u_V": np.abs(u_V).max(axis=0).tolist(),
    }
    if ref_vel_xy is not None:
        out["max_at_reversal_um"] = [_max_near_reversals(t_s, ref_vel_xy[:, i], err[:, i]) * 1e6 for i in range(2)]
    return out


def _max_near_reversals(t_s, velocity, error) -> float:
    """Largest ``error`` within :data:`REVERSAL_WINDOW_S` of a sign change of ``velocity``
    after SETTLED_S (nan if the axis does not reverse there)."""
    flips = t_s[1:][(np.sign(velocity[1:]) != np.sign(velocity[:-1])) & (t_s[1:] >= SETTLED_S)]
    if flips.size == 0:
        return math.nan
    near = (np.abs(t_s[:, None] - flips[None, :]) <= REVERSAL_WINDOW_S).any(axis=1) & (t_s >= SETTLED_S)
    return float(error[near].max())


def tf_circle(
    kind: str, *, zpetc: bool, radius_mm: float, feed: float, duration_s: float, k_il: float = 0.0, k_c: float = 0.0
) -> dict:
    """The circle on the transfer functions (eq. 11 with the cutting gains), saturation 10 V."""
    ctrl = make_controller(f"choi1999_{kind}", s4.DT_S, {"zpetc": zpetc}, axes=("x", "y"))
    ref = circle_reference(radius_mm, feed, duration_s, preview_ticks_needed(ctrl.inputs))
    pos, u = tf_loop_xy(cutting_coupled_plant(s4.nominal_params(), k_il, k_c), ctrl, ref)
    n = len(pos)
    return _errors(np.arange(n) * s4.DT_S, ref[:n, :, 0], pos, u_V=u)


def tf_loop_xy(plant, ctrl, ref):
    """:func:`twin.sim.tf_loop.tf_loop` on axes x, y with the drive's 10 V saturation."""
    from twin.sim.tf_loop import tf_loop

    return tf_loop(plant, ctrl, ref, dt=s4.DT_S, saturation_V=10.0, axes=("x", "y"))


def zpetc_part() -> dict:
    """Part 5: each ZPETC, and the air-cut tracking error on the TF loop with and without it."""
    out: dict[str, Any] = {}
    for kind in KINDS:
        filters = s4.zpetc_filters(kind)
        out[kind] = {
            "preview_ticks": [f.preview for f, _ in filters],
            "delay_ticks": [f.delay for f, _ in filters],
            "unacceptable_zeros": [[[z.real, z.imag] for z in f.unacceptable] for f, _ in filters],
            "with": tf_circle(kind, zpetc=True, radius_mm=20.0, feed=2400.0, duration_s=3.2),
            "without": tf_circle(kind, zpetc=False, radius_mm=20.0, feed=2400.0, duration_s=3.2),
        }
    return out


def scenario_data(name: str) -> dict:
    """A bundled scenario as a dict (to vary)."""
    from twin.scenario import bundled_scenarios

    return tomllib.loads(bundled_scenarios()[name].read_text())


def run_twin(data: dict):
    from twin.scenario import run_scenario, scenario_from_dict

    return run_scenario(scenario_from_dict(data), progress=False).run


@lru_cache(maxsize=2)
def cutting_run(kind: str):
    """The twin's cutting circle of ``kind`` (bundled scenario, mechanistic force): shared by
    the tables, the plots and the recording, run once."""
    return run_twin(scenario_data(f"choi1999_{kind}_cutting"))


def twin_errors(res) -> dict:
    return _errors(res.t_s, res.ref[:, :, 0], res.table_position_m(), u_V=res.u_V, ref_vel_xy=res.ref[:, :, 1])


def static_gains() -> dict:
    """What sets the steady cutting deflection: K(0) of the full and reduced MIMO controllers
    (2 x 2) and each PID's proportional gain per axis, V/mm."""
    mm = s4.POSITION_UNIT_PER_M
    out: dict[str, Any] = {
        f"mimo_{order}_K0_V_per_mm": (s4.mimo_static_gain_V_per_m(order) / mm).tolist() for order in ("full", "reduced")
    }
    for name, (kind, params) in CONTROLLER_VARIANTS.items():
        if kind == "pid":
            design = s4.pid_design(params.get("tuning", "loop_at_input"), params.get("ki_scale", 1.0))
            out[name] = {
                "kp_V_per_mm": [g[0] / mm for g in design["gains"]],
                "ki_V_per_mm_s": [g[1] / mm for g in design["gains"]],
                "kd_V_s_per_mm": [g[2] / mm for g in design["gains"]],
                "pm_deg": [m.pm_deg for m in design["margins"]],
                "crossover_rad_s": [m.w_pm for m in design["margins"]],
            }
    out["mimo_diagonal_crossover_rad_s"] = [m.w_pm for m in s4.mimo_diagonal_margins()]
    return out


def controller_comparison() -> dict:
    """Part 4's question, what beats what and why: every :data:`CONTROLLER_VARIANTS` entry in the
    twin on the same two circles (the MIMO's bundled air cut, R 20, and mechanistic cutting
    circle, R 28; the paper cut R 30 with its PID), with the static gains beside them."""
    runs: dict[str, Any] = {}
    for name, (kind, params) in CONTROLLER_VARIANTS.items():
        runs[name] = {}
        for case in ("air_cut", "cutting"):
            data = scenario_data(f"choi1999_mimo_{case}")
            data["controller"] = {"type": f"choi1999_{kind}", "params": {"zpetc": True, **params}}
            runs[name][case] = twin_errors(run_twin(data))
    return {"static_gains": static_gains(), "runs": runs}


def circle_cases() -> dict:
    """Part 6: the paper's circle tests in the twin (friction, encoders, 982 N), and the
    twin-vs-TF checks on the linear runs (no friction, ideal encoders)."""
    out: dict[str, Any] = {}
    for kind in KINDS:
        air = scenario_data(f"choi1999_{kind}_air_cut")
        cut = scenario_data(f"choi1999_{kind}_cutting")
        average = copy.deepcopy(cut)
        average["disturbances"] = [dict(AVERAGE_FORCE)]
        out[kind] = {
            "air_cut": twin_errors(run_twin(air)),
            "cutting_mechanistic": twin_errors(cutting_run(kind)),
            "cutting_average_force": twin_errors(run_twin(average)),
            "cutting_radius_mm": cut["reference"]["radius_mm"],
        }
        # the same loop on both models: no friction, ideal encoders, no tooth harmonic
        linear = []
        for data, k_il, k_c in (
            (air, 0.0, 0.0),
            (average, AVERAGE_FORCE["k_il_N_s_per_m"], AVERAGE_FORCE["k_c_N_s_per_m"]),
        ):
            data = copy.deepcopy(data)
            data.pop("overrides", None)
            data.pop("sensors", None)
            for d in data.get("disturbances", []):
                d["harmonic_fraction"] = 0.0
            twin = twin_errors(run_twin(data))
            ref = data["reference"]
            tf = tf_circle(
                kind,
                zpetc=True,
                radius_mm=ref["radius_mm"],
                feed=ref["feed_mm_per_min"],
                duration_s=data["duration_s"],
                k_il=k_il,
                k_c=k_c,
            )
            linear.append({"case": "air cut" if k_il == 0 else "average force", "twin": twin, "tf": tf})
        out[kind]["linear"] = linear
    return out


def mismatches(circles: dict) -> list[str]:
    """Twin-vs-TF departures above 2 % on the linear runs (max tracking error per axis after
    the start, max contour error)."""
    lines = []
    for kind in KINDS:
        for case in circles[kind]["linear"]:
            flat = {}
            for side in ("twin", "tf"):
                m = case[side]
                flat[side] = {
                    "x_um": m["max_tracking_settled_um"][0],
                    "y_um": m["max_tracking_settled_um"][1],
                    "contour_um": m["max_contour_path_um"],
                }
            lines += twin_vs_tf(
                f"{kind} {case['case']}", flat["twin"], flat["tf"], keys=flat["twin"].keys(), tol_rel=TWIN_TOL_REL
            )
    return lines
