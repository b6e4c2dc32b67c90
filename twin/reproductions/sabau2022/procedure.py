"""Sabau (2022): every part of the thesis's abstract, computed on the transfer
functions (the TF loop, :func:`twin.sim.tf_loop.tf_loop`, the twin's timing on eq. (6)'s
model) and on the twin (``coupled_servo_xy``).

Steps are 1 mm on both axes at once, with the coupling of eq. (6) switched off (the SISO
models of eqs. 1-5, on which the thesis designs), except where the coupling is the point (the
disturbance from the other axis, the MIMO design, the trajectories).  The control period is
1 ms; velocities are the encoder's backward difference, as on the drive.  Designs:
:mod:`controllers.papers.sabau2022`.
"""

from __future__ import annotations

import math
import tomllib
from functools import cache
from typing import Any

import numpy as np

from controllers import make_controller
from controllers.blocks import Controller
from controllers.design.statefeedback import mimo_model
from controllers.design.tuning import limit_cycle, relay_ultimate_gain
from controllers.papers import sabau2022 as s1
from twin.disturbances.drive_input import VoltageStep
from twin.machines import build, get_machine
from twin.metrics import step_metrics
from twin.references import Step
from twin.sim.drive import Drive
from twin.sim.runner import simulate
from twin.sim.tf_loop import tf_loop

DT = s1.DT_S
STEP_M = 1e-3
UNCOUPLED = {"H_wx_uy": 0.0, "H_wy_ux": 0.0}
TWIN_TOL_REL = 0.02
#: Floors of the twin-vs-TF comparison: overshoot in percentage points, times in control periods.
OVERSHOOT_FLOOR_PCT, TIME_FLOOR_TICKS = 0.1, 1
DISTURBANCE_V, DISTURBANCE_AT_S = 1.0, 1.0
#: The relay test's limit cycle is measured after this time (s).
RELAY_SETTLED_S = 1.0
#: Feed of the trajectories (not in the text).
FEED_MM_PER_MIN = 1000.0
TRAJECTORIES = {
    "square L 3 cm": ("square", 30.0),
    "square L 5 cm": ("square", 50.0),
    "circle R 1 cm": ("circle", 10.0),
    "circle R 5 cm": ("circle", 50.0),
}
#: Table 2's three experiments as run here.
EXPERIMENTS = ("modified_p", "pole_placement", "pi_p_pole_placement")


def controller(design: str, axes=("x", "y"), **params) -> Controller:
    """The registry's ``sabau2022`` controller of ``design`` on ``axes``."""
    return make_controller("sabau2022", DT, {"design": design, **params}, axes=axes)


def plant_si(coupled: bool, scale: dict | None = None):
    """Eq. (6) in SI (m, V) as ``(A, B, C, D)`` for the TF loop; ``scale`` multiplies model
    symbols (``K_x``, ``a_x``, ``K_y``, ``a_y``)."""
    scale = scale or {}
    gains = [s1.MODEL[a][0] * scale.get(f"K_{a}", 1.0) * 1e-3 for a in s1.AXES]
    poles = [s1.MODEL[a][1] * scale.get(f"a_{a}", 1.0) for a in s1.AXES]
    cross = [c * 1e-3 if coupled else 0.0 for c in s1.CROSS]
    A, B, C = mimo_model(gains, poles, cross)
    return A, B, C, np.zeros((2, 2))


def _overrides(coupled: bool, scale: dict | None) -> dict:
    out: dict[str, Any] = {} if coupled else dict(UNCOUPLED)
    for key, f in (scale or {}).items():
        out[key] = get_machine("coupled_servo_xy").parameters[key].value * f
    return out


def _step_ref(n: int, axes=(0, 1)) -> np.ndarray:
    return Step(STEP_M, n_axes=2, axes=tuple(axes)).sample(np.arange(n) * DT)


def _disturbance_V(n: int, dt: float) -> np.ndarray:
    return np.where(np.arange(n)[:, None] * dt >= DISTURBANCE_AT_S, DISTURBANCE_V, 0.0) * np.ones((1, 2))


