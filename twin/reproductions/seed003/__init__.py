"""Seed 003 (Maharof 2021): the entry points ``twin reproduce seed003`` calls.

:mod:`.procedure` computes (cascade design, IMBDO Q-filter, the numerical cases on the
transfer-function loop and the twin); :mod:`.report` prints and plots.  ``samples`` and
``seed`` do not apply; ``twin_samples = 0`` leaves the twin out.
"""

from twin.reproductions.seed003.report import failed, format_report, markdown_tables, record, run, write_plots

__all__ = ["failed", "format_report", "markdown_tables", "record", "run", "write_plots"]
