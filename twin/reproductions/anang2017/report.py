"""Tables and plots of ``twin reproduce anang2017`` (see :mod:`twin.reproductions.anang2017.procedure`)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from tqdm import tqdm

from twin.reproductions.anang2017 import procedure as r
from twin.reproductions.base import mismatch_lines
from twin.reproductions.tables import fmt, markdown_table


def run_all(twin: bool = True, progress: bool = True) -> dict:
    """Every part of the reproduction, as one JSON-ready dict."""
    variants = r.margin_variants()
    gains = r.critical_gains(twin)
    n = len(r.REFERENCES) * len(r.SPINDLES_RPM) * 2
    with tqdm(total=n, desc="anang2017 table runs", unit="run", disable=not progress, leave=False) as bar:
        rows = r.tables(twin, progress=bar.update)
    ke = r.ke()
    for v in variants:
        v["ke_within"] = bool(ke <= v["ke_max"]) if math.isfinite(v["ke_max"]) else None
    return {
        "margins": variants,
        "ke": ke,
        "critical_gain": gains,
        "tables": rows,
        "error_unit": r.error_unit_study(),
        "twin_vs_tf_mismatches": r.mismatches(rows),
        "paper": _paper_json(),
        "settings": {
            "dt_s": r.DT_S,
            "duration_s": r.DURATION_S,
            "steady_from_s": r.STEADY_FROM_S,
            "cut": r.CUT,
            "derivative_filter_s": r.TF_S,
            "twin": twin,
        },
    }


def _paper_json() -> dict:
    return {
        k: v if not isinstance(v, dict) else {" ".join(map(str, key)): val for key, val in v.items()}
        for k, v in r.PAPER.items()
    }


def _f(x, spec=".4g") -> str:
    return "unstable" if x is None else ("-" if isinstance(x, float) and math.isnan(x) else format(x, spec))


def format_report(res: dict) -> str:
    """Plain-text tables: paper | transfer-function loop | twin."""
    p = r.PAPER
    out = [
        "Anang et al. (2017) reproduced on googol_xy: paper | ours",
        "",
        "PID eq. (6) on eq. (1): margins and the Popov bound (Ke_max = 1/|crossing|)",
        f"  {'loop':<88} {'GM dB':>7} {'at Hz':>6} {'PM deg':>7} {'Ms dB':>6} {'-3dB Hz':>7} "
        f"{'crossing':>9} {'Ke_max':>7} {'Ke ok':>5}",
        f"  {'paper':<88} {p['gm_db']:>7} {'':>6} {p['pm_deg']:>7} {p['ms_db']:>6} {p['bw_hz']:>7} "
        f"{p['popov_crossing']:>9} {p['ke_max']:>7} {'yes':>5}",
    ]
    for v in res["margins"]:
        ok = "-" if v["ke_within"] is None else ("yes" if v["ke_within"] else "NO")
        out.append(
            f"  {v['loop']:<88} {_f(v['gm_db'], '.3f'):>7} {_f(v['gm_hz'], '.1f'):>6} "
            f"{_f(v['pm_deg'], '.2f'):>7} {_f(v['ms_db'], '.2f'):>6} {_f(v['bw_hz'], '.1f'):>7} "
            f"{_f(v['popov_crossing'], '.4f'):>9} {_f(v['ke_max'], '.4f'):>7} {ok:>5}"
        )
    g = res["critical_gain"]
    out += [
        "",
        f"Ke = cosh(KO e_max) at KO 6, e_max 0.3 (e in mm): {res['ke']:.4f} | paper {p['ke']} "
        "(Ke ok: Ke <= Ke_max of that loop)",
        f"Critical constant gain in front of the PID (time domain, growing oscillation of a 0.1 mm step): "
        f"TF loop {g['tf_loop']:.4f}"
        + (f", twin {g['twin']:.4f}" if "twin" in g else "")
        + f"; the sampled loop's 10^(GM/20) = {10 ** (res['margins'][-1]['gm_db'] / 20):.4f}",
        "",
    ]
    out.append(
        "Tables 1-3 (max tracking error and RMSE in mm over t >= 2.5 s; max red% = (PID - NPID)/PID of the "
        "max errors, Table 3's metric; rms red% = eq. (9) on the RMSE):"
    )
    sides = ["tf_loop", "twin"] if res["settings"]["twin"] else ["tf_loop"]
    head = f"  {'Hz':>4} {'mm':>3} {'rpm':>5} | {'paper PID':>9} {'NPID':>7} {'max red%':>8} |"
    for side in sides:
        head += f" {side + ' PID':>12} {'NPID':>7} {'max red%':>8} {'rmsPID':>7} {'rmsNPID':>7} {'rms red%':>8} |"
    out.append(head)
    for row in res["tables"]:
        paper = row["paper"] or (None, None)
        rpm = "-" if row["rpm"] is None else f"{row['rpm']:.0f}"
        paper_red = row["paper_max_reduction_pct"]
        line = (
            f"  {row['f_hz']:>4} {row['a_mm']:>3} {rpm:>5} | {_f(paper[0]):>9} {_f(paper[1]):>7} "
            f"{'-' if paper_red is None else format(paper_red, '.2f'):>8} |"
        )
        for side in sides:
            a, b = row["anang2017_pid"][side], row["anang2017_npid"][side]
            line += (
                f" {a['max_mm']:>12.4f} {b['max_mm']:>7.4f} {row['max_reduction_pct_' + side]:>8.2f} "
                f"{a['rmse_mm']:>7.4f} {b['rmse_mm']:>7.4f} {row['rmse_reduction_pct_' + side]:>8.2f} |"
            )
        out.append(line)
    plain = {
        (row["f_hz"], row["a_mm"]): row["anang2017_pid"]["tf_loop"]["max_mm"]
        for row in res["tables"]
        if row["rpm"] is None
    }
    out += [
        "",
        "Table 1's middle rows read as swapped: paper (0.4 Hz, 20 mm) "
        f"{p['table1'][(0.4, 20)][0]} against our (0.7 Hz, 10 mm) {plain[(0.7, 10)]:.4f}; paper (0.7 Hz, 10 mm) "
        f"{p['table1'][(0.7, 10)][0]} against our (0.4 Hz, 20 mm) {plain[(0.4, 20)]:.4f} (PID, TF loop)",
    ]
    out += ["", "NPID RMSE reduction (TF loop, no cutting) by the unit of e inside cosh:"]
    for row in res["error_unit"]:
        out.append(
            f"  {row['f_hz']} Hz {row['a_mm']} mm: e in mm {_f(row['mm'], '.2f')} %, "
            f"e in um {_f(row['um'], '.2f')}" + (" %" if row["um"] is not None else "")
        )
    out += mismatch_lines(
        f"Twin vs transfer-function loop (tolerance {r.TWIN_TOL_REL:.0%})", res["twin_vs_tf_mismatches"]
    )
    return "\n".join(out)


def markdown_tables(res: dict) -> dict[str, str]:
    """The docs page's tables (:mod:`twin.reproductions.tables`): ``margins`` (the PID loop's margins
    and Popov bound under each delay and derivative treatment) and ``tables_1_3`` (max error
    and RMSE, the NPID's reductions on Table 3's metric and on eq. (9)'s)."""
    p = r.PAPER
    margins = [["paper", p["gm_db"], p["pm_deg"], p["ms_db"], p["bw_hz"], p["popov_crossing"], p["ke_max"], "yes"]]
    for v in res["margins"]:
        margins.append(
            [
                v["loop"],
                fmt(v["gm_db"], ".2f"),
                fmt(v["pm_deg"], ".2f"),
                fmt(v["ms_db"], ".2f"),
                fmt(v["bw_hz"], ".1f"),
                fmt(v["popov_crossing"], ".4f"),
                fmt(v["ke_max"], ".4f"),
                {True: "yes", False: "no", None: "–"}[v["ke_within"]],
            ]
        )
    twin = res["settings"]["twin"]
    rows = []
    for row in res["tables"]:
        paper = row["paper"] or (None, None)
        pid, npid = row["anang2017_pid"], row["anang2017_npid"]
        cells = [
            row["f_hz"],
            row["a_mm"],
            "–" if row["rpm"] is None else f"{row['rpm']:.0f}",
            f"{fmt(paper[0], '.4f')} / {fmt(paper[1], '.4f')}",
            fmt(row["paper_max_reduction_pct"], ".2f"),
            f"{pid['tf_loop']['max_mm']:.4f} / {npid['tf_loop']['max_mm']:.4f}",
            f"{row['max_reduction_pct_tf_loop']:.2f}",
            f"{row['rmse_reduction_pct_tf_loop']:.2f}",
        ]
        if twin:
            cells += [
                f"{pid['twin']['max_mm']:.4f} / {npid['twin']['max_mm']:.4f}",
                f"{row['max_reduction_pct_twin']:.2f}",
            ]
        rows.append(cells)
    head = [
        "Hz",
        "mm",
        "rpm",
        "paper max PID / NPID",
        "paper red. % (Table 3)",
        "TF max PID / NPID",
        "TF red. % (max)",
        "TF red. % (RMSE, eq. 9)",
    ] + (["twin max PID / NPID", "twin red. % (max)"] if twin else [])
    return {
        "margins": markdown_table(
            ["loop", "GM dB", "PM deg", "Ms dB", "S -3 dB (Hz)", "Popov crossing", "Ke_max", "Ke = 3.1075 within"],
            margins,
        ),
        "tables_1_3": markdown_table(head, rows),
    }


def write_plots(directory: Path, results: dict | None = None) -> list[Path]:
    """Popov plot, Bode magnitude/phase of L with |S|, and the twin's tracking error and its
    spectrum for Fig. 10's case (0.4 Hz, 10 mm, 1500 rpm), PID against NPID."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    directory.mkdir(parents=True, exist_ok=True)
    written = []
    w = np.logspace(0, 4.2, 4000)
    loops = {
        "exact delay, ideal D": r.continuous_loop("exact", 0.0),
        "Pade-2 delay, ideal D": r.continuous_loop("pade2", 0.0),
        f"exact delay, D filtered {r.TF_S:g} s": r.continuous_loop("exact", r.TF_S),
    }
    fig, ax = plt.subplots(figsize=(7, 5))
    for label, L in loops.items():
        Lw = L(w)
        ax.plot(Lw.real, w * Lw.imag, label=label)
    ax.axvline(-1 / r.PAPER["ke_max"], color="k", linestyle=":", label=f"paper crossing {r.PAPER['popov_crossing']}")
    ax.set(
        xlim=(-0.8, 0.3),
        ylim=(-600, 500),
        xlabel="Re L(jw)",
        ylabel="w Im L(jw) (rad/s)",
        title="Fig. 9: Popov plot of the PID loop",
    )
    ax.grid(True, alpha=0.3)
    ax.legend()
    written.append(directory / "anang2017_fig9_popov.png")
    fig.savefig(written[-1], dpi=120, bbox_inches="tight")
    plt.close(fig)
    fig, axes = plt.subplots(2, 1, figsize=(7, 6), sharex=True)
    L = r.continuous_loop("exact", 0.0)
    Lw = L(w)
    hz = w / (2 * math.pi)
    axes[0].semilogx(hz, 20 * np.log10(np.abs(Lw)), label="|L|")
    axes[0].semilogx(hz, -20 * np.log10(np.abs(1 + Lw)), label="|S| = |1/(1 + L)|")
    axes[0].axhline(-3, color="k", linestyle=":", linewidth=0.8)
    axes[0].set(ylabel="dB", title="Figs. 4, 6, 7: loop and sensitivity (exact delay, ideal D)", ylim=(-40, 40))
    axes[0].legend()
    axes[1].semilogx(hz, np.degrees(np.unwrap(np.angle(Lw))))
    axes[1].axhline(-180, color="k", linestyle=":", linewidth=0.8)
    axes[1].set(xlabel="frequency (Hz)", ylabel="phase of L (deg)", ylim=(-400, 0))
    for ax in axes:
        ax.grid(True, which="both", alpha=0.3)
    written.append(directory / "anang2017_fig4_bode_sensitivity.png")
    fig.savefig(written[-1], dpi=120, bbox_inches="tight")
    plt.close(fig)
    runs = twin_runs()
    fig, axes = plt.subplots(2, 1, figsize=(7, 6))
    for name, res in runs.items():
        e = res.error_m()[:, 0] * 1e3
        axes[0].plot(res.t_s, e, linewidth=0.8, label=name)
        steady = e[int(r.STEADY_FROM_S / r.DT_S) :]
        window = np.hanning(len(steady))
        spectrum = np.abs(np.fft.rfft(steady * window)) * 2 / window.sum()  # amplitude of each sine
        axes[1].loglog(np.fft.rfftfreq(len(steady), r.DT_S)[1:], spectrum[1:], linewidth=0.8, label=name)
    axes[0].set(xlabel="time (s)", ylabel="tracking error (mm)", title="Fig. 10: 0.4 Hz, 10 mm, 1500 rpm (twin)")
    axes[1].set(
        xlabel="frequency (Hz)", ylabel="error amplitude (mm)", title="error spectrum, t >= 2.5 s (Hann window)"
    )
    for ax in axes:
        ax.grid(True, alpha=0.3)
        ax.legend()
    fig.tight_layout()
    written.append(directory / "anang2017_fig10_error.png")
    fig.savefig(written[-1], dpi=120, bbox_inches="tight")
    plt.close(fig)
    return written


def twin_runs() -> dict:
    """The twin runs of Fig. 10: 0.4 Hz, 10 mm, 1500 rpm, PID and NPID."""
    from controllers import make_controller
    from twin.machining.cutting import EndMilling
    from twin.references import SumOfSines
    from twin.sim.runner import simulate

    bm = r.machine()
    cut = (EndMilling(spindle_rpm=1500.0, **r.CUT),)
    return {
        name: simulate(
            bm,
            make_controller(name, r.DT_S, axes=("x", "y")),
            SumOfSines((0.01,), (0.4,), n_axes=2, axes=(0,)),
            duration_s=r.DURATION_S,
            control_period_s=r.DT_S,
            disturbances=cut,
            progress=False,
        )
        for name in ("anang2017_pid", "anang2017_npid")
    }


def run(samples: int, twin_samples: int, seed: int, progress: bool) -> dict:
    """The registry's entry point: :func:`run_all`; ``samples`` and ``seed`` do not apply
    (nothing is random), ``twin_samples = 0`` leaves the twin out."""
    return run_all(twin=twin_samples > 0, progress=progress)