def tf_run(
    ctrl: Controller,
    duration_s: float,
    *,
    coupled: bool = False,
    disturbance: bool = False,
    scale: dict | None = None,
    ref: np.ndarray | None = None,
    delay_s: float = 0.0,
):
    """``(t_s, pos m (n, 2), u V (n, 2))`` of the TF loop at the controller's period (steps on
    both axes by default)."""
    dt = ctrl.dt
    n = round(duration_s / dt)
    ref = _step_ref(n) if ref is None else ref
    pos, u = tf_loop(
        plant_si(coupled, scale),
        ctrl,
        ref,
        dt=dt,
        delay_s=delay_s,
        u_dist_V=_disturbance_V(n, dt) if disturbance else None,
        axes=("x", "y"),
    )
    return np.arange(n) * dt, pos, u


def twin_run(
    ctrl: Controller,
    duration_s: float,
    *,
    coupled: bool = False,
    disturbance: bool = False,
    scale: dict | None = None,
    reference=None,
    delay_s: float = 0.0,
):
    """The same on the twin: :class:`~twin.sim.runner.RunResult`."""
    machine = build("coupled_servo_xy", _overrides(coupled, scale))
    substeps = round(ctrl.dt / machine.model.opt.timestep)
    dist = [VoltageStep(DISTURBANCE_V, DISTURBANCE_AT_S, 2)] if disturbance else []
    return simulate(
        machine,
        ctrl,
        reference or Step(STEP_M, n_axes=2),
        duration_s,
        ctrl.dt,
        progress=False,
        drive=Drive(2, substeps, machine.model.opt.timestep, delay_s),
        disturbances=dist,
    )


def step_table(t_s, pos) -> list[dict]:
    """Step metrics per axis (1 mm step) and ``stable``: the response finite and within 5 %
    of the step at the end."""
    out = []
    for i in range(2):
        y = pos[:, i]
        stable = bool(np.isfinite(y).all() and abs(y[-1] - STEP_M) < 0.05 * STEP_M)
        out.append(step_metrics(t_s, y, final=STEP_M) | {"stable": stable})
    return out


def responses(
    ctrl: Controller,
    duration_s: float,
    twin: bool,
    *,
    coupled: bool = False,
    disturbance: bool = False,
    scale: dict | None = None,
    axes=(0, 1),
) -> dict:
    """``side -> (t_s, pos m (n, 2))`` of 1 mm steps on ``axes``: the TF loop (``"tf"``) and,
    with ``twin``, the twin (``"twin"``), the same loop on both."""
    n = round(duration_s / ctrl.dt)
    out: dict[str, Any] = {
        "tf": tf_run(ctrl, duration_s, coupled=coupled, disturbance=disturbance, scale=scale, ref=_step_ref(n, axes))[
            :2
        ]
    }
    if twin:
        res = twin_run(
            ctrl,
            duration_s,
            coupled=coupled,
            disturbance=disturbance,
            scale=scale,
            reference=Step(STEP_M, n_axes=2, axes=tuple(axes)),
        )
        out["twin"] = (res.t_s, res.table_position_m())
    return out


def steps(ctrl: Controller, duration_s: float, twin: bool, **kw) -> dict:
    """``side -> step_table`` of :func:`responses`."""
    return {side: step_table(*run) for side, run in responses(ctrl, duration_s, twin, **kw).items()}


def _step_pair(ctrl_design: str, duration_s: float, twin: bool, **params) -> dict:
    return steps(controller(ctrl_design, **params), duration_s, twin)


# ---------------------------------------------------------------- part 1: relay and ZN


def relay_scenario(delay_s: float) -> dict:
    """The bundled ``sabau2022_relay`` scenario with ``delay_s`` of drive delay."""
    data = scenario_data("sabau2022_relay")
    data["drive"]["delay_s"] = delay_s
    return data


