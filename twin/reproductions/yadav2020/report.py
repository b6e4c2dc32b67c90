"""Tables and plots of ``twin reproduce yadav2020`` (see :mod:`twin.reproductions.yadav2020.procedure`)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from twin.reproductions.base import mismatch_lines
from twin.reproductions.tables import fmt, markdown_table
from twin.reproductions.yadav2020 import procedure as r


def run(samples: int, twin_samples: int, seed: int, progress: bool) -> dict:
    """Every number of the reproduction (:func:`run_all`)."""
    return run_all(samples, twin_samples, seed, progress=progress)


def twin_runs() -> dict:
    """The nominal twin step runs of Table 2, by controller."""
    nominal = r.nominal_params()
    return {name: r.twin_step_result(c, nominal) for name, c in r.TABLE2_CONTROLLERS.items()}


#: The scenario controller kinds whose certificate this reproduction computes, by Table 2 name.
CERTIFIED = {"yadav2020_robust_pi": "robust_pi", "yadav2020_imc": "imc", "yadav2020_hinf_reduced": "hinf"}


def certificates(machine: str, controller: str | None, symbols: set[str], others: list[str]) -> list[dict]:
    """Yadav 2020's Kharitonov verdict and stability margin over Table 1's box (K1, K2, m, Im) for
    its three controllers on ``cncmt``, when a sweep varies nothing else."""
    if not (machine == "cncmt" and controller in CERTIFIED and symbols <= {"K1", "K2", "m", "Im"} and not others):
        return []
    row = next(row for row in r.interval_table() if row["controller"] == CERTIFIED[controller])
    return [
        {
            "source": "Yadav 2020, Kharitonov over Table 1's box (K1, K2, m, Im)",
            "kharitonov_robustly_stable": bool(row["kharitonov_stable"]),
            "stability_margin": float(row["sm"]),
            "family_stable": bool(row["family_stable"]),
            "note": "SM < 0: Kharitonov cannot prove stability; family_stable: every member checked",
        }
    ]


def run_all(mc_samples: int = 1000, twin_random: int = 20, seed: int = 0, progress: bool = True) -> dict:
    """Every part of the reproduction, as one JSON-ready dict."""
    t2 = r.table2(mc_samples, twin_random, seed, progress)
    return {
        "interval": r.interval_table(),
        "robust_pi": r.robust_pi_designs(),
        "imc": r.imc_design(),
        "hinf": r.hinf_design(),
        "table2": t2.rows,
        "twin_vs_tf_mismatches": t2.mismatches,
        "disturbance_noise": r.disturbance_and_noise(),
        "settings": {
            "mc_samples": mc_samples,
            "twin_random": twin_random,
            "seed": seed,
            "step_horizon_s": r.HORIZON_S,
            "sample_period_s": r.DT_S,
            "disturbance_V": r.DISTURBANCE_V,
            "disturbance_start_s": r.DISTURBANCE_START_S,
            "noise_std_m": r.NOISE_STD_M,
        },
    }


def _fmt(x, spec=".4g") -> str:
    if x is None:
        return "unstable"
    if isinstance(x, tuple):  # a band
        return " to ".join(_fmt(v, spec) for v in x)
    if isinstance(x, list):  # coefficients
        return "[" + ", ".join(_fmt(v, spec) for v in x) + "]"
    return "never" if isinstance(x, float) and np.isnan(x) else format(x, spec)


def format_report(res: dict) -> str:
    """Plain-text tables: parts 2, 3, 5, 6 (paper | transfer function | twin) and 7."""
    out = ["Yadav, Pathak, Gaur (2020) reproduced: paper | ours", ""]
    out.append("Interval model from Table 1's box (exact: coefficients affine in a = K1K2n/(p^2 m + n^2 Im))")
    out.append(
        f"{'controller':<30} {'alpha1':>16} {'alpha2':>16} {'beta3':>16} {'SM eq.5':>18} "
        f"{'Kharitonov':>11} {'family':>7}"
    )
    out.append(
        "  (rows *_ours: our designs beside the printed controller they stand for; the paper's columns repeat "
        "that controller's; no SM where the loop is not of third order)"
    )
    for row in res["interval"]:
        p = row["paper"]
        ours = {k: _fmt(row.get(k)) if k in row else "-" for k in ("alpha1", "alpha2", "beta3", "sm")}
        out.append(
            f"{row['controller']:<30} {p['alpha1']:>7.4g} | {ours['alpha1']:<6} {p['alpha2']:>7.4g} | "
            f"{ours['alpha2']:<6} {p['beta3']:>7.4g} | {ours['beta3']:<6} {p['sm']:>8.5g} | "
            f"{ours['sm']:<7} {'stable' if row['kharitonov_stable'] else 'not shown':>11} "
            f"{'stable' if row['family_stable'] else 'UNSTABLE':>7}"
        )
    out += ["", "Robust PI, eqs. (18)-(19), GM 10 dB, PM 60 deg"]
    pi = res["robust_pi"]
    out.append(f"  paper:                      Kp = {pi['paper']['kp']}, Ki = {pi['paper']['ki']} (Kp/Ki = 0.84)")
    for label in ("eq17_coefficients", "box_coefficients"):
        d = pi[label]
        out.append(
            f"  ours on {label:<19} Kp = {d['kp']:.4g}, Ki = {d['ki']:.4g} (Kp/Ki = {d['kp_per_ki']:.4g}); "
            f"true nominal PM {d['nominal_pm_deg']:.1f} deg"
        )
    imc = res["imc"]
    out += [
        "",
        f"IMC, mu = 1, lambda = 2: C = ({imc['num'][0]:.4g} s + {imc['num'][1]:.4g})/(s + {imc['den'][1]:.4g}) "
        f"| paper (0.21 s + 2)/(s + 2)",
        f"  {imc['reduction']}",
        "  Table 3 (mu, xi, wn, pole, 4/(xi wn), 2 % ST):",
    ]
    for row, paper in zip(imc["table3"], imc["paper_table3"]):
        out.append(
            f"    mu {row['mu_s']:>4}: xi {paper[1]} | {row['damping']:.3f}, wn {paper[2]} | {row['wn_rad_s']:.3f}, "
            f"pole {paper[3]} | {row['pole']:.3f}, ST {paper[4]} | {row['st_4_over_xi_wn_s']:.3f} "
            f"(2 % ST {row['st_2pct_s']:.3f} s)"
        )
    h = res["hinf"]
    out += [
        "",
        f"H-infinity (integrator shifted to -{h['integrator_shift_eps']:g}): optimal gamma {h['gamma_opt']:.4f} "
        f"(theta {h['theta_opt']:.4g}; {h['iterations']} bisections, set by our bracket "
        f"{h['gamma_bracket'][0]:g}-{h['gamma_bracket'][1]:g} and relative tolerance {h['gamma_rel_tol']:g}, "
        f"not the paper's 'iteration number 14') | paper theta {h['paper_theta']} (gamma {1 / h['paper_theta']:.2f})",
    ]
    for key, label in (
        ("controller_at_paper_gamma", "central controller at the paper's gamma"),
        ("paper_eq28", "paper eq. (28)"),
        ("reduced_eq28", "balred(eq. 28, 1)"),
        ("reduced_at_paper_gamma", "balred(ours at paper gamma, 1)"),
        ("paper_eq29", "paper eq. (29)"),
        ("controller_opt", "central controller at optimal gamma"),
        ("reduced_opt", "balred(optimal, 1)"),
    ):
        c = h[key]
        out.append(f"  {label:<38} num {_fmt(np.atleast_1d(c['num']).tolist())}  den {_fmt(c['den'])}")
    out.append(
        f"  Fig. 6 claim (same singular values): max gap eq. 28 vs eq. 29 over 1e-3..1e3 rad/s = "
        f"{h['sv_gap_eq28_vs_eq29_db']:.1f} dB at {h['sv_gap_eq28_vs_eq29_at_rad_s']:.3g} rad/s; "
        f"above 0.1 rad/s {h['sv_gap_eq28_vs_eq29_above_0p1_db']:.2f} dB"
    )
    out += [
        "",
        "Table 2: unit step (OS %, ST 2 % s, RT s: 10-90 % and 0-100 %); the paper's printed controllers, "
        "then ours (*_ours: robust PI unrounded, IMC from eq. 23, H-infinity at the paper's and the optimal "
        "gamma, full and balanced-truncated to first order)",
        f"{'controller':<30} {'source':<26} {'OS':>14} {'ST':>14} {'RT 10-90':>14} {'RT 0-100':>14}",
    ]
    keys = r.KEYS
    for name, row in res["table2"].items():
        if row["source"] == "paper":
            nom, bnd = row["paper"]["nominal"], row["paper"]["band"]
            out.append(f"{name:<30} {'paper nominal':<26} {nom[0]:>14} {nom[1]:>14} {'':>14} {nom[2]:>14}")
        else:
            out.append(f"{name:<30} (ours, beside {row['beside']})")
        for label, m in (
            ("tf nominal", row["tf_nominal"]),
            ("twin nominal", row["twin_nominal"]),
            ("tf nominal, 0.1 s delay", row["tf_nominal_with_0.1s_delay"]),
        ):
            cells = [_fmt(m[k]) for k in keys] if m else ["unstable" if label.startswith("tf") else "not run"] * 4
            out.append(f"{'':<30} {label:<26} " + " ".join(f"{c:>14}" for c in cells))
        if row["source"] == "paper":
            out.append(
                f"{'':<30} {'paper uncertain':<26} {_fmt(bnd[0]):>14} {_fmt(bnd[1]):>14} {'':>14} {_fmt(bnd[2]):>14}"
            )
        for label, key in (
            ("tf, paper's 10 samples", "tf_paper_samples"),
            ("twin, paper's 10 samples", "twin_paper_samples"),
            (f"tf, Monte Carlo {row['mc_samples']}", "tf_monte_carlo"),
            (f"twin, {row['twin_random']} random", "twin_random_samples"),
        ):
            b = row[key]
            if b is None:
                continue
            out.append(
                f"{'':<30} {label:<26} "
                + " ".join(f"{_fmt(b[k], '.3g'):>14}" for k in keys)
                + (f"  ({b['unstable']} unstable)" if b["unstable"] else "")
            )
    out += [
        "",
        f"Disturbance ({res['settings']['disturbance_V']} V input step at {res['settings']['disturbance_start_s']} s) "
        f"and encoder noise ({res['settings']['noise_std_m']} m RMS) on the nominal twin; effort of the unit step",
    ]
    out.append(
        f"{'controller':<10} {'u peak V':>10} {'u RMS V':>10} {'dist RMS m':>12} {'dist peak m':>12} "
        f"{'dist final m':>13} {'noise RMS m':>12} {'noise u RMS V':>14}"
    )
    for name, d in res["disturbance_noise"].items():
        out.append(
            f"{name:<10} {d['u_peak_V']:>10.4g} {d['u_rms_V']:>10.4g} {d['disturbance_dev_rms_m']:>12.4g} "
            f"{d['disturbance_dev_peak_m']:>12.4g} {d['disturbance_dev_final_m']:>13.4g} "
            f"{d['noise_dev_rms_m']:>12.4g} {d['noise_u_rms_V']:>14.4g}"
        )
    out += mismatch_lines(
        f"Twin vs transfer function (tolerance {r.TWIN_TOL_REL:.0%}, OS floor {r.TWIN_TOL_OS_PP} pp)",
        res["twin_vs_tf_mismatches"],
    )
    return "\n".join(out)


#: Names of the Table 2 controllers on the docs page.
LABELS = {
    "robust_pi": "robust PI (paper's 38.33 / 45.65)",
    "imc": "IMC (paper's (0.21 s + 2)/(s + 2))",
    "hinf": "H∞ (paper's eq. 29)",
    "robust_pi_ours": "robust PI, ours (38.05 / 45.12)",
    "imc_ours": "IMC, ours (eq. 23 unrounded)",
    "hinf_ours_paper_gamma": "H∞, ours at the paper's γ (order 4)",
    "hinf_ours_paper_gamma_reduced": "H∞, ours at the paper's γ, truncated to order 1",
    "hinf_ours_optimal": "H∞, ours at the optimal γ (order 4)",
    "hinf_ours_optimal_reduced": "H∞, ours at the optimal γ, truncated to order 1",
}


def _metrics_cells(m: dict | None, keys) -> list[str]:
    return [fmt(m[k], ".4g") for k in keys] if m else ["unstable"] * len(keys)


def _band_cells(b: dict | None, keys) -> list[str]:
    if b is None:
        return ["–"] * len(keys)
    return [("–" if b[k] is None else f"{b[k][0]:.3g}–{b[k][1]:.3g}") for k in keys]


def markdown_tables(res: dict) -> dict[str, str]:
    """The docs page's tables (:mod:`twin.reproductions.tables`): ``interval`` (eqs. 30-35 on Table 1's
    box), ``designs`` (the design procedures beside the paper's numbers), ``table2`` (unit step,
    the paper's printed controllers and ours) and ``disturbance`` (Figs. 11-13's signals, ours)."""
    interval = []
    for row in res["interval"]:
        p = row["paper"]
        cells = [LABELS[row["controller"]]]
        for key in ("alpha1", "alpha2", "beta3", "sm"):
            cells.append(f"{p[key]:.5g} / {fmt(row.get(key), '.3g')}")
        cells += ["yes" if row["kharitonov_stable"] else "no", "stable" if row["family_stable"] else "unstable"]
        interval.append(cells)
    pi, imc, h = res["robust_pi"], res["imc"], res["hinf"]
    eq17, box = pi["eq17_coefficients"], pi["box_coefficients"]
    designs = [
        [
            "robust PI on eq. (17)'s coefficients (7.5, 3, 6)",
            f"Kp {pi['paper']['kp']}, Ki {pi['paper']['ki']}",
            f"Kp {eq17['kp']:.2f}, Ki {eq17['ki']:.2f} (Kp/Ki {eq17['kp_per_ki']:.4f}); true nominal PM "
            f"{eq17['nominal_pm_deg']:.1f}°",
        ],
        [
            "robust PI on the box's coefficients",
            "–",
            f"Kp {box['kp']:.4g}, Ki {box['ki']:.4g}; true nominal PM {box['nominal_pm_deg']:.1f}°",
        ],
        [
            "IMC, μ = 1, λ = 2 (eq. 23)",
            "(0.21 s + 2)/(s + 2)",
            f"({imc['num'][0]:.4f} s + {imc['num'][1]:.4g})/(s + {imc['den'][1]:.4g})",
        ],
        [
            "H∞ optimal γ (θ)",
            f"θ {h['paper_theta']} (γ {1 / h['paper_theta']:.1f}), 'iteration number 14'",
            f"γ {h['gamma_opt']:.4f} (θ {h['theta_opt']:.4f}); floor |W3(0) T(0)| {h['gamma_floor_W3T_at_dc']:.3f}; "
            f"{h['iterations']} bisections from our bracket {h['gamma_bracket'][0]:g}–{h['gamma_bracket'][1]:g} and "
            f"tolerance {h['gamma_rel_tol']:g}",
        ],
        [
            "H∞ central controller at the paper's γ (eq. 28)",
            _poly(h["paper_eq28"]),
            _poly(h["controller_at_paper_gamma"]),
        ],
        [
            "balanced truncation to order 1 (eq. 29)",
            _poly(h["paper_eq29"]),
            f"{_poly(h['reduced_at_paper_gamma'])} (of ours); {_poly(h['reduced_eq28'])} (of eq. 28)",
        ],
        [
            "H∞ at the optimal γ, full and truncated",
            "–",
            f"{_poly(h['controller_opt'])}; truncated {_poly(h['reduced_opt'])}",
        ],
        [
            "Fig. 6: eq. (28) and (29) have the same singular values",
            "claimed",
            f"{h['sv_gap_eq28_vs_eq29_above_0p1_db']:.2f} dB apart above 0.1 rad/s, "
            f"{h['sv_gap_eq28_vs_eq29_db']:.1f} dB at "
            f"{h['sv_gap_eq28_vs_eq29_at_rad_s']:g} rad/s",
        ],
    ]
    keys = ("overshoot_pct", "settling_time_s", "rise_time_10_90_s", "rise_time_0_100_s")
    table2 = []
    for name, row in res["table2"].items():
        label = LABELS[name]
        if row["source"] == "paper":
            nom, bnd = row["paper"]["nominal"], row["paper"]["band"]
            table2.append([label, "paper, nominal", nom[0], nom[1], "", nom[2]])
            table2.append(
                [
                    "",
                    "paper, uncertain",
                    f"{bnd[0][0]}–{bnd[0][1]}",
                    f"{bnd[1][0]}–{bnd[1][1]}",
                    "",
                    f"{bnd[2][0]}–{bnd[2][1]}",
                ]
            )
            first = ""
        else:
            first = label
        table2.append([first, "TF, nominal", *_metrics_cells(row["tf_nominal"], keys)])
        table2.append(
            [
                "",
                "twin, nominal",
                *(_metrics_cells(row["twin_nominal"], keys) if row["twin_nominal"] else ["not run"] * len(keys)),
            ]
        )
        bands = [
            ("TF, the paper's 10 samples", row["tf_paper_samples"]),
            ("twin, the paper's 10 samples", row["twin_paper_samples"]),
            (f"TF, Monte Carlo {row['mc_samples']}", row["tf_monte_carlo"]),
        ]
        for source, band in bands:
            if band is not None:
                note = f" ({band['unstable']} unstable)" if band["unstable"] else ""
                table2.append(["", source + note, *_band_cells(band, keys)])
        table2.append(
            ["", "TF nominal with eq. (2)'s 0.1 s delay", *_metrics_cells(row["tf_nominal_with_0.1s_delay"], keys)]
        )
    disturbance = [
        [
            LABELS[name],
            f"{d['u_peak_V']:.3g}",
            f"{d['u_rms_V']:.3g}",
            f"{d['disturbance_dev_rms_m']:.2g} / {d['disturbance_dev_final_m']:.2g}",
            f"{d['noise_dev_rms_m']:.2g}",
        ]
        for name, d in res["disturbance_noise"].items()
    ]
    return {
        "interval": markdown_table(
            [
                "controller",
                "α1 paper / box",
                "α2 paper / box",
                "β3 paper / box",
                "SM paper / box",
                "Kharitonov proves stability",
                "actual family",
            ],
            interval,
        ),
        "designs": markdown_table(["design", "paper", "ours"], designs),
        "table2": markdown_table(
            ["controller", "source", "OS %", "ST 2 % (s)", "RT 10–90 % (s)", "RT 0–100 % (s)"], table2
        ),
        "disturbance": markdown_table(
            [
                "controller",
                "u peak (V)",
                "u RMS (V)",
                "disturbance: RMS / final deviation (m)",
                "noise: RMS deviation (m)",
            ],
            disturbance,
        ),
    }


def _poly(c: dict) -> str:
    """A transfer function's coefficients, highest power first, as (num)/(den)."""

    def side(coeffs):
        return "[" + ", ".join(f"{v:.4g}" for v in (coeffs if isinstance(coeffs, list) else [coeffs])) + "]"

    return f"{side(c['num'])}/{side(c['den'])}"


