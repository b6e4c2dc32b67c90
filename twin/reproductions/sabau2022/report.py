"""Tables and plots of ``twin reproduce sabau2022`` (see :mod:`twin.reproductions.sabau2022.procedure`)."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
from tqdm import tqdm

from controllers.papers import sabau2022 as s1
from twin.reproductions.sabau2022 import procedure as r
from twin.reproductions.tables import fmt, markdown_table, pair

PARTS = ("relay", "table1", "cascades", "state_feedback", "mimo", "fractional", "abc", "lmi", "trajectories")


def run(samples: int, twin_samples: int, seed: int, progress: bool) -> dict:
    """Every part as one JSON-ready dict.  ``samples``: random points of the +-10 % box for the
    exact fractional responses; ``twin_samples = 0`` leaves the twin out (the relay test's
    (Ku, Pu) then come from the TF loop); ``seed``: those points and the bee colony."""
    twin = twin_samples > 0
    out: dict[str, Any] = {
        "paper": {
            "table1": s1.TABLE1,
            "table2": s1.TABLE2,
            "eq14": s1.EQ14,
            "eq14_rise_s": s1.EQ14_RISE_S,
            "eq14_settling_s": s1.EQ14_SETTLING_S,
            "eq15_16": s1.EQ15_16,
        },
        "settings": {
            "dt_s": r.DT,
            "step_m": r.STEP_M,
            "twin": twin,
            "samples": samples,
            "seed": seed,
            "feed_mm_per_min": r.FEED_MM_PER_MIN,
        },
    }
    for part in tqdm(PARTS, desc="sabau2022", unit="part", disable=not progress, leave=False):
        if part == "relay":
            tests = [r.relay_test(d, twin) for d in (s1.RELAY_DELAY_S, 0.0)]
            side = "twin" if twin else "tf"
            out["relay"] = {
                "implied": [s1.implied_delay(a) for a in s1.AXES],
                "tests": tests,
                "used": side,
                "ku_pu": [(m["ku_V_per_mm"], m["pu_s"]) for m in tests[0][side]],
            }
        elif part == "table1":
            out["table1"] = r.table1(out["relay"]["ku_pu"], twin)
        elif part == "cascades":
            out["cascades"] = r.cascades(twin)
        elif part == "state_feedback":
            out["state_feedback"] = r.state_feedback_part(
                ("pole_placement", "lqr_classical", "lqr_energy", "pi_p_pole_placement", "pi_p_lqr"), twin
            )
            out["energy_weights"] = [dict(zip(("J", "k"), s1.energy_inertia_stiffness(a))) for a in s1.AXES]
            out["improvement_pct"] = r.improvement(out["state_feedback"], out["table1"], out["cascades"])
        elif part == "mimo":
            out["mimo"] = r.mimo_part(twin)
        elif part == "fractional":
            out["fractional"] = r.fractional_part(samples, seed, twin)
        elif part == "abc":
            out["abc"] = r.abc_part(seed, twin)
        elif part == "lmi":
            out["lmi"] = r.lmi_part(twin)
        else:
            out["trajectories"] = r.trajectories(twin)
    out["twin_vs_tf_mismatches"] = r.mismatches(out)
    out["stability_differences"] = r.stability_differences(out)
    return out


def _pair(values, fmt="{:.3g}") -> str:
    return " / ".join(fmt.format(v) for v in values)


def _steps(row: dict, axis: int) -> str:
    """``OS % ts s`` of TF | twin for one axis."""
    cells = []
    for side in ("tf", "twin"):
        if side in row:
            m = row[side][axis]
            cells.append(f"{m['overshoot_pct']:5.1f} % {m['settling_time_s']:.3f} s" if m["stable"] else "unstable")
    return " | ".join(cells)


def _disturbance(row: dict, axis: int) -> str:
    """``peak / final`` (um) of the 1 V disturbance, TF | twin, for one axis."""
    dist = row["disturbance"]
    return " | ".join(
        f"{dist[s]['peak_um'][axis]:.1f} / {dist[s]['final_um'][axis]:.1f}" for s in ("tf", "twin") if s in dist
    )


def format_report(res: dict) -> str:
    """Plain-text tables: paper | TF loop | twin, one section per design of the thesis."""
    sections = (_relay_and_table1, _cascades, _state_feedback, _fractional, _bee_colony, _lmi, _table2)
    return "\n".join(line for section in sections for line in section(res))


def _sides(res: dict) -> str:
    """The columns beside the paper's: the transfer-function loop, and the twin where it ran."""
    return "TF loop | twin" if res["settings"]["twin"] else "TF loop"