def relay_test(delay_s: float, twin: bool) -> dict:
    """The relay experiment (bundled ``sabau2022_relay``: both axes, coupling off, at the physics
    step) with ``delay_s`` of drive delay: Ku = 4 d/(pi a), Pu measured over t >= 1 s, on the TF
    loop and the twin, beside the exact ultimate point of the same sampled loop."""
    from twin.scenario import assemble, run_scenario, scenario_from_dict

    data = relay_scenario(delay_s)
    params = data["controller"]["params"]
    inputs = assemble(scenario_from_dict(data))
    dt, duration = inputs.control_period_s, inputs.duration_s
    zero = np.zeros((round(duration / dt), 2, 3))
    runs: dict[str, Any] = {"tf": tf_run(inputs.controllers[0], duration, ref=zero, delay_s=delay_s)[:2]}
    if twin:
        res = run_scenario(scenario_from_dict(data), progress=False).run
        runs["twin"] = (res.t_s, res.table_position_m())
    out: dict[str, Any] = {
        "delay_s": delay_s,
        "control_period_s": dt,
        "amplitude_V": params["amplitude_V"],
        "hysteresis_mm": params["hysteresis_m"] * 1e3,
    }
    for side, (t, pos) in runs.items():
        late = t >= RELAY_SETTLED_S
        cycles = [limit_cycle(t[late], pos[late, i] * 1e3) for i in range(2)]
        out[side] = [
            {
                "amplitude_mm": c.amplitude,
                "pu_s": c.period_s,
                "periods": c.periods,
                "ku_V_per_mm": relay_ultimate_gain(params["amplitude_V"], c.amplitude),
                "hysteresis_phase_deg": math.degrees(math.asin(min(1.0, out["hysteresis_mm"] / c.amplitude))),
            }
            for c in cycles
        ]
    out["exact"] = [dict(zip(("ku_V_per_mm", "pu_s"), s1.ultimate_point(a, delay_s, dt))) for a in s1.AXES]
    return out


def zn_controller(kind: str, ku_pu: list[tuple[float, float]]) -> Controller:
    """The ZN design ``kind`` on both axes, each from its own (Ku V/mm, Pu s)."""
    parts = [controller(kind, (a,), ku_V_per_mm=ku, pu_s=pu) for a, (ku, pu) in zip(s1.AXES, ku_pu)]
    return Controller([b for c in parts for b in c.blocks], DT, kind)


def table1(ku_pu: list[tuple[float, float]], twin: bool) -> dict:
    """ZN and modified P/PI/PID from the relay's (Ku, Pu) per axis; steps on the delay-free loop."""
    out: dict[str, Any] = {}
    for kind in s1.TABLE1_ROWS:
        gains = [s1.design_gains(a, kind, *ku_pu[i]) for i, a in enumerate(s1.AXES)]
        out[kind] = {
            "gains": [{k: g[k] for k in ("kp", "ki", "kd")} for g in gains],
            "agreement": s1.TABLE1_AGREEMENT[kind],
            **steps(zn_controller(kind, ku_pu), 3.0, twin),
        }
    return out


# ---------------------------------------------------------------- parts 2-5, 8: cascades, state feedback


def disturbance_response(design: str, twin: bool) -> dict:
    """1 mm steps, then a 1 V input step at 1 s (a step on the speed equation: the coupling
    from the other axis enters the same way): the largest deviation after it and the offset
    left at 2 s (um), per axis."""
    out: dict[str, Any] = {}
    for side, (t, pos) in responses(controller(design), 2.0, twin, disturbance=True).items():
        after = t >= DISTURBANCE_AT_S
        base = pos[np.argmax(after) - 1]
        dev = pos[after] - STEP_M
        out[side] = {
            "peak_um": (np.abs(dev).max(axis=0) * 1e6).tolist(),
            "final_um": (dev[-1] * 1e6).tolist(),
            "before_um": ((base - STEP_M) * 1e6).tolist(),
        }
    return out


def coupling_response(design: str, twin: bool) -> dict:
    """The coupled machine: Y steps 1 mm while X holds 0: X's largest excursion and final
    offset (um), the coupling of eq. (6) as X's disturbance."""
    runs = responses(controller(design), 2.0, twin, coupled=True, axes=(1,))
    return {
        side: {"x_peak_um": float(np.abs(pos[:, 0]).max() * 1e6), "x_final_um": float(pos[-1, 0] * 1e6)}
        for side, (t, pos) in runs.items()
    }


def cascades(twin: bool) -> dict:
    """Part 2: P-P, PI-P and P-PID with part 2's rules."""
    return {
        d: {
            "gains": [s1.design_gains(a, d) for a in s1.AXES],
            "step": _step_pair(d, 2.0, twin),
            "disturbance": disturbance_response(d, twin),
            "coupling": coupling_response(d, twin),
        }
        for d in ("p_p", "pi_p", "p_pid")
    }


