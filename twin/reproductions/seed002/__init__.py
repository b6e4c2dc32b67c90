"""Seed 002 (Anang et al.): the entry points ``twin reproduce seed002`` calls.

:mod:`.procedure` computes (margins, Popov bound, critical gains, Tables 1-3 on the
transfer-function loop and the twin); :mod:`.report` prints and plots.  ``samples`` and
``seed`` do not apply (nothing is random); ``twin_samples = 0`` leaves the twin out.
"""

from twin.reproductions.seed002.report import failed, format_report, markdown_tables, record, run, write_plots

__all__ = ["failed", "format_report", "markdown_tables", "record", "run", "write_plots"]