def _axis_steps(row: dict, without_ff: bool = False) -> list[str]:
    """A design's step and disturbance response per axis; with ``without_ff``, its step without
    feedforward too where it ran."""
    lines = []
    for i, a in enumerate("xy"):
        shown = without_ff and "step_without_ff" in row
        extra = f"; without feedforward {_steps(row['step_without_ff'], i)}" if shown else ""
        lines.append(f"      {a}: {_steps(row['step'], i)}; disturbance {_disturbance(row, i)}{extra}")
    return lines


def _relay_and_table1(res: dict) -> list[str]:
    """1. The relay test and Table 1's rows from it: its text lines."""
    head = _sides(res)
    rl = res["relay"]
    t0 = rl["tests"][0]
    out = [
        "Sabau (2022) reproduced on coupled_servo_xy: mm and V assumed, 1 ms control period, 1 mm steps "
        "(coupling of eq. (6) off unless said), velocity by backward difference",
        "",
        f"1. Relay test (sabau2022_relay: relay {t0['amplitude_V']:g} V, hysteresis {t0['hysteresis_mm']:g} mm, run at "
        f"{t0['control_period_s'] * 1e3:g} ms): Ku = 4 d/(pi a) (V/mm), Pu (s), x / y",
    ]
    for a, imp in zip("xy", rl["implied"]):
        out.append(
            f"  Table 1's P row implies ({a}): kp {imp['kp_V_per_mm']:.3f}, Ku {imp['ku_V_per_mm']:.3f}, "
            f"Pu {imp['pu_s']:.4f} s, a loop delay of {imp['delay_s'] * 1e3:.1f} ms"
        )
    for test in rl["tests"]:
        for side in ("tf", "twin"):
            if side in test:
                q = test[side]
                out.append(
                    f"  {test['delay_s'] * 1e3:4.0f} ms drive delay, {side:<4}: "
                    f"Ku {_pair([m['ku_V_per_mm'] for m in q])}, "
                    f"Pu {_pair([m['pu_s'] for m in q], '{:.4f}')}, amplitude "
                    f"{_pair([m['amplitude_mm'] for m in q], '{:.4f}')} mm, hysteresis lag "
                    f"{_pair([m['hysteresis_phase_deg'] for m in q], '{:.1f}')} deg"
                )
        out.append(
            f"  {test['delay_s'] * 1e3:4.0f} ms exact ultimate point: "
            f"Ku {_pair([m['ku_V_per_mm'] for m in test['exact']])}, "
            f"Pu {_pair([m['pu_s'] for m in test['exact']], '{:.4f}')}"
        )
    out += [
        "",
        f"   Table 1 from the {rl['used']} relay's (Ku, Pu), delay-free loop: settling 2 % / overshoot, "
        f"paper | {head}; [fitted]: agrees by construction (the P rows' overshoot through the relay delay "
        "derived from it, the modified rows' overshoot as the detuning's target); [check]: an independent "
        "comparison",
    ]
    names = s1.TABLE1_ROWS
    for kind, row in res["table1"].items():
        paper = res["paper"]["table1"][names[kind]]
        g = row["gains"]
        agree = row["agreement"]
        out.append(
            f"  {names[kind]:<13} kp {_pair([x['kp'] for x in g])} ki {_pair([x['ki'] for x in g])} "
            f"kd {_pair([x['kd'] for x in g])}  [overshoot {agree['overshoot']}, settling {agree['settling']}]"
        )
        for i, a in enumerate("xy"):
            out.append(f"      {a}: paper {paper[a][1]:4.0f} % {paper[a][0]:.2f} s | {_steps(row, i)}")
    return out