def _poles(design: str, axis: str) -> list:
    g = s1.state_feedback(axis, design)
    K, a = s1.MODEL[axis]
    # closed loop of the cascade form on eq. (5): s^2 + (a + K kv) s + K kv kp (+ K kv ki / s)
    coeffs = [1.0, a + K * g.kv, K * g.kv * g.kp] + ([K * g.kv * g.ki] if g.ki else [])
    return sorted(np.roots(coeffs).tolist(), key=lambda p: p.real)


def state_feedback_part(designs, twin: bool) -> dict:
    """Parts 3-5 and 8: each design's gains, closed-loop poles, steps and disturbance response."""
    out: dict[str, Any] = {}
    for d in designs:
        g = [s1.state_feedback(a, d) for a in s1.AXES]
        out[d] = {
            "gains": [vars(x) for x in g],
            "poles": [[[p.real, p.imag] for p in _poles(d, a)] for a in s1.AXES],
            "step": _step_pair(d, 2.0, twin),
            "disturbance": disturbance_response(d, twin),
        }
        if g[0].ki:
            out[d]["step_without_ff"] = _step_pair(d, 2.0, twin, feedforward=False)
    return out


def mimo_part(twin: bool) -> dict:
    """Part 3, MIMO: eq. (6)'s state feedback against the SISO designs on the coupled machine
    (both axes step together)."""
    K, N = s1.mimo_pole_placement()
    out: dict[str, Any] = {"K": K.tolist(), "N": N.tolist()}
    for d in ("pole_placement", "state_feedback_mimo"):
        out[d] = steps(controller(d), 2.0, twin, coupled=True)
    return out


def improvement(sf: dict, t1: dict, casc: dict) -> dict:
    """The text's "up to 20 %" for SISO state feedback: the pole placement's settling time
    against the ZN PID (Table 1) and the P-P cascade (part 2), TF loop, per axis (%)."""
    ts = [m["settling_time_s"] for m in sf["pole_placement"]["step"]["tf"]]
    out: dict[str, Any] = {}
    for name, ref in (
        ("ZN PID", t1["pid"]["tf"]),
        ("modified PID", t1["modified_pid"]["tf"]),
        ("P-P cascade", casc["p_p"]["step"]["tf"]),
        ("PI-P cascade", casc["pi_p"]["step"]["tf"]),
    ):
        out[name] = [100.0 * (r["settling_time_s"] - t) / r["settling_time_s"] for r, t in zip(ref, ts)]
    return out


# ---------------------------------------------------------------- part 6: fractional PI, structured mu


def box_corners() -> list[dict]:
    """The four corners of the +-10 % box of (K, a), the same signs on both axes."""
    return [
        {f"K_{a}": 1 + sk * s1.BOX for a in s1.AXES} | {f"a_{a}": 1 + sa * s1.BOX for a in s1.AXES}
        for sk in (-1, 1)
        for sa in (-1, 1)
    ]


#: The band where the Oustaloup realization is compared with s^-lambda (rad/s).
OUSTALOUP_CHECK_RAD_S = np.logspace(-1, 2, 61)


def oustaloup_accuracy(w=OUSTALOUP_CHECK_RAD_S) -> dict:
    """Largest magnitude (dB) and phase (deg) error of the Oustaloup s^-lambda against the
    exact one over ``w`` (rad/s), per axis."""
    from controllers.design.fractional import oustaloup

    out = []
    for a in s1.AXES:
        lam = s1.EQ14[a][2]
        ratio = oustaloup(-lam, *s1.OUSTALOUP_BAND, s1.OUSTALOUP_ORDER).response(w) / (1j * w) ** -lam
        out.append(
            {
                "mag_db": float(np.abs(20 * np.log10(np.abs(ratio))).max()),
                "phase_deg": float(np.abs(np.degrees(np.angle(ratio))).max()),
            }
        )
    return {"w_rad_s": [float(w[0]), float(w[-1])], "axes": out}


#: Ways of reading eq. (14)'s loop (section 5.3), computed exactly by :func:`fractional_step`.
ARRANGEMENTS = (
    "unity position loop, mm (the plain reading)",
    "2-DOF I-P (kp on the measurement only)",
    "unity loop, position in cm (G/10)",
    "unity loop, position in m (G/1000)",
    "around the speed P of eqs. (15)-(16)",
    "on the speed loop, r -> omega (no integrator)",
)


