"""Anang et al. (2017): the PID of eq. (6) on the Googol table, its margins, the NPID's
Popov bound, and Tables 1-3 computed on the transfer functions and on the twin.

Plant, eq. (1): G(s) = 78020/(s^2 + 163 s + 193.3) mm/V with a 1.2 ms delay; the PID of
eq. (6) is in V/mm.  Loop gains here are dimensionless, L = C G e^(-sT) with both in mm.

- Margins: exact delay e^(-j w T) on the frequency response, the derivative ideal or filtered
  (tf_s), against first- and second-order Pade approximations, and the sampled loop the twin
  runs (10 kHz: Tustin controller, zero-order-hold plant, 12-tick delay).
- Popov: the real-axis crossing of (Re L, w Im L) and Ke_max = 1/|crossing|, for the same
  loops; Ke = cosh(KO e_max) against it; the critical constant gain of the sampled loop found
  in time by bisection on the transfer-function loop and on the twin.
- Tables 1-3: sine references, PID and NPID, without cutting and with the mechanistic end
  milling of the bundled scenario (2 flutes, 10 mm, 1 mm deep slot in Al7075; the paper gives
  no cutting conditions) at 1500/2500/3500 rpm, 10 s at 10 kHz as in the paper.  Metrics over
  the steady window t >= 2.5 s: the paper's PID maxima equal the steady amplitude of the
  error (0.4 Hz, 10 mm: 0.0639 mm paper, 0.0640 ours), not the start-up transient.  The
  transfer-function loop with cutting takes the twin's own force history as an equivalent
  input voltage F / (M b0) at the plant (M the axis's equivalent mass), so both see the
  same force.
"""

from __future__ import annotations

import math
from functools import lru_cache
from typing import Any

import numpy as np

from controllers import make_controller
from controllers.blocks import error_feedback
from controllers.design.loop_analysis import loop_margins, popov_crossing
from controllers.lti import SisoTf, discretize, tf_to_ss
from controllers.papers import anang2017
from twin.machines import build
from twin.machines.googol import GoogolXY
from twin.machining.cutting import EndMilling
from twin.references import SumOfSines
from twin.reproductions.base import twin_vs_tf
from twin.sim.runner import simulate
from twin.sim.tf_loop import tf_loop

#: The paper's numbers.  Table 1 is printed with its middle rows as given: (0.4 Hz, 20 mm) and
#: (0.7 Hz, 10 mm) read as swapped against every linear loop (see the report).
PAPER: dict[str, Any] = {
    "gm_db": 9.94,
    "pm_deg": 61.4,
    "ms_db": 5.12,
    "bw_hz": 44.4,
    "popov_crossing": -0.3071,
    "ke_max": 3.2563,
    "ke": 3.1075,
    "ko": 6.0,
    "e_max": 0.3,
    "table1": {
        (0.4, 10): (0.0639, 0.0425),
        (0.4, 20): (0.1048, 0.0694),
        (0.7, 10): (0.1273, 0.0842),
        (0.7, 20): (0.2086, 0.1369),
    },
    "table2": {
        (0.4, 10, 1500): (0.0757, 0.0507),
        (0.4, 10, 2500): (0.0746, 0.0500),
        (0.4, 10, 3500): (0.0727, 0.0484),
        (0.4, 20, 1500): (0.1172, 0.0777),
        (0.4, 20, 2500): (0.1155, 0.0762),
        (0.4, 20, 3500): (0.1141, 0.0761),
        (0.7, 10, 1500): (0.1398, 0.0924),
        (0.7, 10, 2500): (0.1386, 0.0918),
        (0.7, 10, 3500): (0.1367, 0.0906),
        (0.7, 20, 1500): (0.2217, 0.1459),
        (0.7, 20, 2500): (0.2197, 0.1449),
        (0.7, 20, 3500): (0.2193, 0.1444),
    },
    "table3": {
        (0.4, 10, 1500): 33.03,
        (0.4, 10, 2500): 32.98,
        (0.4, 10, 3500): 33.43,
        (0.4, 20, 1500): 33.70,
        (0.4, 20, 2500): 34.03,
        (0.4, 20, 3500): 33.30,
        (0.7, 10, 1500): 33.91,
        (0.7, 10, 2500): 33.77,
        (0.7, 10, 3500): 33.72,
        (0.7, 20, 1500): 34.19,
        (0.7, 20, 2500): 34.05,
        (0.7, 20, 3500): 34.15,
    },
}
DT_S, DURATION_S, STEADY_FROM_S = 1e-4, 10.0, 2.5
REFERENCES = ((0.4, 10), (0.4, 20), (0.7, 10), (0.7, 20))
SPINDLES_RPM = (None, 1500.0, 2500.0, 3500.0)
#: The bundled scenario's cut (anang2017_sine_cutting.toml).
CUT: dict[str, Any] = {"n_flutes": 2, "diameter_mm": 10.0, "axial_depth_mm": 1.0, "radial_depth_mm": 10.0}
#: Derivative filter of the twin's PID (s).
TF_S = 1e-4
#: Largest departure of a twin number from its transfer-function number.
TWIN_TOL_REL = 0.02