def _cascades(res: dict) -> list[str]:
    """2. The cascades with a P speed loop: its text lines."""
    out = [
        "",
        f"2. Cascades with a P speed loop (speed pole {s1.SPEED_LOOP_FACTOR:g} a, critically damped P, PI "
        "corner kp/10): "
        "overshoot, settling; 1 V speed disturbance at 1 s: peak / final deviation (um); coupling: X's "
        "excursion while Y steps (um)",
    ]
    for d, row in res["cascades"].items():
        g = row["gains"]
        out.append(
            f"  {d:<6} kp {_pair([x['kp'] for x in g])} 1/s, ki {_pair([x['ki'] for x in g])} 1/s^2, kd "
            f"{_pair([x['kd'] for x in g])}, kv {_pair([x['kv'] for x in g], '{:.4f}')} V/(mm/s)"
        )
        out += _axis_steps(row)
        cpl = row["coupling"]
        out.append(
            "      coupling, X while Y steps 1 mm: "
            + " | ".join(f"{cpl[s]['x_peak_um']:.2f} / {cpl[s]['x_final_um']:.2f}" for s in ("tf", "twin") if s in cpl)
        )
    return out


def _state_feedback(res: dict) -> list[str]:
    """3-5. State feedback, the energy weights and the MIMO coupling: its text lines."""
    sf = res["state_feedback"]
    out = [
        "",
        f"3-5. State feedback (poles {', '.join(f'{p:g}' for p in s1.POLES)}; PI-P adds {s1.INTEGRAL_POLE:g}) "
        "as the cascade the drive runs:",
    ]
    for d in ("pole_placement", "lqr_classical", "lqr_energy", "pi_p_pole_placement", "pi_p_lqr"):
        row = sf[d]
        g = row["gains"]
        out.append(
            f"  {d:<20} kp {_pair([x['kp'] for x in g])} ki {_pair([x['ki'] for x in g])} kv "
            f"{_pair([x['kv'] for x in g], '{:.4f}')} kr {_pair([x['kr'] for x in g])}; poles x "
            + ", ".join(f"{p[0]:.1f}{p[1]:+.1f}j" for p in row["poles"][0])
        )
        out += _axis_steps(row, without_ff=True)
    ew = res["energy_weights"]
    out.append(
        "  energy weights (eqs. 7-9): J = T_M/K_M "
        + _pair([w["J"] for w in ew], "{:.3e}")
        + " V s^2/mm, k = J omega_n^2 "
        + _pair([w["k"] for w in ew])
        + " V/mm"
    )
    out.append(
        f"  text: SISO state feedback up to {s1.STATE_FEEDBACK_GAIN_PCT:g} % better than PID / cascade; pole "
        "placement's settling time against (TF loop, x / y): "
        + "; ".join(f"{k} {_pair(v, '{:+.0f}')} %" for k, v in res["improvement_pct"].items())
    )
    m = res["mimo"]
    out.append(
        "  coupled machine, both axes step: SISO pole placement x "
        + _steps(m["pole_placement"], 0)
        + ", y "
        + _steps(m["pole_placement"], 1)
        + "; MIMO (eq. 6) x "
        + _steps(m["state_feedback_mimo"], 0)
        + ", y "
        + _steps(m["state_feedback_mimo"], 1)
    )
    return out


