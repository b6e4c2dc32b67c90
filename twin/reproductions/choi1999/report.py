"""Tables and plots of ``twin reproduce choi1999`` (see :mod:`twin.reproductions.choi1999.procedure`)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from tqdm import tqdm

from controllers.papers import choi1999 as s4
from twin.reproductions.choi1999 import procedure as r
from twin.reproductions.tables import markdown_table, pair

CONTOUR_GAIN = 300  # Fig. 12(c)'s magnification


def run(samples: int, twin_samples: int, seed: int, progress: bool) -> dict:
    """Every part as one JSON-ready dict: ``samples`` random plants per controller in the mu
    check, ``twin_samples = 0`` leaves the twin out."""
    steps = ["design", "pid", "zpetc", "mu"] + (["circles", "comparison"] if twin_samples > 0 else [])
    out: dict[str, Any] = {
        "paper": s4.PAPER,
        "settings": {
            "dt_s": s4.DT_S,
            "samples": samples,
            "seed": seed,
            "twin": twin_samples > 0,
            "position_unit_per_m": s4.POSITION_UNIT_PER_M,
        },
    }
    for step in tqdm(steps, desc="choi1999", unit="part", disable=not progress, leave=False):
        if step == "design":
            out["design"] = r.design()
        elif step == "pid":
            out["pid"] = r.pid()
        elif step == "zpetc":
            out["zpetc"] = r.zpetc_part()
        elif step == "mu":
            out["mu"] = r.mu_analysis(samples, seed)
        elif step == "circles":
            out["circles"] = r.circle_cases()
        else:
            out["comparison"] = r.controller_comparison()
    out["twin_vs_tf_mismatches"] = r.mismatches(out["circles"]) if "circles" in out else []
    return out


def _pair(values, fmt="{:.2f}") -> str:
    return " / ".join(fmt.format(v) for v in values)


def format_report(res: dict) -> str:
    """Plain-text tables: paper | TF loop | twin."""
    d, p, z, m = res["design"], res["pid"], res["zpetc"], res["mu"]
    paper = res["paper"]
    out = [
        "Choi et al. (1999) reproduced on linear_motor_xy (design positions in mm, see controllers/papers/choi1999.py)",
        "",
        "1. Glover-McFarlane loop shaping, Ws = diag(990, 660)(s+110)/(s+1500), up milling k_il -2500, k_c 2500:",
        f"  gamma_min {d['gamma_min']:.5f} (Riccati) | {d['gamma_min_sb10ad']:.5f} (SB10AD gamma-iteration on the "
        f"NCF generalized plant), difference {d['gamma_min_rel_diff']:.1e}",
        f"  gamma used {d['gamma']:.4f} = {d['gamma_factor']} gamma_min; robustness margin 1/gamma {d['margin']:.4f}; "
        f"achieved ||[K;I](I-GK)^-1 M^-1|| {d['achieved_norm']:.4f}",
        f"  orders: shaped plant {d['shaped_order']}, K_inf {d['k_inf_order']}, K = Ws K_inf {d['order']} "
        f"(paper {paper['controller_order']})",
        "  loop broken at each input: PM "
        + _pair([q["pm_deg"] for q in d["loop_at_input"]], "{:.1f}")
        + " deg at "
        + _pair([q["w_pm"] for q in d["loop_at_input"]], "{:.0f}")
        + " rad/s, GM "
        + _pair([q["gm_db"] for q in d["loop_at_input"]], "{:.1f}")
        + " dB (x / y)",
        "",
        f"2. Balanced truncation (AB09AD, square-root Schur) {d['order']} -> {d['reduced_order']} "
        f"(paper {paper['controller_order']} -> {paper['reduced_order']}), "
        f"Tustin at {res['settings']['dt_s'] * 1e3:g} ms:",
        "  Hankel singular values (V/mm): " + ", ".join(f"{h:.4g}" for h in d["hankel_V_per_mm"]),
        f"  dropped: {', '.join(f'{h:.3g}' for h in d['dropped_V_per_mm'])}; bound 2 sum = "
        f"{d['truncation_bound_V_per_mm']:.3g} V/mm; largest relative difference 1-1e4 rad/s "
        f"{d['reduction_rel_error_1_to_1e4_rad_s']:.3f}",
        "  sampled closed loop (nominal, 2 kHz): "
        + "; ".join(
            f"{k} max |pole| {v['max_pole_abs']:.4f}, peak sigma(S) {v['sensitivity_peak']:.3f}"
            for k, v in d["loops"].items()
        ),
        "",
        "3. PID per axis, ours (the paper gives no gains): diagonal plant (k_c = 0), the crossover and phase "
        "margin of the MIMO loop broken at that input, integral corner a decade below:",
    ]
    for a, g, t, q in zip("xy", p["gains"], p["targets"], p["margins"]):
        out.append(
            f"  {a}: kp {g['kp']:.4g} V/m, ki {g['ki']:.4g} V/(m s), kd {g['kd']:.4g} V s/m, "
            f"tf {g['tf_s'] * 1e6:.0f} us;"
            f" PM {q['pm_deg']:.1f} deg at {q['w_pm']:.0f} rad/s (target {t['pm_deg']:.1f} at {t['w_pm']:.0f})"
        )
    out += [
        "",
        "4. mu analysis (AB13MD upper bound, k_il and k_c as separate real scalars per axis: conservative):",
        "  controller | RS peak (rad/s) | RS max w<=80 | RP peak (rad/s) | RP max w<=5 | corners stable | random "
        "stable | 1/min destabilizing scale | worst ||Wp S|| sampled (nominal)",
    ]
    for kind in r.KINDS:
        q = m[kind]
        out.append(
            f"  {kind:<4} | {q['rs_peak']['value']:.3f} ({q['rs_peak']['w_rad_s']:.0f}) | "
            f"{q['rs_peak_below_80']['value']:.3f} | {q['rp_peak']['value']:.3f} ({q['rp_peak']['w_rad_s']:.0f}) | "
            f"{q['rp_peak_below_5']['value']:.3f} | {q['corners_stable']}/{q['corners']} | "
            f"{q['random_stable']}/{q['random']} | {q['mu_lower_from_samples']:.3f} | "
            f"{q['worst_wps_sampled']:.2f} ({q['nominal_wps']:.2f})"
        )
    claim = m["claim"]
    out.append(
        f"  paper: stable for k_il in {list(claim['paper']['k_il'])}, k_c in {list(claim['paper']['k_c'])} "
        f"(= Table 1's box: {claim['agree']}); grid 11 x 11 x m,b corners: "
        + ", ".join(f"{k} {v['unstable']} unstable of {v['points']}" for k, v in m["claim_grid"].items())
    )
    out += ["", "5. ZPETC per axis (air cut R 20 mm, 2400 mm/min, TF loop, max tracking error after 0.1 s, um x / y):"]
    for kind in r.KINDS:
        q = z[kind]
        out.append(
            f"  {kind:<4} preview {q['preview_ticks']} ticks, not inverted zeros "
            + str([[round(c[0], 4) for c in zs] for zs in q["unacceptable_zeros"]])
            + f": without {_pair(q['without']['max_tracking_settled_um'], '{:.3f}')}"
            f" | with {_pair(q['with']['max_tracking_settled_um'], '{:.3f}')}"
        )
    if "circles" in res:
        c = res["circles"]
        out += [
            "",
            "6. Circle tests in the twin (friction, 1/2 um encoders, 10 V = 982 N); after 0.1 s; um; "
            "contour to the path | to the reference point of the same instant:",
            f"  paper MIMO: air cut max tracking below {_pair(paper['air_cut_max_tracking_um'], '{:g}')}; "
            f"cutting max contour {_pair(paper['cutting_max_contour_um'], '{:g}')} (x / y axes)",
        ]
        for kind in r.KINDS:
            for case in ("air_cut", "cutting_mechanistic", "cutting_average_force"):
                q = c[kind][case]
                radius = 20.0 if case == "air_cut" else c[kind]["cutting_radius_mm"]
                out.append(
                    f"  {kind:<4} {case:<22} R {radius:g}: tracking {_pair(q['max_tracking_settled_um'])}, "
                    f"contour {q['max_contour_path_um']:.2f} | {q['max_contour_point_um']:.2f}, max |u| "
                    f"{_pair(q['max_u_V'])} V (whole run: tracking {_pair(q['max_tracking_um'])})"
                )
        out.append("  twin vs TF loop (no friction, ideal encoders), tracking x / y and contour after 0.1 s:")
        for kind in r.KINDS:
            for case in c[kind]["linear"]:
                tw, tf = case["twin"], case["tf"]
                out.append(
                    f"    {kind:<4} {case['case']:<13} twin {_pair(tw['max_tracking_settled_um'], '{:.3f}')}, "
                    f"{tw['max_contour_path_um']:.3f} | TF {_pair(tf['max_tracking_settled_um'], '{:.3f}')}, "
                    f"{tf['max_contour_path_um']:.3f}"
                )
        out.append("  departures above 2 %: " + ("; ".join(res["twin_vs_tf_mismatches"]) or "none"))
    if "comparison" in res:
        out += ["", *format_comparison(res["comparison"])]
    return "\n".join(out)


def format_comparison(comparison: dict) -> list[str]:
    """Part 4's comparison: static gains, then every controller on the same circles."""
    g = comparison["static_gains"]
    out = [
        "7. What beats what, and why: static gain (V/mm) and the twin on the same circles (air cut R 20; "
        "mechanistic cutting R 28), um, after 0.1 s",
        "  K(0) of the MIMO controller, full (order 8): "
        + str(np.round(g["mimo_full_K0_V_per_mm"], 2).tolist())
        + "; reduced (order 4): "
        + str(np.round(g["mimo_reduced_K0_V_per_mm"], 2).tolist()),
        "  MIMO diagonal loops cross over at " + _pair(g["mimo_diagonal_crossover_rad_s"], "{:.0f}") + " rad/s",
    ]
    for name in r.CONTROLLER_VARIANTS:
        if name in g:
            q = g[name]
            out.append(
                f"  {name}: kp {_pair(q['kp_V_per_mm'], '{:.1f}')} V/mm, ki {_pair(q['ki_V_per_mm_s'], '{:.4g}')} "
                f"V/(mm s), kd {_pair(q['kd_V_s_per_mm'], '{:.3f}')} V s/mm; PM {_pair(q['pm_deg'], '{:.1f}')} "
                f"deg at {_pair(q['crossover_rad_s'], '{:.0f}')} rad/s"
            )
    out.append(
        f"  {'controller':<32} | {'air: tracking x / y':>20} | {'reversal x / y':>15} | {'contour':>7} | "
        f"{'cut: tracking x / y':>20} | {'reversal x / y':>15} | {'contour path / point':>20}"
    )
    for name, runs in comparison["runs"].items():
        air, cut = runs["air_cut"], runs["cutting"]
        out.append(
            f"  {name:<32} | {_pair(air['max_tracking_settled_um']):>20} | {_pair(air['max_at_reversal_um']):>15} | "
            f"{air['max_contour_path_um']:>7.2f} | {_pair(cut['max_tracking_settled_um']):>20} | "
            f"{_pair(cut['max_at_reversal_um']):>15} | "
            f"{_pair([cut['max_contour_path_um'], cut['max_contour_point_um']]):>20}"
        )
    return out