@lru_cache(maxsize=1)
def machine():
    """The ``googol_xy`` twin at the control period, built once (the reproductions only read it)."""
    return build("googol_xy", timestep_s=DT_S)


def plant_mm() -> SisoTf:
    """Eq. (1), mm/V."""
    bm = machine()
    g = bm.plant[0][0]
    return SisoTf(np.asarray(g.num) * 1e3, g.den)


def pid_mm(tf_s: float = 0.0) -> SisoTf:
    """Eq. (6) in V/mm, derivative ideal (tf_s = 0, improper) or filtered."""
    if tf_s == 0.0:
        return SisoTf(
            (anang2017.KD_V_S_PER_M * 1e-3, anang2017.KP_V_PER_M * 1e-3, anang2017.KI_V_PER_M_S * 1e-3), (1.0, 0.0)
        )
    c = anang2017.pid(tf_s)
    return SisoTf(np.asarray(c.num) * 1e-3, c.den)


def _pade(T: float, order: int):
    """Pade approximation of e^(-sT): numerator and denominator polynomials."""
    import control  # the design side: python-control's pade

    num, den = control.pade(T, order)
    return np.asarray(num), np.asarray(den)


def continuous_loop(delay: str = "exact", tf_s: float = 0.0):
    """L(w) = C(jw) G(jw) D(jw) with the delay D exact, Pade 1 or 2, or none."""
    g, c = plant_mm(), pid_mm(tf_s)
    T = machine().delay_s
    if delay.startswith("pade"):
        pn, pd = _pade(T, int(delay[-1]))

    def L(w):
        s = 1j * np.asarray(w, float)
        d = {"exact": np.exp(-s * T), "none": 1.0}.get(delay)
        if d is None:
            d = np.polyval(pn, s) / np.polyval(pd, s)
        return c(s) * g(s) * d

    return L


def sampled_loop(dt: float = DT_S, tf_s: float = TF_S):
    """L(w) of the twin's sampled loop: Tustin controller, ZOH plant, delay in whole ticks."""
    bm = machine()
    A, B, C, D = discretize(*tf_to_ss(pid_mm(tf_s)), dt=dt, method="tustin")
    Ag, Bg, Cg, Dg = discretize(*tf_to_ss(plant_mm()), dt=dt, method="zoh")
    n = round(bm.delay_s / dt)

    def response(A, B, C, D, *, z):
        out = np.empty(len(z), complex)
        for k, zk in enumerate(z):
            out[k] = (C @ np.linalg.solve(zk * np.eye(len(A)) - A, B) + D)[0, 0] if len(A) else D[0, 0]
        return out

    def L(w):
        w = np.asarray(w, float)
        z = np.exp(1j * np.minimum(w, math.pi / dt * (1 - 1e-9)) * dt)
        return response(A, B, C, D, z=z) * response(Ag, Bg, Cg, Dg, z=z) * z ** (-n)

    return L


def _summary(L, w_max: float = 1e5) -> dict:
    m = loop_margins(L, w_max=w_max, n=20_000 if w_max < 1e5 else 70_000)
    crossing, _w_c = popov_crossing(L, w_max=w_max, n=20_000 if w_max < 1e5 else 70_000)
    return {
        "gm_db": m.gm_db,
        "gm_hz": m.w_gm / (2 * math.pi),
        "pm_deg": m.pm_deg,
        "pm_hz": m.w_pm / (2 * math.pi),
        "ms_db": m.ms_db,
        "bw_hz": m.w_bw / (2 * math.pi),
        "popov_crossing": crossing,
        "ke_max": 1.0 / abs(crossing),
    }


def margin_variants() -> list[dict]:
    """Part 1: the four numbers and the Popov bound under each delay and derivative treatment."""
    rows = []
    for delay in ("exact", "pade2", "pade1", "none"):
        for tf_s in (0.0, TF_S):
            rows.append(
                {
                    "loop": f"continuous, delay {delay}, derivative "
                    + ("ideal" if tf_s == 0 else f"filtered {tf_s:g} s"),
                    "delay": delay,
                    "tf_s": tf_s,
                    **_summary(continuous_loop(delay, tf_s)),
                }
            )
    rows.append(
        {
            "loop": f"sampled {1 / DT_S:g} Hz as the twin (Tustin PID, tf {TF_S:g} s; ZOH plant; "
            f"{round(machine().delay_s / DT_S)}-tick delay)",
            "delay": "ticks",
            "tf_s": TF_S,
            **_summary(sampled_loop(), w_max=math.pi / DT_S * 0.999),
        }
    )
    return rows