def _fractional(res: dict) -> list[str]:
    """6. The fractional PI of eq. (14) and the mu cascade: its text lines."""
    fr = res["fractional"]
    out = [
        "",
        f"6. Fractional PI eq. (14): Oustaloup {s1.OUSTALOUP_BAND[0]:g}..{s1.OUSTALOUP_BAND[1]:g} rad/s, order "
        f"{s1.OUSTALOUP_ORDER}: max error 0.1..100 rad/s "
        + "; ".join(
            f"{a} {q['mag_db']:.3f} dB {q['phase_deg']:.2f} deg" for a, q in zip("xy", fr["oustaloup"]["axes"])
        ),
        "  exact responses (Bromwich integral), overshoot / 2 % settling / 10-90 rise; text: "
        + ", ".join(f"{a} rise {s1.EQ14_RISE_S[a][0]:g} s settling {s1.EQ14_SETTLING_S[a][0]:g} s" for a in s1.AXES)
        + ", no overshoot:",
    ]
    for name, ms in fr["arrangements"].items():
        out.append(
            f"  {name:<46} "
            + " | ".join(
                f"{a} {q['overshoot_pct']:.1f} % {q['settling_time_s']:.3f} s {q['rise_time_10_90_s']:.3f} s"
                for a, q in zip("xy", ms)
            )
        )
    for a, f in fr["fit"].items():
        q = f["metrics"]
        out.append(
            f"  FIT (labelled): speed model x g, best g = {f['g']:.4f} on {a}: {q['overshoot_pct']:.1f} % "
            f"{q['settling_time_s']:.3f} s {q['rise_time_10_90_s']:.3f} s (miss {f['miss_s']:.3f} s)"
        )
    bands = fr["exact_random"]["bands"]
    out.append(
        f"  plain reading over the +-10 % box ({fr['exact_random']['samples']} random + 4 corners, exact): "
        + "; ".join(
            f"{a} OS {b['overshoot_pct'][0]:.1f}-{b['overshoot_pct'][1]:.1f} %, settling "
            f"{b['settling_time_s'][0]:.3f}-{b['settling_time_s'][1]:.3f} s, rise {b['rise_time_10_90_s'][0]:.3f}-"
            f"{b['rise_time_10_90_s'][1]:.3f} s"
            for a, b in zip("xy", bands)
        )
    )
    for design in ("fo_pi", "mu_cascade"):
        rows = fr[design]
        label = (
            "eq. (14), Oustaloup"
            if design == "fo_pi"
            else (f"eqs. (15)-(16) cascade (text: eq. (14) settles {s1.FRACTIONAL_FASTER_S:g} s faster than this)")
        )
        out.append(
            f"  {label}: nominal x {_steps({k: v[0] for k, v in rows.items()}, 0)}, y "
            f"{_steps({k: v[0] for k, v in rows.items()}, 1)}; corners settling (TF) x "
            + _pair([c[0]["settling_time_s"] if c[0]["stable"] else math.nan for c in rows["tf"][1:]])
            + ", y "
            + _pair([c[1]["settling_time_s"] if c[1]["stable"] else math.nan for c in rows["tf"][1:]])
            + " (nan: not settled or unstable)"
        )
    return out


def _bee_colony(res: dict) -> list[str]:
    """7. The bee colony on the LQR weights: its text lines."""
    ab = res["abc"]
    out = [
        "",
        f"7. Bee colony on LQR Q = diag(10^q1, 10^q2), R = 1, X axis (q in {ab['bounds_log10']}, "
        f"{ab['iterations']} iterations, colony {ab['population']}, seed {ab['seed']}):",
    ]
    for name in ("minimize", "required"):
        q = ab[name]
        out.append(
            f"  {name:<8} q = {_pair(q['log10_q'], '{:.3f}')}: kv {q['metrics']['k_omega']:.4f}, kp "
            f"{q['metrics']['k_theta'] / q['metrics']['k_omega']:.2f}; "
            f"settling {q['metrics']['settling_time_s']:.4f} s,"
            f" overshoot {q['metrics']['overshoot_pct']:.3f} %; cost {q['cost']:.4f} "
            f"after {q['evaluations']} evaluations;"
            " settling by iteration " + ", ".join(f"{v:.3f}" for v in q["settling_by_iteration_s"][::5])
        )
        out.append(f"           as P-P in the 1 ms loop, x: {_steps(q['step'], 0)}")
    return out


