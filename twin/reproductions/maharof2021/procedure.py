"""Maharof 2021: the cascade P/PI designed for the thesis's margins, the IMBDO's
Q-filter from robust stability, the harmonic disturbance force observer (DFO), and the
thesis's numerical cases on the transfer-function loop and the twin.

- Design: :func:`controllers.papers.maharof2021.design_cascade` on eq. (1) of Anang 2017 with the
  1.2 ms delay and the encoder's backward-difference velocity at 10 kHz.
- IMBDO: Q = 1/(tau s + 1)^2 (order = the plant's relative degree), cutoff the largest round
  frequency with sup |Q Delta| <= 0.5 for the delay unmodelled and a +-20 % gain
  (:mod:`controllers.design.dob`).
- DFO: :func:`controllers.blocks.harmonic_observer` at the disturbance's frequencies,
  bandwidth 5 Hz, on the same 100 Hz inverse-model signal; combined with the IMBDO it
  estimates what the IMBDO leaves.
- Cases: references 10 mm at 0.5 Hz and 0.5 mm at 1 Hz, input disturbances of one (0.2 Hz),
  two (0.2, 0.5) and three (0.2, 0.5, 0.8 Hz) harmonics of 0.01 V each (about 290 N on this
  model; the thesis gives no amplitudes), seeded phases, 10 s at 10 kHz.  Metrics over
  t >= 2 s: maximum tracking error, RMSE, the error's spectral line at each harmonic (Hann
  window), and the same for the disturbance's own share of the error (the run minus the same
  configuration's run without disturbance).
"""

from __future__ import annotations

import math
from functools import lru_cache
from typing import Any

import numpy as np

from controllers import make_controller
from controllers.blocks import with_correction
from controllers.design.dob import delay_and_gain_error, q_cutoff, q_response
from controllers.papers import maharof2021
from controllers.registry import Context, make_observers
from twin.disturbances.drive_input import HarmonicInput
from twin.machines.googol import GoogolXY
from twin.machining.cutting import EndMilling
from twin.references import SumOfSines
from twin.reproductions.anang2017.procedure import CUT, DT_S, TWIN_TOL_REL, machine, sine_reference
from twin.reproductions.base import twin_vs_tf
from twin.sim.runner import simulate
from twin.sim.tf_loop import tf_loop

# the machine, its control period, the cut and the 2 % check are Anang 2017's (the same table)
DURATION_S, STEADY_FROM_S = 10.0, 2.0
REFERENCES = ((10.0, 0.5), (0.5, 1.0))  # mm, Hz
DISTURBANCE_V, BANDWIDTH_HZ, GAIN_ERROR = 0.01, 5.0, 0.2
CONFIGURATIONS = {"cascade": None, "imbdo": "inverse_model", "dfo": "harmonic", "imbdo_dfo": "inverse_model_harmonic"}
#: Reference feedforward on the cascade (ours; the thesis states none): none (the thesis's
#: cascade as designed), the reference velocity into the velocity loop, and that plus the
#: model's velocity and acceleration terms on the drive (:func:`model_feedforward`).
FEEDFORWARDS = ("none", "velocity", "velocity_acceleration")
#: Disturbance amplitudes (V per harmonic) of the amplitude study: the conclusion's dependence
#: on the assumed 0.01 V.
AMPLITUDES_V = (0.001, 0.01, 0.1, 1.0)
#: The thesis's headline reductions of IMBDO plus DFO against the cascade alone (%).
THESIS: dict[str, Any] = {
    "mte_pct": (97.52, 98.70, 99.13),
    "rmse_pct": (98.80, 97.75, 97.97),
    "fft_pct": ((99.78,), (99.67, 99.53), (99.86, 99.81, 99.91)),
}