def fractional_step(
    axis: str, arrangement: str, *, scale=(1.0, 1.0), plant_gain: float = 1.0, t_max_s: float = 6.0
) -> tuple[np.ndarray, np.ndarray]:
    """``(t_s, y)``: exact (Bromwich-integral) step response of eq. (14) on ``axis`` in ``arrangement`` (one of
    :data:`ARRANGEMENTS`, or ``"velocity plant, gain x g"`` with ``plant_gain``); ``scale``
    multiplies (K, a)."""
    from controllers.design.fractional import step_response

    kp, ki, lam = s1.EQ14[axis]
    K, a = s1.MODEL[axis]
    K, a = K * scale[0], a * scale[1]

    def C(s):
        return kp + ki * s**-lam

    def G(s):
        return K / (s * (s + a))

    if arrangement == "2-DOF I-P (kp on the measurement only)":
        return step_response(lambda s: G(s) * ki * s**-lam / (1 + G(s) * C(s)), t_max_s)
    if arrangement == "around the speed P of eqs. (15)-(16)":
        kv = s1.EQ15_16[axis][2]

        def inner(s):
            return K * kv / (s + a + K * kv) / s

        return step_response(lambda s: C(s) * inner(s) / (1 + C(s) * inner(s)), t_max_s)
    if arrangement in ("on the speed loop, r -> omega (no integrator)", "velocity plant, gain x g"):
        g = plant_gain if arrangement == "velocity plant, gain x g" else 1.0
        return step_response(lambda s: C(s) * g * K / (s + a) / (1 + C(s) * g * K / (s + a)), t_max_s)
    g = {
        "unity position loop, mm (the plain reading)": 1.0,
        "unity loop, position in cm (G/10)": 0.1,
        "unity loop, position in m (G/1000)": 1e-3,
    }[arrangement]
    return step_response(lambda s: C(s) * g * G(s) / (1 + C(s) * g * G(s)), t_max_s)


def _metrics(response) -> dict:
    t_s, y = response
    return step_metrics(t_s, y, final=1.0)


def _bands(metrics: list[dict]) -> dict:
    """(min, max) of each step metric over a list of metric dicts."""
    keys = ("overshoot_pct", "settling_time_s", "rise_time_10_90_s")
    return {k: (float(np.nanmin([m[k] for m in metrics])), float(np.nanmax([m[k] for m in metrics]))) for k in keys}


def fitted_velocity_gain(axis: str) -> dict:
    """A FIT, labelled as such: the gain g on the speed model g K/(s + a) (no integrator) that
    brings eq. (14)'s rise and settling times closest to the text's (least |rise - 0.248| +
    |settling - 0.558| on X, likewise Y), searched on a log grid: evidence for or against a
    scaled velocity loop, not a model of the machine."""
    best = None
    for g in np.logspace(-2, 0, 41):
        m = _metrics(fractional_step(axis, "velocity plant, gain x g", plant_gain=g))
        miss = abs(m["rise_time_10_90_s"] - s1.EQ14_RISE_S[axis][0]) + abs(
            m["settling_time_s"] - s1.EQ14_SETTLING_S[axis][0]
        )
        if np.isfinite(miss) and (best is None or miss < best[0]):
            best = (miss, g, m)
    if best is None:
        raise ValueError(f"axis {axis}: no speed-loop scale gives a finite rise and settling time")
    return {"g": float(best[1]), "miss_s": float(best[0]), "metrics": best[2]}