def _lmi(res: dict) -> list[str]:
    """8. The LMI pole regions: its text lines."""
    lm = res["lmi"]
    reg = lm["region"]
    out = ["", f"8. LMI regions: Re s < -{reg['alpha']:g}, damping >= {reg['damping']:g}, |s| < {reg['radius']:g}:"]
    for d in ("lmi", "pi_p_lmi"):
        row = lm[d]
        out.append(
            f"  {d:<9} in region {row['in_region']}; poles x "
            + ", ".join(f"{p[0]:.1f}{p[1]:+.1f}j" for p in row["poles"][0])
        )
        out += _axis_steps(row)
    return out


def _table2(res: dict) -> list[str]:
    """9. Table 2's fitting indices, and the twin's verdict: its text lines."""
    twin = res["settings"]["twin"]
    head = _sides(res)
    out = [
        "",
        f"9. Table 2, fitting index 100 (1 - |y - r| / |r - mean r|) per axis (%), {r.FEED_MM_PER_MIN:g} mm/min; "
        "experiments: 1 modified P, 2 pole placement as P-P, 3 PI-P (part 5) + velocity feedforward; paper | " + head,
    ]
    for path, rows in res["trajectories"].items():
        cells = []
        for e, row in enumerate(rows):
            sides = " | ".join(_pair(row[s], "{:.1f}") for s in ("tf", "twin") if s in row)
            cells.append(f"{e + 1}: {_pair(res['paper']['table2'][path][e], '{:.1f}')} | {sides}")
        out.append(f"  {path:<14} " + "; ".join(cells))
    out.append("")
    if twin:
        out.append("twin vs TF departures above 2 %: " + ("; ".join(res["twin_vs_tf_mismatches"]) or "none"))
        out.append(
            "stable on one side only (a stability boundary, not compared): "
            + ("; ".join(res["stability_differences"]) or "none")
        )
    else:
        out.append("twin left out (--twin-samples 0)")
    return out


def _step_cell(metrics: dict) -> str:
    return f"{metrics['overshoot_pct']:.1f} % {metrics['settling_time_s']:.3f} s"


