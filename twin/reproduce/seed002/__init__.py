"""Seed 002 (Anang et al.): the entry points ``twin reproduce seed002`` calls.

:mod:`.procedure` computes (margins, Popov bound, critical gains, Tables 1-3 on the
transfer-function loop and the twin); :mod:`.report` prints and plots.  ``samples`` and
``seed`` do not apply (nothing is random); ``twin_samples = 0`` leaves the twin out.
"""

from __future__ import annotations

from pathlib import Path


def run(samples: int, twin_samples: int, seed: int, progress: bool) -> dict:
    """Every number of the reproduction (see :func:`.report.run_all`)."""
    from twin.reproduce.seed002.report import run_all

    return run_all(twin=twin_samples > 0, progress=progress)


def format_report(results: dict) -> str:
    """The text tables: paper | transfer-function loop | twin."""
    from twin.reproduce.seed002 import report

    return report.format_report(results)


def write_plots(folder: Path) -> list[Path]:
    """PNG Popov plot, Bode and sensitivity, tracking error and its spectrum."""
    from twin.reproduce.seed002.report import write_plots as plots

    return plots(folder)


def record(path: Path) -> None:
    """Rerun recording of Fig. 10's twin runs (0.4 Hz, 10 mm, 1500 rpm; PID and NPID)."""
    from twin.recording import record_runs
    from twin.reproduce.seed002.report import fig10_runs

    record_runs(fig10_runs(), path)


def failed(results: dict) -> bool:
    """Whether a twin table number departs from its transfer-function number by more than 2 %."""
    return bool(results["twin_vs_tf_mismatches"])
