"""Tables and plots of ``twin reproduce maharof2021`` (see :mod:`twin.reproductions.maharof2021.procedure`)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from tqdm import tqdm

from twin.reproductions.base import mismatch_lines
from twin.reproductions.maharof2021 import procedure as r
from twin.reproductions.tables import markdown_table


def run_all(twin: bool = True, progress: bool = True) -> dict:
    """Every part of the reproduction, as one JSON-ready dict."""
    n = (len(r.REFERENCES) * 3 * len(r.FEEDFORWARDS) + (len(r.SPINDLES_RPM) if twin else 0)) * len(r.CONFIGURATIONS)
    with tqdm(total=n, desc="maharof2021 cases", unit="case", disable=not progress, leave=False) as bar:
        rows = r.cases(twin, progress=bar.update)
        with_ff = {ff: r.cases(twin, progress=bar.update, feedforward=ff) for ff in r.FEEDFORWARDS if ff != "none"}
        milling = r.milling_cases(progress=bar.update) if twin else []
    return {
        "design": r.design(),
        "cases": rows,
        "feedforward_cases": with_ff,
        "feedforward": r.model_feedforward(),
        "amplitude_study": r.amplitude_study(),
        "milling": milling,
        "twin_vs_tf_mismatches": r.mismatches([*rows, *(row for ff_rows in with_ff.values() for row in ff_rows)]),
        "thesis": r.THESIS,
        "settings": {
            "dt_s": r.DT_S,
            "duration_s": r.DURATION_S,
            "steady_from_s": r.STEADY_FROM_S,
            "disturbance_V": r.DISTURBANCE_V,
            "dfo_bandwidth_hz": r.BANDWIDTH_HZ,
            "twin": twin,
        },
    }


def format_report(res: dict) -> str:
    """Plain-text tables: thesis | ours."""
    d = res["design"]
    out = [
        "Maharof 2021 reproduced on googol_xy: thesis | ours",
        "",
        "Cascade P/PI by loop shaping (velocity measured by backward difference at 10 kHz, 1.2 ms delay):",
        f"  velocity PI kp {d['kp_vel']:.4g} V s/m, ki {d['ki_vel']:.4g} V/m; position P {d['kp_pos']:.4g} 1/s",
    ]
    for loop in ("velocity", "position"):
        t, o = d[f"thesis_{loop}"], d[loop]
        out.append(
            f"  {loop:<8} GM {t['gm_db']} dB at {t['gm_hz']} Hz | {o['gm_db']:.2f} dB at {o['gm_hz']:.1f} Hz;"
            f"  PM {t['pm_deg']} deg at {t['pm_hz']} Hz | {o['pm_deg']:.2f} deg at {o['pm_hz']:.1f} Hz"
        )
    out += [
        f"IMBDO Q-filter: order {d['q_order']}, cutoff {d['q_cutoff_hz']:g} Hz, sup|Q Delta| = {d['sup_q_delta']:.3f} "
        f"(delay unmodelled, gain +-{d['gain_error']:.0%}; < 1: robustly stable)",
        "",
    ]
    sides = ["tf_loop", "twin"] if res["settings"]["twin"] else ["tf_loop"]
    out.append("Numerical cases (t >= 2 s; errors in um; 'dist' = the disturbance's own share of the error):")
    for row in res["cases"]:
        out.append(f"  reference {row['amplitude_mm']} mm at {row['f_hz']} Hz, harmonics {row['harmonics_hz']} Hz:")
        for config in r.CONFIGURATIONS:
            line = f"    {config:<10}"
            for side in sides:
                m = row[config][side]
                line += (
                    f" | {side}: MTE {m['mte_um']:8.3f} RMSE {m['rmse_um']:8.3f} dist MTE "
                    f"{m['disturbance']['mte_um']:.3g} FFT " + " ".join(f"{v:.3g}" for v in m["disturbance"]["fft_um"])
                )
            out.append(line)
        h = len(row["harmonics_hz"]) - 1
        for config, red in row[f"reduction_pct_{sides[-1]}"].items():
            thesis = (
                f" (thesis {r.THESIS['mte_pct'][h]}, {r.THESIS['rmse_pct'][h]}, "
                f"{', '.join(map(str, r.THESIS['fft_pct'][h]))})"
                if config == "imbdo_dfo"
                else ""
            )
            out.append(
                f"    {config} vs cascade ({sides[-1]}): MTE {red['mte']:.2f} %, RMSE {red['rmse']:.2f} %; "
                f"disturbance MTE {red['disturbance_mte']:.2f} %, FFT "
                + ", ".join(f"{v:.2f}" for v in red["disturbance_fft"])
                + f" %{thesis}"
            )
    ff = res["feedforward"]
    out += [
        "",
        f"With reference feedforward (ours; the thesis states none): 'velocity' feeds the reference velocity "
        f"into the velocity loop; 'velocity_acceleration' adds u_ff = {ff['velocity_ff_V_s_per_m']:.4g} V s/m "
        f"x v_ref + {ff['acceleration_ff_V_s2_per_m']:.4g} V s^2/m x a_ref (eq. (1)'s a1/b0 and 1/b0). "
        f"MTE | RMSE (um) and IMBDO + DFO's reductions against the cascade ({sides[-1]}):",
        f"  {'reference, harmonics':<30} {'feedforward':<22} {'cascade':>17} {'imbdo':>17} {'dfo':>17} "
        f"{'imbdo_dfo':>17} {'MTE red %':>9} {'RMSE red %':>10}",
    ]
    for ff_name, ff_rows in (("none", res["cases"]), *res["feedforward_cases"].items()):
        for row in ff_rows:
            cells = " ".join(
                f"{row[c][sides[-1]]['mte_um']:>8.3f}|{row[c][sides[-1]]['rmse_um']:<8.3f}" for c in r.CONFIGURATIONS
            )
            red = row[f"reduction_pct_{sides[-1]}"]["imbdo_dfo"]
            case = f"{row['amplitude_mm']} mm {row['f_hz']} Hz, {len(row['harmonics_hz'])}"
            out.append(f"  {case:<30} {ff_name:<22} {cells} {red['mte']:>9.2f} {red['rmse']:>10.2f}")
    out += [
        "",
        "The assumed disturbance amplitude decides the reductions (TF loop, 10 mm at 0.5 Hz, three harmonics, "
        "velocity and acceleration feedforward; thesis: MTE 99.13 %, RMSE 97.97 %):",
    ]
    for row in res["amplitude_study"]:
        out.append(
            f"  {row['amplitude_V']:>6g} V per harmonic: cascade MTE {row['cascade']['tf_loop']['mte_um']:8.3f} um, "
            f"IMBDO + DFO {row['imbdo_dfo']['tf_loop']['mte_um']:8.3f} um; reduction MTE "
            f"{row['reduction_pct']['mte']:.2f} %, RMSE {row['reduction_pct']['rmse']:.2f} %"
        )
    if res["milling"]:
        out += [
            "",
            f"Mechanistic milling (10 mm at 0.5 Hz; {r.CUT['diameter_mm']:g} mm slot, "
            f"{r.CUT['axial_depth_mm']:g} mm deep, {r.CUT['n_flutes']} flutes; DFO at the first two tooth "
            f"harmonics, inverse-model signal at {r.MILLING_CUTOFF_HZ:g} Hz); twin | TF loop driven by the "
            "twin's force; tooth lines: the error's largest line within 1 Hz of each (um):",
        ]
        for row in res["milling"]:
            h = row["cascade"]["harmonics_hz"]
            out.append(f"  {row['rpm']:.0f} rpm (tooth harmonics {h[0]:.1f}, {h[1]:.1f} Hz):")
            for config in r.CONFIGURATIONS:
                tw, tf = row[config]["twin"], row[config]["tf_loop"]
                out.append(
                    f"    {config:<10} MTE {tw['mte_um']:8.3f} | {tf['mte_um']:8.3f}  cutting share MTE "
                    f"{tw['disturbance']['mte_um']:.3f} | {tf['disturbance']['mte_um']:.3f}  tooth lines "
                    + " ".join(f"{a:.3g}" for a in tw["disturbance"]["fft_um"])
                    + " | "
                    + " ".join(f"{b:.3g}" for b in tf["disturbance"]["fft_um"])
                )
    out += mismatch_lines(
        f"Twin vs transfer-function loop (MTE, RMSE; tolerance {r.TWIN_TOL_REL:.0%})", res["twin_vs_tf_mismatches"]
    )
    return "\n".join(out)


def markdown_tables(res: dict) -> dict[str, str]:
    """The docs page's tables (:mod:`twin.reproductions.tables`): ``design`` (the cascade's margins
    beside the thesis's), ``cases`` (every numerical case and feedforward: MTE / RMSE and IMBDO
    + DFO's reductions), ``amplitude`` (the reductions against the assumed disturbance) and
    ``milling`` (the cutting share of the error and the first tooth line)."""
    d = res["design"]
    design = []
    for loop, gains in (
        ("velocity", f"PI: kp {d['kp_vel']:.4g} V s/m, ki {d['ki_vel']:.4g} V/m"),
        ("position", f"P: {d['kp_pos']:.4g} 1/s"),
    ):
        t, o = d[f"thesis_{loop}"], d[loop]
        design.append(
            [
                f"{loop} {gains}",
                f"{t['gm_db']} dB at {t['gm_hz']} Hz",
                f"{o['gm_db']:.2f} dB at {o['gm_hz']:.1f} Hz",
                f"{t['pm_deg']}° at {t['pm_hz']} Hz",
                f"{o['pm_deg']:.2f}° at {o['pm_hz']:.1f} Hz",
            ]
        )
    side = "twin" if res["settings"]["twin"] else "tf_loop"
    cases = []
    for ff_name, rows in (("none", res["cases"]), *res["feedforward_cases"].items()):
        for row in rows:
            h = len(row["harmonics_hz"]) - 1
            red = row[f"reduction_pct_{side}"]["imbdo_dfo"]
            cases.append(
                [
                    f"{row['amplitude_mm']:g} mm {row['f_hz']:g} Hz",
                    ", ".join(f"{f:g}" for f in row["harmonics_hz"]),
                    ff_name.replace("_", " + "),
                    *(f"{row[c][side]['mte_um']:.3g} / {row[c][side]['rmse_um']:.3g}" for c in r.CONFIGURATIONS),
                    f"{red['mte']:z.1f} / {red['rmse']:z.1f}",
                    f"{r.THESIS['mte_pct'][h]} / {r.THESIS['rmse_pct'][h]}",
                ]
            )
    amplitude = [
        [
            f"{row['amplitude_V']:g}",
            f"{row['cascade']['tf_loop']['mte_um']:.3g}",
            f"{row['imbdo_dfo']['tf_loop']['mte_um']:.3g}",
            f"{row['reduction_pct']['mte']:.1f}",
            f"{row['reduction_pct']['rmse']:.1f}",
        ]
        for row in res["amplitude_study"]
    ]
    milling = []
    for row in res["milling"]:
        for config in r.CONFIGURATIONS:
            tw, tf = row[config]["twin"], row[config]["tf_loop"]
            milling.append(
                [
                    f"{row['rpm']:.0f}" if config == "cascade" else "",
                    config,
                    f"{tw['mte_um']:.1f}",
                    f"{tw['disturbance']['mte_um']:.3g} | {tf['disturbance']['mte_um']:.3g}",
                    f"{tw['disturbance']['fft_um'][0]:.3g} | {tf['disturbance']['fft_um'][0]:.3g}",
                ]
            )
    name = "twin" if side == "twin" else "TF loop"
    return {
        "design": markdown_table(["loop", "thesis GM", "ours GM", "thesis PM", "ours PM"], design),
        "cases": markdown_table(
            [
                "reference",
                "harmonics (Hz)",
                "feedforward (ours)",
                *(f"{c} MTE / RMSE (µm, {name})" for c in r.CONFIGURATIONS),
                "IMBDO + DFO reduction MTE / RMSE (%)",
                "thesis (%)",
            ],
            cases,
        ),
        "amplitude": markdown_table(
            [
                "disturbance per harmonic (V)",
                "cascade MTE (µm)",
                "IMBDO + DFO MTE (µm)",
                "MTE reduction (%)",
                "RMSE reduction (%)",
            ],
            amplitude,
        ),
        "milling": markdown_table(
            [
                "rpm",
                "configuration",
                "MTE (µm, twin)",
                "cutting share of the MTE (µm): twin | TF",
                "first tooth line (µm): twin | TF",
            ],
            milling,
        )
        if milling
        else "",
    }


def write_plots(directory: Path, results: dict | None = None) -> list[Path]:
    """Disturbance sensitivity of the four configurations and the reference loops (Figs.
    4.19-4.37), and the twin's tracking-error spectra for three harmonics (Fig. 5.9)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    directory.mkdir(parents=True, exist_ok=True)
    written = []
    w = 2 * math.pi * np.logspace(-2, 3, 3000)
    fig, (ax, ax2) = plt.subplots(2, 1, figsize=(7, 8))
    for name, mag in r.disturbance_sensitivity(w, (0.2, 0.5, 0.8)).items():
        ax.loglog(w / (2 * math.pi), mag * 1e6, label=name)
    for f in (0.2, 0.5, 0.8):
        ax.axvline(f, color="k", linestyle=":", linewidth=0.7)
    ax.set(
        xlabel="frequency (Hz)",
        ylabel="|position / input disturbance| (um/V)",
        title="Input-disturbance sensitivity, three harmonics (TF model)",
    )
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    for name, mag in r.reference_loops(w).items():
        ax2.semilogx(w / (2 * math.pi), 20 * np.log10(mag), label=name)
    ax2.set(
        xlabel="frequency (Hz)",
        ylabel="dB",
        ylim=(-80, 20),
        title="Reference loops: the same with and without the observers (nominal model)",
    )
    ax2.grid(True, which="both", alpha=0.3)
    ax2.legend()
    fig.tight_layout()
    written.append(directory / "maharof2021_disturbance_sensitivity.png")
    fig.savefig(written[-1], dpi=120, bbox_inches="tight")
    plt.close(fig)
    fig, ax = plt.subplots(figsize=(7, 4.5))
    for config, res in twin_runs().items():
        e = res.error_m()[int(r.STEADY_FROM_S / r.DT_S) :, 0]
        window = np.hanning(len(e))
        ax.loglog(
            np.fft.rfftfreq(len(e), r.DT_S)[1:],
            (np.abs(np.fft.rfft(e * window)) * 2 / window.sum())[1:] * 1e6,
            linewidth=0.8,
            label=config,
        )
    ax.set(
        xlim=(0.05, 50),
        xlabel="frequency (Hz)",
        ylabel="tracking error amplitude (um)",
        title="Twin: 10 mm at 0.5 Hz, harmonics 0.2/0.5/0.8 Hz, t >= 2 s (Hann)",
    )
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    written.append(directory / "maharof2021_error_spectra.png")
    fig.savefig(written[-1], dpi=120, bbox_inches="tight")
    plt.close(fig)
    return written


def twin_runs() -> dict:
    """Twin runs of the four configurations: 10 mm at 0.5 Hz, three harmonics."""
    from twin.references import SumOfSines
    from twin.sim.runner import simulate

    harmonics = (0.2, 0.5, 0.8)
    return {
        config: simulate(
            r.machine(),
            r.controller(config, harmonics, axes=("x", "y")),
            SumOfSines((0.01,), (0.5,), n_axes=2, axes=(0,)),
            r.DURATION_S,
            r.DT_S,
            disturbances=(r._disturbance(harmonics),),
            progress=False,
        )
        for config in r.CONFIGURATIONS
    }


def run(samples: int, twin_samples: int, seed: int, progress: bool) -> dict:
    """The registry's entry point: :func:`run_all`; ``samples`` and ``seed`` do not apply
    (nothing is random), ``twin_samples = 0`` leaves the twin out."""
    return run_all(twin=twin_samples > 0, progress=progress)