def design() -> dict:
    """The cascade's gains and margins beside the thesis's, and the IMBDO's Q-filter."""
    bm = machine()
    d = maharof2021.design_cascade(bm.plant[0][0], bm.delay_s, DT_S)
    cutoff, worst = q_filter()

    def loop(m):
        return {"gm_db": m.gm_db, "gm_hz": m.w_gm / (2 * math.pi), "pm_deg": m.pm_deg, "pm_hz": m.w_pm / (2 * math.pi)}

    return {
        "kp_pos": d["kp_pos"],
        "kp_vel": d["kp_vel"],
        "ki_vel": d["ki_vel"],
        "velocity": loop(d["velocity"]),
        "position": loop(d["position"]),
        "thesis_velocity": {
            "gm_db": maharof2021.VELOCITY_GM_DB,
            "gm_hz": maharof2021.VELOCITY_GM_HZ,
            "pm_deg": maharof2021.VELOCITY_PM_DEG,
            "pm_hz": maharof2021.VELOCITY_PM_HZ,
        },
        "thesis_position": {
            "gm_db": maharof2021.POSITION_GM_DB,
            "gm_hz": maharof2021.POSITION_GM_HZ,
            "pm_deg": maharof2021.POSITION_PM_DEG,
            "pm_hz": maharof2021.POSITION_PM_HZ,
        },
        "q_cutoff_hz": cutoff,
        "q_order": 2,
        "sup_q_delta": worst,
        "gain_error": GAIN_ERROR,
    }


def model_feedforward() -> dict:
    """Feedforward gains from eq. (1), G = b0 / (s^2 + a1 s + a0) in m/V: the reference velocity
    into the velocity loop, and ``u_ff = (a1 v_ref + a_ref) / b0`` on the drive (V per m/s and
    per m/s^2): the inverse model but for its a0 term (0.25 % of u at 0.5 Hz) and the delay."""
    g = machine().plant[0][0]
    num, den = np.asarray(g.num, float), np.asarray(g.den, float)
    b0 = num[-1] / den[0]
    return {
        "velocity_ref_ff": 1.0,
        "velocity_ff_V_s_per_m": float(den[1] / den[0] / b0),
        "acceleration_ff_V_s2_per_m": float(1.0 / b0),
    }


def controller(
    config: str,
    harmonics,
    *,
    axes=("x",),
    bandwidth_hz: float = BANDWIDTH_HZ,
    cutoff_hz: float | None = None,
    feedforward: str = "none",
):
    """The cascade for ``axes``, with the configuration's observer (DFO at ``harmonics`` with
    ``bandwidth_hz``; the inverse-model cutoff of :func:`q_filter` unless ``cutoff_hz``) and one
    of :data:`FEEDFORWARDS` (ours: the thesis states none)."""
    bm = machine()
    plants = {a.name: bm.plant[i][i] for i, a in enumerate(bm.axes)}
    ff = model_feedforward()
    velocity_ff = ff["velocity_ff_V_s_per_m"] if feedforward == "velocity_acceleration" else 0.0
    acceleration_ff = ff["acceleration_ff_V_s2_per_m"] if feedforward == "velocity_acceleration" else 0.0
    params = {} if feedforward == "none" else {"velocity_ref_ff": ff["velocity_ref_ff"]}
    ctrl = make_controller(
        "maharof2021_cascade",
        DT_S,
        params,
        velocity_ff=velocity_ff,
        acceleration_ff=acceleration_ff,
        axes=axes,
        plants=plants,
        delay_s=bm.delay_s,
    )
    kind = CONFIGURATIONS[config]
    if kind is None:
        return ctrl
    params = {"cutoff_hz": cutoff_hz or q_filter()[0], "order": 2}
    if kind != "inverse_model":
        params |= {"frequencies_hz": list(harmonics), "bandwidth_hz": bandwidth_hz}
    ctx = Context(DT_S, tuple(axes), plants=plants, delay_s=bm.delay_s)
    return with_correction(ctrl, make_observers(kind, params, ctx))


@lru_cache(maxsize=1)
def q_filter() -> tuple[float, float]:
    """The IMBDO's Q cutoff (Hz) and its sup |Q Delta| (:func:`design`), computed once."""
    return q_cutoff(2, delay_and_gain_error(machine().delay_s, GAIN_ERROR))


def _disturbance(harmonics, seed: int = 0, amplitude_V: float = DISTURBANCE_V) -> HarmonicInput:
    return HarmonicInput(
        amplitudes_V=(amplitude_V,) * len(harmonics), frequencies_hz=tuple(harmonics), n_axes=2, axes=(0,), seed=seed
    )


