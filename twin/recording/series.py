"""Rerun logging of a run's named series (:func:`twin.series.named_series`)."""

from __future__ import annotations

import numpy as np
import rerun as rr

from twin.series import named_series


def log_series(rec, result, prefix: str, rows: slice) -> None:
    """Every series of :func:`twin.series.named_series` at the recorded ``rows``, under
    ``prefix``, each with its legend name and unit."""
    t = result.t_s[rows]
    for series in named_series(result, rows):
        path = f"{prefix}{series.path}"
        rec.log(
            path,
            rr.SeriesLines(names=f"{series.name} ({series.unit})", colors=series.color, widths=series.width),
            static=True,
        )
        rec.send_columns(
            path,
            indexes=[rr.TimeColumn("sim_time", duration=t)],
            columns=rr.Scalars.columns(scalars=np.ascontiguousarray(series.values, float)),
        )
