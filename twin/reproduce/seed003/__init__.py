"""Seed 003 (Maharof 2021): the entry points ``twin reproduce seed003`` calls.

:mod:`.procedure` computes (cascade design, IMBDO Q-filter, the numerical cases on the
transfer-function loop and the twin); :mod:`.report` prints and plots.  ``samples`` and
``seed`` do not apply; ``twin_samples = 0`` leaves the twin out.
"""

from __future__ import annotations

from pathlib import Path


def run(samples: int, twin_samples: int, seed: int, progress: bool) -> dict:
    """Every number of the reproduction (see :func:`.report.run_all`)."""
    from twin.reproduce.seed003.report import run_all

    return run_all(twin=twin_samples > 0, progress=progress)


def format_report(results: dict) -> str:
    """The text tables: thesis | ours."""
    from twin.reproduce.seed003 import report

    return report.format_report(results)


def write_plots(folder: Path) -> list[Path]:
    """PNG disturbance sensitivity and error spectra."""
    from twin.reproduce.seed003.report import write_plots as plots

    return plots(folder)


def record(path: Path) -> None:
    """Rerun recording of the four configurations' twin runs (10 mm at 0.5 Hz, three harmonics)."""
    from twin.recording import record_runs
    from twin.reproduce.seed003.report import config_runs

    record_runs(config_runs(), path)


def failed(results: dict) -> bool:
    """Whether a twin MTE or RMSE departs from its transfer-function number by more than 2 %."""
    return bool(results["twin_vs_tf_mismatches"])