def _metrics(error_m: np.ndarray, harmonics, search_hz: float = 0.0) -> dict:
    """MTE and RMSE (um) over t >= :data:`STEADY_FROM_S`, and the error's largest spectral line
    (um, Hann window) within ``search_hz`` of each harmonic (the nearest bin for 0)."""
    e = error_m[int(STEADY_FROM_S / DT_S) :]
    window = np.hanning(len(e))
    spectrum = np.abs(np.fft.rfft(e * window)) * 2 / window.sum()
    freqs = np.fft.rfftfreq(len(e), DT_S)
    lines = [
        float(
            max(spectrum[np.argmin(np.abs(freqs - f))], spectrum[np.abs(freqs - f) <= search_hz].max(initial=0.0)) * 1e6
        )
        for f in harmonics
    ]
    return {"mte_um": float(np.abs(e).max() * 1e6), "rmse_um": float(np.sqrt(np.mean(e**2)) * 1e6), "fft_um": lines}


def run_case(
    amplitude_mm: float,
    f_hz: float,
    *,
    harmonics,
    config: str,
    twin: bool,
    duration_s: float = DURATION_S,
    feedforward: str = "none",
    amplitude_V: float = DISTURBANCE_V,
) -> dict:
    """One configuration under one reference and disturbance: TF loop and (``twin``) the twin,
    the tracking error's metrics and those of the disturbance's share."""
    bm = machine()
    n = round(duration_s / DT_S)
    t = np.arange(n) * DT_S
    ref = sine_reference(f_hz, amplitude_mm, n)
    dist = _disturbance(harmonics, amplitude_V=amplitude_V)
    d = dist.input_V(t)[:, 0]
    out: dict[str, Any] = {}
    errors = {}
    for label, u_dist in (("with", d), ("without", None)):
        pos, _ = tf_loop(
            bm.plant[0][0],
            controller(config, harmonics, feedforward=feedforward),
            ref,
            dt=DT_S,
            delay_s=bm.delay_s,
            u_dist_V=u_dist,
        )
        errors[label] = ref[:, 0] - pos
    out["tf_loop"] = {
        **_metrics(errors["with"], harmonics),
        "disturbance": _metrics(errors["with"] - errors["without"], harmonics),
    }
    if twin:
        reference = SumOfSines((amplitude_mm * 1e-3,), (f_hz,), n_axes=2, axes=(0,))
        runs: dict[str, Any] = {
            label: simulate(
                bm,
                controller(config, harmonics, axes=("x", "y"), feedforward=feedforward),
                reference,
                duration_s,
                DT_S,
                disturbances=ds,
                progress=False,
            ).error_m()[:, 0]
            for label, ds in (("with", (dist,)), ("without", ()))
        }
        out["twin"] = {
            **_metrics(runs["with"], harmonics),
            "disturbance": _metrics(runs["with"] - runs["without"], harmonics),
        }
    return out


def cases(twin: bool = True, duration_s: float = DURATION_S, progress=None, feedforward: str = "none") -> list[dict]:
    """Every reference x harmonic set x configuration, with reductions against the cascade (all
    with ``feedforward``, one of :data:`FEEDFORWARDS`)."""
    rows = []
    for amplitude, f in REFERENCES:
        for h in range(1, len(maharof2021.HARMONICS_HZ) + 1):
            harmonics = maharof2021.HARMONICS_HZ[:h]
            row: dict[str, Any] = {
                "amplitude_mm": amplitude,
                "f_hz": f,
                "harmonics_hz": list(harmonics),
                "feedforward": feedforward,
            }
            for config in CONFIGURATIONS:
                row[config] = run_case(
                    amplitude,
                    f,
                    harmonics=harmonics,
                    config=config,
                    twin=twin,
                    duration_s=duration_s,
                    feedforward=feedforward,
                )
                if progress:
                    progress()
            for side in ("tf_loop", "twin") if twin else ("tf_loop",):
                row[f"reduction_pct_{side}"] = _reductions(row, side)
            rows.append(row)
    return rows


