"""Seed 004 (Choi, Hong, Kim, Kim 1999): the entry points ``twin reproduce seed004`` calls.

:mod:`.procedure` computes (loop-shaping design, reduction, PID, mu analysis and sampled
plants, ZPETC, the circle tests on the transfer functions and the twin); :mod:`.report`
prints and plots.  ``samples`` random plants per controller beside the 1024 corners;
``twin_samples = 0`` leaves the twin out.
"""

from twin.reproductions.seed004.report import (
    certificates,
    failed,
    format_report,
    markdown_tables,
    record,
    run,
    write_plots,
)

__all__ = ["certificates", "failed", "format_report", "markdown_tables", "record", "run", "write_plots"]
