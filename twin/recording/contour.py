"""The XY contour in mm on the plane z = 0, seen from above (+x right, +y up, as on the
machine): reference, actual path, the error magnified about the reference, and a tool marker
that follows the time cursor."""

from __future__ import annotations

import numpy as np
import rerun as rr

#: Colours: reference grey, actual blue, magnified error red, tool yellow.
REFERENCE_COLOR, ACTUAL_COLOR, ERROR_COLOR, TOOL_COLOR = (150, 150, 150), (30, 140, 255), (230, 60, 60), (255, 220, 0)


def _xyz(xy_mm: np.ndarray) -> np.ndarray:
    return np.column_stack([xy_mm, np.zeros(len(xy_mm))])


def log_contour(rec, result, prefix: str, rows: slice, gain: int) -> None:
    """``contour/reference``, ``contour/actual``, ``contour/error_x<gain>`` (static line strips)
    and ``contour/tool`` (a point over time), all in mm."""
    ref = result.ref[rows, :, 0] * 1e3
    act = result.table_position_m()[rows] * 1e3
    root = f"{prefix}contour"
    rec.log(root, rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
    rec.log(f"{root}/reference", rr.LineStrips3D([_xyz(ref)], colors=[REFERENCE_COLOR], radii=[-1.0]), static=True)
    rec.log(f"{root}/actual", rr.LineStrips3D([_xyz(act)], colors=[ACTUAL_COLOR], radii=[-3.0]), static=True)
    rec.log(
        f"{root}/error_x{gain}",
        rr.LineStrips3D([_xyz(ref + gain * (act - ref))], colors=[ERROR_COLOR], radii=[-1.5]),
        static=True,
    )
    rec.log(f"{root}/tool", rr.Points3D.from_fields(colors=[TOOL_COLOR], radii=[-8.0]), static=True)
    rec.send_columns(
        f"{root}/tool",
        indexes=[rr.TimeColumn("sim_time", duration=result.t_s[rows])],
        columns=rr.Points3D.columns(positions=_xyz(act)),
    )