def ke(ko_per_mm: float = anang2017.KO_PER_MM, e_max_mm: float = anang2017.E_MAX_MM) -> float:
    """Eq. (8) at the clip: cosh(KO e_max)."""
    return math.cosh(ko_per_mm * e_max_mm)


def _scaled_pid(gain: float, axis: str = "x"):
    c = anang2017.pid(TF_S)
    return error_feedback(SisoTf(np.asarray(c.num) * gain, c.den), DT_S, axes=(axis,), name=f"K PID.{axis}")


def _grows(error: np.ndarray, dt: float) -> bool:
    """Whether the tick-to-tick change of the error grows from 0.25-0.35 s to 0.65-0.75 s."""
    if not np.isfinite(error).all():
        return True
    de = np.abs(np.diff(error))
    early, late = (de[int(a / dt) : int(b / dt)].max() for a, b in ((0.25, 0.35), (0.65, 0.75)))
    return not (late <= early and np.isfinite(late))


def critical_gain(run, lo: float = 2.0, hi: float = 4.5, rel_tol: float = 2e-3) -> float:
    """Smallest constant gain K in front of the PID whose step response oscillates with a growing
    amplitude, by bisection; ``run(K)`` returns the error series (m) of a 0.1 mm step."""
    while (hi - lo) > rel_tol * lo:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if not _grows(run(mid), DT_S) else (lo, mid)
    return 0.5 * (lo + hi)


def _step(n: int) -> np.ndarray:
    ref = np.zeros((n, 3))
    ref[:, 0] = 1e-4
    return ref


def critical_gains(twin: bool = True) -> dict:
    """Part 2's test in time: the critical gain of the sampled loop on the transfer functions
    and on the twin (0.8 s runs of a 0.1 mm step), beside 10^(GM/20) of the sampled loop."""
    bm = machine()
    n = int(0.8 / DT_S)
    step = _step(n)

    def tf_run(k):
        pos, _ = tf_loop(bm.plant[0][0], _scaled_pid(k), step, dt=DT_S, delay_s=bm.delay_s)
        return step[:, 0] - pos

    def twin_run(k):
        from twin.errors import SimulationDiverged
        from twin.references import Step

        try:
            res = simulate(
                bm, [_scaled_pid(k, a) for a in ("x", "y")], Step(1e-4, n_axes=2, axes=(0,)), 0.8, DT_S, progress=False
            )
        except SimulationDiverged:
            return np.full(n, np.inf)
        return res.error_m()[:, 0]

    out: dict[str, Any] = {"tf_loop": critical_gain(tf_run)}
    if twin:
        out["twin"] = critical_gain(twin_run)
    return out


def sine_reference(f_hz: float, a_mm: float, n: int) -> np.ndarray:
    """Position (m), velocity, acceleration of ``a_mm`` sin(2 pi f t) at ``n`` ticks: (n, 3)."""
    return np.asarray(SumOfSines((a_mm * 1e-3,), (f_hz,), n_axes=1).sample(np.arange(n) * DT_S)).reshape(n, -1, 3)[:, 0]


def _metrics(error_m: np.ndarray) -> dict:
    """Max |e| and RMSE (mm) over the steady window; inf for a loop that diverged."""
    e = error_m[int(STEADY_FROM_S / DT_S) :]
    with np.errstate(all="ignore"):
        return {"max_mm": float(np.abs(e).max() * 1e3), "rmse_mm": float(np.sqrt(np.mean(e**2)) * 1e3)}


def table_case(
    f_hz: float,
    a_mm: float,
    rpm: float | None,
    *,
    controller: str,
    twin: bool,
    duration_s: float = DURATION_S,
    npid_params: dict | None = None,
) -> dict:
    """One cell of Tables 1-3: the transfer-function loop and (``twin``) the twin."""
    bm = machine()
    n = round(duration_s / DT_S)
    ref = sine_reference(f_hz, a_mm, n)
    params = npid_params if controller == "anang2017_npid" and npid_params else {}
    out: dict[str, Any] = {}
    force_V = None
    if twin:
        dist = () if rpm is None else (EndMilling(spindle_rpm=rpm, **CUT),)
        res = simulate(
            bm,
            make_controller(controller, DT_S, params, axes=("x", "y")),
            SumOfSines((a_mm * 1e-3,), (f_hz,), n_axes=2, axes=(0,)),
            duration_s,
            DT_S,
            disturbances=dist,
            progress=False,
        )
        out["twin"] = _metrics(res.error_m()[:, 0])
        force_V = res.workpiece_force_N[:, 0] * GoogolXY.volts_per_newton(bm.params, bm.model, "x")
    pos, _ = tf_loop(
        bm.plant[0][0],
        make_controller(controller, DT_S, params),
        ref,
        dt=DT_S,
        delay_s=bm.delay_s,
        plant_dist_V=force_V,
    )
    out["tf_loop"] = _metrics(ref[:, 0] - pos)
    return out