def markdown_tables(res: dict) -> dict[str, str]:
    """The docs page's tables (:mod:`twin.reproductions.tables`): ``design`` (loop shaping and its
    reduction), ``mu`` (robust stability and performance beside sampled plants), ``zpetc``,
    ``circles`` (the paper's circle tests in the twin) and ``comparison`` (every controller on
    the same circles, with the static gains)."""
    d, paper = res["design"], res["paper"]
    design = [
        ["γ_min (Riccati)", "–", f"{d['gamma_min']:.5f}"],
        [
            "γ_min by SB10AD on the NCF generalized plant (independent)",
            "–",
            f"{d['gamma_min_sb10ad']:.5f} (difference {d['gamma_min_rel_diff']:.0e})",
        ],
        ["γ used", '"slightly suboptimal"', f"{d['gamma']:.4f} = {d['gamma_factor']} γ_min (ours)"],
        ["robustness margin 1/γ", "–", f"{d['margin']:.3f}"],
        ["order of K = Ws K_inf", paper["controller_order"], f"{d['order']} (shaped plant {d['shaped_order']})"],
        ["reduced by balanced truncation (AB09AD)", paper["reduced_order"], d["reduced_order"]],
        ["Hankel singular values dropped (V/mm)", "–", ", ".join(f"{h:.3g}" for h in d["dropped_V_per_mm"])],
        [
            "largest relative change of K by the reduction, 1–10⁴ rad/s",
            "–",
            f"{d['reduction_rel_error_1_to_1e4_rad_s']:.2f}",
        ],
        [
            "sampled loop at 2 kHz: max σ(S), full / reduced",
            "–",
            f"{d['loops']['full']['sensitivity_peak']:.2f} / {d['loops']['reduced']['sensitivity_peak']:.2f}",
        ],
        [
            "loop broken at input x / y: PM, crossover, GM",
            "–",
            f"{pair([q['pm_deg'] for q in d['loop_at_input']], '.1f')}°, "
            f"{pair([q['w_pm'] for q in d['loop_at_input']], '.0f')} rad/s, "
            f"{pair([q['gm_db'] for q in d['loop_at_input']], '.1f')} dB",
        ],
    ]
    g = res["comparison"]["static_gains"] if "comparison" in res else None
    if g is not None:
        design.append(
            [
                "K(0) of the MIMO controller, diagonal x / y (V/mm)",
                "–",
                f"full {pair(np.diag(g['mimo_full_K0_V_per_mm']), '.1f')}, "
                f"reduced {pair(np.diag(g['mimo_reduced_K0_V_per_mm']), '.1f')}",
            ]
        )
    m = res["mu"]
    mu = [
        [
            kind.upper() if kind == "pid" else "MIMO",
            f"{q['rs_peak']['value']:.3f} ({q['rs_peak']['w_rad_s']:.0f})",
            f"{q['rs_peak_below_80']['value']:.3f}",
            f"{q['rp_peak']['value']:.3f} ({q['rp_peak']['w_rad_s']:.0f})",
            f"{q['rp_peak_below_5']['value']:.3f}",
            f"{q['corners_stable']}/{q['corners']}",
            f"{q['random_stable']}/{q['random']}",
            f"{q['mu_lower_from_samples']:.3f}",
            f"{q['worst_wps_sampled']:.2f} ({q['nominal_wps']:.2f})",
        ]
        for kind, q in ((k, m[k]) for k in r.KINDS)
    ]
    z = res["zpetc"]
    zpetc = [
        [
            kind.upper() if kind == "pid" else "MIMO",
            pair(z[kind]["preview_ticks"], "d"),
            "; ".join(", ".join(f"{c[0]:.4f}" for c in zs) for zs in z[kind]["unacceptable_zeros"]),
            pair(z[kind]["without"]["max_tracking_settled_um"], ".3f"),
            pair(z[kind]["with"]["max_tracking_settled_um"], ".3f"),
        ]
        for kind in r.KINDS
    ]
    out: dict[str, Any] = {
        "design": markdown_table(["", "paper", "ours"], design),
        "mu": markdown_table(
            [
                "controller",
                "RS peak (rad/s)",
                "RS max ω ≤ 80",
                "RP peak (rad/s)",
                "RP max ω ≤ 5",
                "corners stable",
                "random stable",
                "1 / smallest destabilizing scale",
                "worst ‖Wp S‖ sampled (nominal)",
            ],
            mu,
        ),
        "zpetc": markdown_table(
            [
                "controller",
                "preview (ticks) x / y",
                "zeros left uninverted, x; y",
                "air cut max tracking after 0.1 s without ZPETC (µm)",
                "with ZPETC (µm)",
            ],
            zpetc,
        ),
    }
    if "circles" in res:
        c = res["circles"]
        names = {
            "air_cut": "air cut R 20, 2400 mm/min",
            "cutting_mechanistic": "cutting, mechanistic force",
            "cutting_average_force": "cutting, average force |k| 1800 + 20 % harmonic",
        }
        paper_cells = {
            ("mimo", "air_cut"): f"below {pair(paper['air_cut_max_tracking_um'], 'g')}",
            ("mimo", "cutting_mechanistic"): f"about {pair(paper['cutting_max_contour_um'], 'g')}",
            ("pid", "air_cut"): "larger quadrant glitches",
            ("pid", "cutting_mechanistic"): "larger than MIMO",
        }
        circles = []
        for kind in r.KINDS:
            for case, label in names.items():
                q = c[kind][case]
                radius = "" if case == "air_cut" else f", R {c[kind]['cutting_radius_mm']:g}"
                circles.append(
                    [
                        f"{'MIMO' if kind == 'mimo' else 'PID (ours)'} {label}{radius}",
                        paper_cells.get((kind, case), "–"),
                        pair(q["max_tracking_settled_um"], ".2f"),
                        pair(q["max_at_reversal_um"], ".2f"),
                        f"{q['max_contour_path_um']:.2f} / {q['max_contour_point_um']:.2f}",
                    ]
                )
        out["circles"] = markdown_table(
            ["run", "paper (µm)", "tracking x / y (µm)", "at reversals x / y (µm)", "contour to path / to point (µm)"],
            circles,
        )
    if "comparison" in res:
        comparison = []
        g = res["comparison"]["static_gains"]
        for name, runs in res["comparison"]["runs"].items():
            gains = g.get(name)
            kp = (
                pair(gains["kp_V_per_mm"], ".1f")
                if gains
                else pair(np.diag(g["mimo_full_K0_V_per_mm" if "full" in name else "mimo_reduced_K0_V_per_mm"]), ".1f")
                + " (K(0))"
            )
            air, cut = runs["air_cut"], runs["cutting"]
            comparison.append(
                [
                    name,
                    kp,
                    pair(air["max_tracking_settled_um"], ".2f"),
                    pair(air["max_at_reversal_um"], ".2f"),
                    pair(cut["max_tracking_settled_um"], ".1f"),
                    pair(cut["max_at_reversal_um"], ".1f"),
                    f"{cut['max_contour_path_um']:.1f} / {cut['max_contour_point_um']:.1f}",
                ]
            )
        out["comparison"] = markdown_table(
            [
                "controller (every PID ours)",
                "kp x / y (V/mm)",
                "air cut: tracking x / y (µm)",
                "air cut: at reversals",
                "cutting R 28: tracking x / y (µm)",
                "cutting: at reversals",
                "cutting: contour to path / point",
            ],
            comparison,
        )
    return out