def _stable_series(ctrl, params) -> tuple[np.ndarray, np.ndarray]:
    """The step response of a loop the paper's controllers keep stable (Figs. 7-9)."""
    series = r.tf_step_series(ctrl, params)
    if series is None:
        raise ValueError(f"the loop is unstable at {params}")
    return series


def write_plots(directory: Path, results: dict | None = None) -> list[Path]:
    """PNG step responses as Figs. 7-10: per controller the nominal response with the band of
    the paper's 10 samples (transfer functions) and the nominal twin, then all three nominal."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    directory.mkdir(parents=True, exist_ok=True)
    nominal = r.nominal_params()
    written, nominal_curves = [], {}
    for fig_no, (name, ctrl) in zip((7, 8, 9), r.TABLE2_CONTROLLERS.items()):
        samples = np.array([_stable_series(ctrl, p)[1] for p in r.paper_samples()])
        t, y_tf = _stable_series(ctrl, nominal)
        twin = r.twin_step_result(ctrl, nominal)
        nominal_curves[name] = (t, y_tf)
        fig, ax = plt.subplots(figsize=(7, 4))
        ax.fill_between(
            t,
            samples.min(axis=0),
            samples.max(axis=0),
            color="tab:blue",
            alpha=0.2,
            label="paper's 10 samples (TF), band",
        )
        ax.plot(t, y_tf, color="tab:blue", label="nominal, transfer function")
        ax.plot(twin.t_s, twin.table_position_m()[:, 0], "--", color="tab:red", label="nominal, MuJoCo twin")
        ax.set(xlabel="time (s)", ylabel="table position (m), unit step", title=f"Fig. {fig_no}: {name}")
        ax.grid(True, alpha=0.3)
        ax.legend()
        path = directory / f"yadav2020_fig{fig_no}_{name}.png"
        fig.savefig(path, dpi=120, bbox_inches="tight")
        plt.close(fig)
        written.append(path)
    fig, ax = plt.subplots(figsize=(7, 4))
    for name, (t, y) in nominal_curves.items():
        ax.plot(t, y, label=name)
    ax.set(xlabel="time (s)", ylabel="table position (m), unit step", title="Fig. 10: nominal, all controllers")
    ax.grid(True, alpha=0.3)
    ax.legend()
    path = directory / "yadav2020_fig10_nominal.png"
    fig.savefig(path, dpi=120, bbox_inches="tight")
    plt.close(fig)
    return [*written, path]