def fractional_part(samples: int, seed: int, twin: bool) -> dict:
    """Part 6: eq. (14) read several ways (exact responses), exact responses of the plain
    reading at the box corners and ``samples`` random points of the box, the Oustaloup
    realization on the TF loop and the twin (plain reading) at the nominal point and the
    corners, and eqs. (15)-(16) likewise."""
    out: dict[str, Any] = {
        "oustaloup": oustaloup_accuracy(),
        "arrangements": {},
        "fit": {a: fitted_velocity_gain(a) for a in s1.AXES},
    }
    for name in ARRANGEMENTS:
        out["arrangements"][name] = [_metrics(fractional_step(a, name)) for a in s1.AXES]
    exact_box = []
    for c in box_corners():
        exact_box.append(
            [_metrics(fractional_step(a, ARRANGEMENTS[0], scale=(c[f"K_{a}"], c[f"a_{a}"]))) for a in s1.AXES]
        )
    out["exact_box"] = exact_box
    rng = np.random.default_rng(seed)
    sampled = []
    for q in rng.uniform(1 - s1.BOX, 1 + s1.BOX, (samples, 2, 2)):
        sampled.append(
            [_metrics(fractional_step(a, ARRANGEMENTS[0], scale=tuple(q[i]))) for i, a in enumerate(s1.AXES)]
        )
    out["exact_random"] = {"samples": samples, "bands": [_bands([m[i] for m in sampled + exact_box]) for i in range(2)]}
    for design, horizon in (("fo_pi", 4.0), ("mu_cascade", 20.0)):
        ctrl = controller(design)
        points = [steps(ctrl, horizon, twin, scale=c) for c in [None, *box_corners()]]
        out[design] = {side: [p[side] for p in points] for side in points[0]}  # side -> nominal, corners
    return out


# ---------------------------------------------------------------- part 7: bee colony on LQR weights

ABC_LOG10_BOUNDS = (-6.0, 2.0)
ABC_ITERATIONS, ABC_POPULATION = 30, 10
ABC_REQUIRED_SETTLING_S = 0.2


def lqr_step_metrics(axis: str, log10_q) -> dict:
    """Step metrics of the LQR state feedback Q = diag(10^q1, 10^q2), R = 1 on eq. (5)
    (continuous, exact: eigen-decomposition of the closed loop), u = -K x + k_theta r."""
    from controllers.design.statefeedback import lqr

    A, B, C = s1.model(axis)
    K = lqr(A, B, np.diag(10.0 ** np.asarray(log10_q)), 1.0)
    Acl, Bcl = A - B @ K, B * K[0, 1]
    lam, V = np.linalg.eig(Acl)
    t = np.linspace(0.0, 2.0, 4001)
    # y(t) = C Acl^-1 (e^(Acl t) - I) Bcl
    coef = np.linalg.solve(V, np.linalg.solve(Acl, Bcl))[:, 0]
    y = ((C @ V)[0] * coef * (np.exp(np.outer(t, lam)) - 1.0)).sum(axis=1).real
    return step_metrics(t, y, final=1.0) | {"k_omega": float(K[0, 0]), "k_theta": float(K[0, 1])}


def abc_costs() -> dict:
    """The two cost functions of section 6 (s): ``minimize`` = settling + overshoot/100 (1 % of
    overshoot weighs like 10 ms); ``required`` = |settling - 0.2 s| + overshoot/100."""
    return {
        "minimize": lambda m: m["settling_time_s"] + m["overshoot_pct"] / 100.0,
        "required": lambda m: abs(m["settling_time_s"] - ABC_REQUIRED_SETTLING_S) + m["overshoot_pct"] / 100.0,
    }


def abc_part(seed: int, twin: bool) -> dict:
    """Part 7: ABC over log10 of Q's diagonal (R = 1) for both costs, X axis as Fig. 14."""
    from controllers.design.tuning import bee_colony_minimize

    out: dict[str, Any] = {
        "bounds_log10": ABC_LOG10_BOUNDS,
        "iterations": ABC_ITERATIONS,
        "population": ABC_POPULATION,
        "seed": seed,
    }
    for name, cost in abc_costs().items():

        def evaluate(x, cost=cost):
            m = lqr_step_metrics("x", x)
            return cost(m) if np.isfinite(m["settling_time_s"]) else math.inf

        res = bee_colony_minimize(
            evaluate,
            [ABC_LOG10_BOUNDS[0]] * 2,
            [ABC_LOG10_BOUNDS[1]] * 2,
            iterations=ABC_ITERATIONS,
            seed=seed,
            population=ABC_POPULATION,
        )
        best = lqr_step_metrics("x", res.x)
        history = [lqr_step_metrics("x", x) for x in res.best_x]
        row: dict[str, Any] = {
            "log10_q": res.x.tolist(),
            "cost": res.cost,
            "evaluations": res.evaluations,
            "metrics": best,
            "settling_by_iteration_s": [h["settling_time_s"] for h in history],
            "overshoot_by_iteration_pct": [h["overshoot_pct"] for h in history],
            "log10_q_by_iteration": [x.tolist() for x in res.best_x],
        }
        row["step"] = steps(_abc_controller(best), 2.0, twin)
        out[name] = row
    return out