def markdown_tables(res: dict) -> dict[str, str]:
    """The docs page's tables (:mod:`twin.reproductions.tables`): ``relay``, ``table1`` (with what is
    fitted and what is checked), ``state_feedback``, ``fractional`` and ``table2`` (fits)."""
    twin = res["settings"]["twin"]
    sides = ("tf", "twin") if twin else ("tf",)
    test = res["relay"]["tests"][0]
    relay = [
        [
            f"implied by Table 1's P rows ({pair([t['delay_s'] * 1e3 for t in res['relay']['implied']], '.1f')} ms)",
            pair([t["ku_V_per_mm"] for t in res["relay"]["implied"]]),
            pair([t["pu_s"] for t in res["relay"]["implied"]], ".4f"),
        ]
    ]
    for side in sides:
        relay.append(
            [
                f"{'twin' if side == 'twin' else 'TF loop'}, relay with {test['delay_s'] * 1e3:g} ms delay",
                pair([m["ku_V_per_mm"] for m in test[side]]),
                pair([m["pu_s"] for m in test[side]], ".4f"),
            ]
        )
    relay.append(
        [
            "exact ultimate point of that loop",
            pair([m["ku_V_per_mm"] for m in test["exact"]]),
            pair([m["pu_s"] for m in test["exact"]], ".4f"),
        ]
    )
    names, paper1 = s1.TABLE1_ROWS, res["paper"]["table1"]
    table1 = []
    for kind, row in res["table1"].items():
        paper, agree = paper1[names[kind]], row["agreement"]
        cells = [names[kind], pair([g["kp"] for g in row["gains"]]), pair([g["ki"] for g in row["gains"]])]
        for i, a in enumerate("xy"):
            cells.append(f"{paper[a][1]:g} % {paper[a][0]:.2f} s")
            cells.append(" | ".join(_step_cell(row[side][i]) for side in sides))
        cells += [agree["overshoot"], agree["settling"]]
        table1.append(cells)
    head1 = ["controller", "kp x / y (V/mm)", "ki x / y"]
    for a in "xy":
        head1 += [f"{a} paper OS, ts", f"{a} TF" + (" | twin" if twin else "")]
    head1 += ["overshoot agrees", "settling agrees"]
    sf = []
    for name, row in res["state_feedback"].items():
        g = row["gains"]
        step = row["step"]["tf"]
        dist = row["disturbance"]["tf"]
        cells = [
            name,
            pair([x["kp"] for x in g]),
            pair([x["ki"] for x in g]),
            pair([x["kv"] for x in g], ".3f"),
            f"{pair([m['overshoot_pct'] for m in step], '.1f')} %, "
            f"{pair([m['settling_time_s'] for m in step], '.3f')} s",
            f"{pair(dist['peak_um'], '.0f')}; {pair(dist['final_um'], '.0f')}",
        ]
        if "step_without_ff" in row:
            cells[4] += (
                f" ({pair([m['overshoot_pct'] for m in row['step_without_ff']['tf']], '.1f')} % "
                "without the feedforward)"
            )
        sf.append(cells)
    frac = res["fractional"]
    fractional = [
        [
            name,
            *(
                f"{m['overshoot_pct']:.1f} % / {fmt(m['settling_time_s'], '.3f')} / {m['rise_time_10_90_s']:.3f}"
                for m in ms
            ),
        ]
        for name, ms in frac["arrangements"].items()
    ]
    fit = frac["fit"]
    fractional.append(
        [
            "FIT: speed loop with its gain scaled by g",
            *(
                f"g = {fit[a]['g']:.3f}: {fit[a]['metrics']['overshoot_pct']:.1f} % / "
                f"{fmt(fit[a]['metrics']['settling_time_s'], '.3f')} / {fit[a]['metrics']['rise_time_10_90_s']:.3f}"
                for a in "xy"
            ),
        ]
    )
    fractional.append(
        [
            "the text",
            *(
                f"no overshoot / {res['paper']['eq14_settling_s'][a][0]} / {res['paper']['eq14_rise_s'][a][0]}"
                for a in "xy"
            ),
        ]
    )
    table2 = []
    for path, runs in res["trajectories"].items():
        paper = res["paper"]["table2"][path]
        table2.append(
            [
                path,
                *(
                    f"{pair(paper[i], '.4g')} | {pair(run['twin' if twin else 'tf'], '.1f')}"
                    for i, run in enumerate(runs)
                ),
            ]
        )
    return {
        "relay": markdown_table(["relay test", "Ku x / y (V/mm)", "Pu x / y (s)"], relay),
        "table1": markdown_table(head1, table1),
        "state_feedback": markdown_table(
            [
                "design",
                "kp x / y (1/s)",
                "ki x / y (1/s²)",
                "kv x / y (V/(mm/s))",
                "OS, settling x / y (TF)",
                "1 V disturbance (µm): peak x / y; final x / y",
            ],
            sf,
        ),
        "fractional": markdown_table(
            ["reading of eq. (14)'s loop", "x: OS / settling (s) / rise 10–90 (s)", "y: OS / settling / rise"],
            fractional,
        ),
        "table2": markdown_table(
            ["path", "experiment 1, fit x / y: paper | " + ("twin" if twin else "TF"), "experiment 2", "experiment 3"],
            table2,
        ),
    }


