"""Seed 000 (Yadav, Pathak, Gaur 2020): the entry points ``twin reproduce seed000`` calls.

:mod:`.procedure` computes (interval model, designs, Table 2 on the transfer functions and the
twin, disturbance runs); :mod:`.report` prints and plots.
"""

from __future__ import annotations

from pathlib import Path


def run(samples: int, twin_samples: int, seed: int, progress: bool) -> dict:
    """Every number of the reproduction (see :func:`.report.run_all`)."""
    from twin.reproductions.seed000.report import run_all

    return run_all(samples, twin_samples, seed, progress=progress)


def markdown_tables(results: dict) -> dict[str, str]:
    """The docs page's generated tables (see :func:`.report.markdown_tables`)."""
    from twin.reproductions.seed000 import report

    return report.markdown_tables(results)


def format_report(results: dict) -> str:
    """The text tables: paper | transfer function | twin."""
    from twin.reproductions.seed000 import report

    return report.format_report(results)


def write_plots(folder: Path, results: dict | None = None) -> list[Path]:
    """PNG step responses as the paper's Figs. 7-10."""
    from twin.reproductions.seed000.report import write_plots as plots

    return plots(folder)


def record(path: Path) -> None:
    """Rerun recording of the nominal twin step runs of Table 2."""
    from twin.recording import record_runs
    from twin.reproductions.seed000 import procedure as r

    nominal = r.nominal_params()
    record_runs({name: r.twin_step_result(c, nominal) for name, c in r.TABLE2_CONTROLLERS.items()}, path)


def failed(results: dict) -> bool:
    """Whether a twin number departs from its transfer-function number by more than 2 %."""
    return bool(results["twin_vs_tf_mismatches"])


#: The scenario controller kinds whose certificate this reproduction computes, by Table 2 name.
CERTIFIED = {"seed000_robust_pi": "robust_pi", "seed000_imc": "imc", "seed000_hinf_reduced": "hinf"}


def certificates(machine: str, controller: str | None, symbols: set[str], others: list[str]) -> list[dict]:
    """Seed 000's Kharitonov verdict and stability margin over Table 1's box (K1, K2, m, Im) for
    its three controllers on ``cncmt``, when a sweep varies nothing else."""
    if not (machine == "cncmt" and controller in CERTIFIED and symbols <= {"K1", "K2", "m", "Im"} and not others):
        return []
    from twin.reproductions.seed000.procedure import interval_table

    row = next(r for r in interval_table() if r["controller"] == CERTIFIED[controller])
    return [
        {
            "source": "seed 000, Kharitonov over Table 1's box (K1, K2, m, Im)",
            "kharitonov_robustly_stable": bool(row["kharitonov_stable"]),
            "stability_margin": float(row["sm"]),
            "family_stable": bool(row["family_stable"]),
            "note": "SM < 0: Kharitonov cannot prove stability; family_stable: every member checked",
        }
    ]