def _reductions(row: dict, side: str) -> dict:
    """Each observer configuration in ``row``: its reductions (%) against the cascade alone of
    the tracking error's MTE and RMSE, and of the disturbance's share (MTE and each line)."""
    base = row["cascade"][side]
    out: dict[str, Any] = {}
    for config in CONFIGURATIONS:
        if config == "cascade" or config not in row:
            continue
        m = row[config][side]
        out[config] = {
            "mte": _reduction(base["mte_um"], m["mte_um"]),
            "rmse": _reduction(base["rmse_um"], m["rmse_um"]),
            "disturbance_mte": _reduction(base["disturbance"]["mte_um"], m["disturbance"]["mte_um"]),
            "disturbance_fft": [
                _reduction(a, b) for a, b in zip(base["disturbance"]["fft_um"], m["disturbance"]["fft_um"])
            ],
        }
    return out


def amplitude_study(feedforward: str = "velocity_acceleration", duration_s: float = DURATION_S) -> list[dict]:
    """How the headline reductions depend on the assumed disturbance amplitude: the
    three-harmonic case under the 10 mm, 0.5 Hz reference on the TF loop, cascade against IMBDO
    + DFO, for each of :data:`AMPLITUDES_V` (the disturbance's share scales with the amplitude,
    the following error does not)."""
    amplitude_mm, f_hz = REFERENCES[0]
    harmonics = maharof2021.HARMONICS_HZ
    rows = []
    for amplitude_V in AMPLITUDES_V:
        row: dict[str, Any] = {"amplitude_V": amplitude_V, "feedforward": feedforward}
        for config in ("cascade", "imbdo_dfo"):
            row[config] = run_case(
                amplitude_mm,
                f_hz,
                harmonics=harmonics,
                config=config,
                twin=False,
                duration_s=duration_s,
                feedforward=feedforward,
                amplitude_V=amplitude_V,
            )
        red = _reductions(row, "tf_loop")["imbdo_dfo"]
        row["reduction_pct"] = {"mte": red["mte"], "rmse": red["rmse"]}
        rows.append(row)
    return rows


#: Milling cases: the thesis's spindle speeds, the bundled slot cut (anang2017_sine_cutting.toml),
#: the DFO at the first two tooth harmonics with its bandwidth 1.5 times the higher one and the
#: inverse-model signal at 500 Hz (with the delay matched, a +-20 % gain error keeps
#: |Q Delta| <= 0.2 at any cutoff).
SPINDLES_RPM = (1500.0, 2500.0, 3000.0)
MILLING_CUTOFF_HZ = 500.0


def milling_case(rpm: float, config: str, duration_s: float = DURATION_S) -> dict:
    """Twin and TF loop under the mechanistic milling force (10 mm at 0.5 Hz): the TF loop takes
    the twin's force of the same configuration as an equivalent voltage at the plant."""
    bm = machine()
    tooth_hz = rpm / 60.0 * CUT["n_flutes"]
    harmonics = (tooth_hz, 2 * tooth_hz)
    n = round(duration_s / DT_S)
    ref = sine_reference(0.5, 10.0, n)
    reference = SumOfSines((0.01,), (0.5,), n_axes=2, axes=(0,))

    def build(axes):
        return controller(config, harmonics, axes=axes, bandwidth_hz=1.5 * harmonics[-1], cutoff_hz=MILLING_CUTOFF_HZ)

    twin, tf = {}, {}
    for label, dist in (("with", (EndMilling(spindle_rpm=rpm, **CUT),)), ("without", ())):
        res = simulate(bm, build(("x", "y")), reference, duration_s, DT_S, disturbances=dist, progress=False)
        twin[label] = res.error_m()[:, 0]
        force_V = res.workpiece_force_N[:, 0] * GoogolXY.volts_per_newton(bm.params, bm.model, "x")
        pos, _ = tf_loop(bm.plant[0][0], build(("x",)), ref, dt=DT_S, delay_s=bm.delay_s, plant_dist_V=force_V)
        tf[label] = ref[:, 0] - pos
    # the feed reverses with the 0.5 Hz sine, so the tooth force sits at f +- 0.5 Hz, not at f
    search_hz = 1.0
    return {
        "rpm": rpm,
        "harmonics_hz": list(harmonics),
        **{
            side: {
                **_metrics(e["with"], harmonics, search_hz),
                "disturbance": _metrics(e["with"] - e["without"], harmonics, search_hz),
            }
            for side, e in (("twin", twin), ("tf_loop", tf))
        },
    }