def write_plots(folder, results: dict) -> list[Path]:
    """Step responses (Table 1, Fig. 6, Fig. 7, Figs. 10-11, Fig. 12-13, Figs. 16-17), the bee
    colony's settling time by iteration (Fig. 14) and the trajectories (Table 2)."""
    from twin.plots import plot_folder

    plt, save, written = plot_folder(folder)

    def step_plot(groups, title, name, *, horizon=2.0, disturbance=False):
        fig, axes = plt.subplots(1, 2, figsize=(11, 4), sharey=True)
        for label, ctrl in groups:
            t, pos = r.responses(ctrl, horizon, False, disturbance=disturbance)["tf"]
            for i, ax in enumerate(axes):
                ax.plot(t, pos[:, i] * 1e3, label=label, linewidth=1)
        for i, ax in enumerate(axes):
            ax.set(title=f"{'XY'[i]} axis", xlabel="time (s)")
            ax.grid(alpha=0.3)
        axes[0].set_ylabel("position (mm), 1 mm step")
        axes[1].legend(fontsize=8)
        fig.suptitle(f"Sabau 2022 {title} (TF loop, 1 ms)")
        save(fig, name)

    ku_pu = results["relay"]["ku_pu"]
    step_plot(
        [(row, r.zn_controller(k, ku_pu)) for k, row in s1.TABLE1_ROWS.items()],
        "Table 1: Ziegler-Nichols from the relay test",
        "sabau2022_table1.png",
    )
    step_plot(
        [(d, r.controller(d)) for d in ("p_p", "pi_p", "p_pid")],
        "Fig. 6: cascades, 1 V speed disturbance at 1 s",
        "sabau2022_cascades.png",
        disturbance=True,
    )
    step_plot(
        [(d, r.controller(d)) for d in ("pole_placement", "lqr_classical", "lqr_energy")],
        "Fig. 7: state feedback as P-P",
        "sabau2022_state_feedback.png",
    )
    step_plot(
        [
            (f"{d}{' ' if ff else ' without '}feedforward", r.controller(d, feedforward=ff))
            for d in ("pi_p_pole_placement", "pi_p_lqr")
            for ff in (True, False)
        ],
        "Figs. 10-11: PI-P from integral state feedback",
        "sabau2022_pi_p.png",
    )
    step_plot(
        [(d, r.controller(d)) for d in ("lmi", "pi_p_lmi")],
        "Figs. 16-17: LMI regions, 1 V disturbance at 1 s",
        "sabau2022_lmi.png",
        disturbance=True,
    )
    step_plot(
        [("eq. (14) Oustaloup, unity loop", r.controller("fo_pi")), ("eqs. (15)-(16)", r.controller("mu_cascade"))],
        "Figs. 12-13: fractional PI and structured-mu cascade",
        "sabau2022_fractional.png",
        horizon=5.0,
    )

    fig, ax = plt.subplots(figsize=(7, 4))
    for name in ("minimize", "required"):
        ax.plot(
            np.arange(1, len(results["abc"][name]["settling_by_iteration_s"]) + 1),
            results["abc"][name]["settling_by_iteration_s"],
            marker="o",
            markersize=3,
            label=f"cost: {name}",
        )
    ax.axhline(r.ABC_REQUIRED_SETTLING_S, color="k", linewidth=0.6, linestyle="--")
    ax.set(
        xlabel="iteration",
        ylabel="settling time of the best (s)",
        title="Sabau 2022 Fig. 14: ABC on LQR weights, X axis",
    )
    ax.grid(alpha=0.3)
    ax.legend()
    save(fig, "sabau2022_abc.png")

    if results["settings"]["twin"]:
        fig, axes = plt.subplots(2, 2, figsize=(10, 10))
        for ax, path in zip(axes.ravel(), r.TRAJECTORIES):
            ref = r.trajectory_run(path, 1).ref[:, :, 0] * 1e3
            ax.plot(*ref.T, color="0.6", linewidth=2, label="reference")
            for e in (1, 2, 3):
                ax.plot(*(r.trajectory_run(path, e).table_position_m() * 1e3).T, linewidth=0.8, label=f"experiment {e}")
            ax.set(aspect="equal", title=path, xlabel="x (mm)", ylabel="y (mm)")
            ax.grid(alpha=0.3)
        axes[0, 0].legend(fontsize=8)
        fig.suptitle("Sabau 2022 Table 2 trajectories on the twin")
        save(fig, "sabau2022_trajectories.png")
    return written


def twin_runs() -> dict:
    """The twin's Table 2 runs of experiment 3, by path."""
    return {path_name.replace(" ", "_"): r.trajectory_run(path_name, 3) for path_name in r.TRAJECTORIES}