def _abc_controller(metrics: dict) -> Controller:
    """The bee colony's LQR on X run as the P-P cascade (Y: the pole placement), for the loops."""
    from controllers.blocks import cascade
    from controllers.design.pid import pid_tf

    kp, kv = metrics["k_theta"] / metrics["k_omega"], metrics["k_omega"] * s1.MM_PER_M
    x = cascade(pid_tf(kp), pid_tf(kv), DT, axis="x", name="abc.x")
    y = controller("pole_placement", ("y",))
    return Controller(x.blocks + y.blocks, DT, "abc")


# ---------------------------------------------------------------- part 8: LMI regions


def lmi_part(twin: bool) -> dict:
    """Part 8: the region, the plain and the integral-augmented LMI designs (poles, steps,
    disturbance: only the integral one removes it)."""
    region = s1.lmi_region()
    out = state_feedback_part(("lmi", "pi_p_lmi"), twin)
    for d in ("lmi", "pi_p_lmi"):
        out[d]["in_region"] = [region.contains([complex(*p) for p in poles]) for poles in out[d]["poles"]]
    out["region"] = {"alpha": region.alpha, "damping": region.damping, "radius": region.radius}
    return out


# ---------------------------------------------------------------- part 9: trajectories, fitting index


def scenario_data(name: str) -> dict:
    """A bundled scenario as a dict (to vary)."""
    from twin.scenario import bundled_scenarios

    return tomllib.loads(bundled_scenarios()[name].read_text())


def trajectory_scenario(path: str, experiment: int) -> dict:
    """The bundled ``sabau2022_<square|circle>_<size>mm`` scenario for Table 2's ``experiment`` (1-3)."""
    kind, size = TRAJECTORIES[path]
    data = scenario_data(f"sabau2022_{kind}_{size:g}mm")
    data["controller"]["params"] = {
        "design": EXPERIMENTS[experiment - 1],
        "feedforward": False,
        "velocity_ff": experiment == 3,
    }
    return data


@cache
def trajectory_run(path: str, experiment: int):
    """The twin's run of one Table 2 cell (cached: tables, plots and recording share it)."""
    from twin.scenario import run_scenario, scenario_from_dict

    return run_scenario(scenario_from_dict(trajectory_scenario(path, experiment)), progress=False).run