def milling_cases(duration_s: float = DURATION_S, progress=None) -> list[dict]:
    """Every spindle speed and configuration (needs the twin: its force drives the TF loop)."""
    rows = []
    for rpm in SPINDLES_RPM:
        row: dict[str, Any] = {"rpm": rpm}
        for config in CONFIGURATIONS:
            row[config] = milling_case(rpm, config, duration_s)
            if progress:
                progress()
        rows.append(row)
    return rows


def _reduction(base: float, value: float) -> float:
    return (base - value) / base * 100.0


def disturbance_sensitivity(w: np.ndarray, harmonics) -> dict:
    """|y/d|(jw) (m/V) from an input disturbance to the position, for each configuration: the
    cascade's ``P/(1 + C_v (kp + M s) P)`` times what each observer leaves:
    IMBDO ``1 - Q e^(-jwT)``, DFO ``1 - H Q e^(-jwT)``, both the product."""
    from controllers.blocks import harmonic_estimator
    from controllers.design.cascade import backward_difference

    bm = machine()
    g, T = bm.plant[0][0], bm.delay_s
    d = maharof2021.design_cascade(g, T, DT_S)
    s = 1j * w
    P = g(s) * np.exp(-s * T)
    cv = d["kp_vel"] + d["ki_vel"] / s
    base = np.abs(P / (1 + cv * (d["kp_pos"] + backward_difference(DT_S)(w) * s) * P))
    cutoff = q_filter()[0]
    q = q_response(cutoff, 2, w) * np.exp(-s * T)
    lead = round(T / DT_S) * DT_S
    wh = 2 * math.pi * np.asarray(harmonics)
    H = harmonic_estimator(harmonics, BANDWIDTH_HZ, np.exp(1j * wh * lead) / q_response(cutoff, 2, wh))(s)
    return {
        "cascade": base,
        "imbdo": base * np.abs(1 - q),
        "dfo": base * np.abs(1 - H * q),
        "imbdo_dfo": base * np.abs((1 - q) * (1 - H * q)),
    }


def reference_loops(w: np.ndarray) -> dict:
    """|S|, |T| of the position loop and |S| of the velocity loop (reference to error and to
    position), the same with and without the observers: with the model matched, an observer's
    estimate does not depend on the command, so it leaves the reference loops unchanged."""
    from controllers.design.cascade import backward_difference

    bm = machine()
    g, T = bm.plant[0][0], bm.delay_s
    d = maharof2021.design_cascade(g, T, DT_S)
    s = 1j * w
    m = backward_difference(DT_S)(w)
    velocity = (d["kp_vel"] + d["ki_vel"] / s) * s * g(s) * np.exp(-s * T) * m
    position = d["kp_pos"] * velocity / (1 + velocity) / m / s
    return {
        "position |S|": np.abs(1 / (1 + position)),
        "position |T|": np.abs(position / (1 + position)),
        "velocity |S|": np.abs(1 / (1 + velocity)),
    }


def mismatches(rows: list[dict]) -> list[str]:
    """Tracking-error MTE and RMSE of the twin more than 2 % from the TF loop's (the harmonic
    cases; in the milling cases the TF loop replays the twin's force, so they are reported,
    not checked)."""
    return [
        line
        for row in rows
        for config in CONFIGURATIONS
        if "twin" in row[config]
        for line in twin_vs_tf(
            f"{config} {row['amplitude_mm']} mm {row['f_hz']} Hz {row['harmonics_hz']}",
            row[config]["twin"],
            row[config]["tf_loop"],
            keys=("mte_um", "rmse_um"),
            tol_rel=TWIN_TOL_REL,
        )
    ]
