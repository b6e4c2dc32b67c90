"""Seed 001 (Sabau 2022): the entry points ``twin reproduce seed001`` calls.

:mod:`.procedure` computes (relay test and Ziegler-Nichols, cascades, state feedback by pole
placement, LQR and LMI regions with their cascades, the fractional PI and the structured-mu
cascade, the bee colony, the trajectories of Table 2, on the transfer functions and the
twin); :mod:`.report` prints and plots.
"""

from twin.reproductions.seed001.report import failed, format_report, markdown_tables, record, run, write_plots

__all__ = ["failed", "format_report", "markdown_tables", "record", "run", "write_plots"]