def trajectory_tf(path: str, experiment: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(t_s, ref m (n, 2), pos m (n, 2))`` of the same cell on the TF loop (coupled eq. 6)."""
    from twin.scenario import assemble, scenario_from_dict

    inputs = assemble(scenario_from_dict(trajectory_scenario(path, experiment)))
    n = round(inputs.duration_s / DT)
    t = np.arange(n) * DT
    ref = inputs.reference.sample(t)
    _, pos, _ = tf_run(inputs.controllers[0], inputs.duration_s, coupled=True, ref=ref)
    return t, ref[:, :, 0], pos


def trajectories(twin: bool) -> dict:
    """Table 2: the fitting index per axis for every path and experiment, TF loop and twin."""
    from twin.metrics import fit_index

    out: dict[str, Any] = {}
    for path in TRAJECTORIES:
        rows = []
        for e in (1, 2, 3):
            _, ref, pos = trajectory_tf(path, e)
            row: dict[str, Any] = {"tf": fit_index(pos, ref).tolist()}
            if twin:
                res = trajectory_run(path, e)
                row["twin"] = fit_index(res.table_position_m(), res.ref[:, :, 0]).tolist()
                row["twin_max_contour_um"] = float(_contour_max(res) * 1e6)
            rows.append(row)
        out[path] = rows
    return out


def _contour_max(res) -> float:
    from twin.metrics import contour_error

    return float(contour_error(res.table_position_m(), res.ref[:, :, 0]).max())


# ---------------------------------------------------------------- twin against the TF loop


def _flat_steps(prefix: str, pair: dict) -> tuple[dict, dict]:
    """The step metrics of both sides by name, for the axes where both responses are stable."""
    twin, tf = {}, {}
    for axis, a, b in zip(s1.AXES, pair["twin"], pair["tf"]):
        if a["stable"] and b["stable"]:
            for key in ("overshoot_pct", "settling_time_s", "rise_time_10_90_s"):
                twin[f"{prefix} {axis} {key}"], tf[f"{prefix} {axis} {key}"] = a[key], b[key]
    return twin, tf


def _step_pairs(res: dict) -> list[tuple[str, dict]]:
    pairs = [(f"table1 {k}", v) for k, v in res["table1"].items()]
    pairs += [(f"cascade {k}", v["step"]) for k, v in res["cascades"].items()]
    pairs += [(f"state feedback {k}", v["step"]) for k, v in res["state_feedback"].items()]
    pairs += [(f"lmi {k}", res["lmi"][k]["step"]) for k in ("lmi", "pi_p_lmi")]
    pairs += [(f"mimo {k}", res["mimo"][k]) for k in ("pole_placement", "state_feedback_mimo")]
    pairs += [(f"abc {k}", res["abc"][k]["step"]) for k in ("minimize", "required")]
    for design in ("fo_pi", "mu_cascade"):
        pairs += [
            (f"{design} {'nominal' if i == 0 else f'corner {i}'}", {"twin": a, "tf": b})
            for i, (a, b) in enumerate(zip(res["fractional"][design]["twin"], res["fractional"][design]["tf"]))
        ]
    return pairs


def stability_differences(res: dict) -> list[str]:
    """Step responses one side finds stable and the other not (at a stability boundary the
    twin's semi-implicit Euler step and the exact ZOH model may fall on either side)."""
    if not res["settings"]["twin"]:
        return []
    return [
        f"{prefix} {axis}: TF {'stable' if b['stable'] else 'unstable'}, twin {'stable' if a['stable'] else 'unstable'}"
        for prefix, pair in _step_pairs(res)
        for axis, a, b in zip(s1.AXES, pair["twin"], pair["tf"])
        if a["stable"] != b["stable"]
    ]


def _departures(twin: dict, tf: dict) -> list[str]:
    """Keys whose twin value is more than 2 % from the TF value, beyond the floors."""
    lines = []
    for key, tv in twin.items():
        fv = tf[key]
        if not (np.isfinite(tv) and np.isfinite(fv)):
            if np.isfinite(tv) != np.isfinite(fv):
                lines.append(f"{key}: twin {tv:.4g} vs TF {fv:.4g}")
            continue
        floor = OVERSHOOT_FLOOR_PCT if "overshoot" in key else TIME_FLOOR_TICKS * DT if key.endswith("_s") else 0.0
        if abs(tv - fv) > max(TWIN_TOL_REL * abs(fv), floor):
            lines.append(f"{key}: twin {tv:.4g} vs TF {fv:.4g}")
    return lines


def mismatches(res: dict) -> list[str]:
    """Every twin number more than 2 % from its TF-loop number (overshoot: 0.1 point floor;
    times: one control period floor; fits compared as 100 - fit, the NRMSE in %); responses
    that either side finds unstable are listed by :func:`stability_differences` instead."""
    if not res["settings"]["twin"]:
        return []
    twin, tf = {}, {}
    # the relay without delay is left out: its only lag is the hysteresis's 11-15 deg, so the
    # twin's half-physics-step phase lead (0.6 deg at 220 rad/s) moves its Ku by about 3 %
    for r in res["relay"]["tests"][:1]:
        for axis, a, b in zip(s1.AXES, r["twin"], r["tf"]):
            for key in ("ku_V_per_mm", "pu_s"):
                twin[f"relay {r['delay_s'] * 1e3:g} ms {axis} {key}"] = a[key]
                tf[f"relay {r['delay_s'] * 1e3:g} ms {axis} {key}"] = b[key]
    for prefix, pair in _step_pairs(res):
        a, b = _flat_steps(prefix, pair)
        twin |= a
        tf |= b
    for path, rows in res["trajectories"].items():
        for e, row in enumerate(rows, 1):
            for axis, a, b in zip(s1.AXES, row["twin"], row["tf"]):
                twin[f"{path} experiment {e} {axis} 100 - fit"] = 100.0 - a
                tf[f"{path} experiment {e} {axis} 100 - fit"] = 100.0 - b
    return _departures(twin, tf)