def reduction_pct(pid: float, npid: float) -> float:
    """Error reduction of the NPID against the PID (%): (PID - NPID) / PID x 100.  On the maximum
    tracking errors it is the paper's Table 3 (its 33.03 % is (0.0757 - 0.0507) / 0.0757 of
    Table 2); on the RMSE it is eq. (9) (whose absolute value hides a growth of the error)."""
    return (pid - npid) / pid * 100.0


def tables(twin: bool = True, duration_s: float = DURATION_S, progress=None) -> list[dict]:
    """Tables 1-3: every reference, spindle speed and controller, and the NPID's reduction of the
    maximum error (Table 3's metric, ``max_reduction_pct_<side>``) and of the RMSE (eq. (9),
    ``rmse_reduction_pct_<side>``)."""
    rows = []
    for f, a in REFERENCES:
        for rpm in SPINDLES_RPM:
            row: dict[str, Any] = {"f_hz": f, "a_mm": a, "rpm": rpm}
            for ctrl in ("anang2017_pid", "anang2017_npid"):
                row[ctrl] = table_case(f, a, rpm, controller=ctrl, twin=twin, duration_s=duration_s)
                if progress:
                    progress()
            for side in ("tf_loop", "twin") if twin else ("tf_loop",):
                pid, npid = row["anang2017_pid"][side], row["anang2017_npid"][side]
                row[f"max_reduction_pct_{side}"] = reduction_pct(pid["max_mm"], npid["max_mm"])
                row[f"rmse_reduction_pct_{side}"] = reduction_pct(pid["rmse_mm"], npid["rmse_mm"])
            key = (f, a) if rpm is None else (f, a, int(rpm))
            row["paper"] = (PAPER["table1"] if rpm is None else PAPER["table2"]).get(key)
            row["paper_max_reduction_pct"] = None if rpm is None else PAPER["table3"].get(key)
            rows.append(row)
    return rows


def error_unit_study(duration_s: float = DURATION_S) -> list[dict]:
    """How the NPID's RMSE reduction depends on the unit of e inside cosh (TF loop, no cutting):
    e in mm (the twin's reading: KO 6/mm, e_max 0.3 mm) or in um (KO 6/um, e_max 0.3 um)."""
    units = {"mm": {"ko_per_mm": 6.0, "e_max_mm": 0.3}, "um": {"ko_per_mm": 6000.0, "e_max_mm": 0.0003}}
    rows = []
    for f, a in REFERENCES:
        pid = table_case(f, a, None, controller="anang2017_pid", twin=False, duration_s=duration_s)["tf_loop"]
        row: dict[str, Any] = {"f_hz": f, "a_mm": a}
        for unit, params in units.items():
            npid = table_case(
                f, a, None, controller="anang2017_npid", twin=False, duration_s=duration_s, npid_params=params
            )["tf_loop"]
            stable = math.isfinite(npid["rmse_mm"]) and npid["rmse_mm"] < 10 * pid["rmse_mm"]
            row[unit] = (pid["rmse_mm"] - npid["rmse_mm"]) / pid["rmse_mm"] * 100.0 if stable else None
        rows.append(row)
    return rows


def mismatches(rows: list[dict]) -> list[str]:
    """Table numbers of the twin more than :data:`TWIN_TOL_REL` from their transfer-function
    numbers.  The critical gain is reported beside its TF number but not held to 2 %: at the
    stability boundary it magnifies the twin's one difference in phase (MuJoCo's semi-implicit
    Euler step against the exact zero-order hold: 2.9 % in gain, 0.25 dB)."""
    return [
        line
        for row in rows
        for ctrl in ("anang2017_pid", "anang2017_npid")
        if "twin" in row[ctrl]
        for line in twin_vs_tf(
            f"{ctrl} {row['f_hz']} Hz {row['a_mm']} mm rpm {row['rpm']}",
            row[ctrl]["twin"],
            row[ctrl]["tf_loop"],
            keys=("max_mm", "rmse_mm"),
            tol_rel=TWIN_TOL_REL,
        )
    ]