def write_plots(folder, results: dict | None = None) -> list[Path]:
    """Fig. 2 (singular values), Figs. 6-7 (mu), Fig. 12 (contour x300) and Fig. 13 (inputs)."""
    from controllers.design.mimo import frequency_response
    from twin.plots import plot_folder

    plt, save, written = plot_folder(folder)

    d = s4.mimo_design()
    w = np.logspace(-1, 5, 400)
    fig, ax = plt.subplots(figsize=(7, 4.5))
    G = frequency_response(s4.design_plant(), w)
    target = frequency_response(d["design"].shaped, w)
    loop = G @ frequency_response(d["reduced"] * (1.0 / s4.POSITION_UNIT_PER_M), w)
    for resp, label, style in (
        (G, "plant G", ":"),
        (target, "target loop G Ws", "--"),
        (loop, "open loop G K (order 4)", "-"),
    ):
        sv = np.linalg.svd(resp, compute_uv=False)
        ax.loglog(w, sv[:, 0], style, color="C0" if style == "-" else "C1" if style == "--" else "C2", label=label)
        ax.loglog(w, sv[:, 1], style, color="C0" if style == "-" else "C1" if style == "--" else "C2")
    ax.axhline(1.0, color="k", linewidth=0.5)
    ax.set(
        xlabel="frequency (rad/s)",
        ylabel="singular values (mm/V, mm/mm)",
        title="Choi 1999 Fig. 2: open and target loop",
    )
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    save(fig, "choi1999_loop_shape.png")

    for index, title, name in (
        (0, "Fig. 6: mu, robust stability", "choi1999_mu_rs.png"),
        (1, "Fig. 7: mu, robust performance", "choi1999_mu_rp.png"),
    ):
        fig, ax = plt.subplots(figsize=(7, 4.5))
        for kind in r.KINDS:
            ax.semilogx(r.OMEGA, r.mu_curves(kind)[index], label=f"{kind} (upper bound)")
        ax.axhline(1.0, color="k", linewidth=0.5)
        ax.set(xlabel="frequency (rad/s)", ylabel="mu", title=f"Choi 1999 {title}")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend()
        save(fig, name)

    runs = twin_runs()
    fig, ax = plt.subplots(figsize=(6.5, 6.5))
    for kind, res in runs.items():
        ref, pos = res.ref[:, :, 0], res.table_position_m()
        centre = np.array([-np.ptp(ref[:, 0]) / 2, 0.0])
        rel = ref - centre
        radius = np.linalg.norm(rel, axis=1, keepdims=True)
        radial_error = np.linalg.norm(pos - centre, axis=1, keepdims=True) - radius
        shown = rel / radius * (radius + CONTOUR_GAIN * radial_error)
        ax.plot(*(rel * 1e3).T, color="0.6", linewidth=0.8)
        ax.plot(*(shown * 1e3).T, linewidth=0.8, label=f"{kind}: radial error x{CONTOUR_GAIN}")
    ax.set(aspect="equal", xlabel="x (mm)", ylabel="y (mm)", title="Choi 1999 Fig. 12(c): cutting circles, error x300")
    ax.legend()
    save(fig, "choi1999_contour_x300.png")

    fig, axes = plt.subplots(2, 1, figsize=(7, 6), sharex=True)
    for kind, res in runs.items():
        for i, a in enumerate("xy"):
            axes[i].plot(res.t_s, res.u_V[:, i], linewidth=0.6, label=kind)
            axes[i].set(ylabel=f"u_{a} (V)")
    axes[0].set_title("Choi 1999 Fig. 13: control inputs while cutting")
    axes[1].set(xlabel="time (s)")
    axes[0].legend()
    save(fig, "choi1999_control_inputs.png")
    return written


def twin_runs() -> dict:
    """The twin's two cutting circles (MIMO R 28, PID R 30), mechanistic force."""
    return {kind: r.cutting_run(kind) for kind in r.KINDS}


def certificates(machine: str, controller: str | None, symbols: set[str], others: list[str]) -> list[dict]:
    """Choi 1999's mu upper bounds over Table 1's box (m, b, k_il, k_c with the amplifier weight)
    for its two controllers on ``linear_motor_xy``."""
    if not (machine == "linear_motor_xy" and controller in ("choi1999_mimo", "choi1999_pid")):
        return []
    rs, rp = r.mu_curves(controller.removeprefix("choi1999_"))
    return [
        {
            "source": "Choi 1999, mu (AB13MD upper bound) over Table 1's box of m, b, k_il, k_c with the "
            "amplifier weight; robustly stable where the peak is below 1",
            "rs_peak": float(rs.max()),
            "rs_peak_rad_s": float(r.OMEGA[int(np.argmax(rs))]),
            "rp_peak": float(rp.max()),
            "robustly_stable": bool(rs.max() < 1.0),
            "note": "covers the sweep only where its draws lie inside that box",
        }
    ]
