"""The XY contour in mm on the plane z = 0, seen from above (+x right, +y up, as on the
machine): reference, actual path, the error magnified about the reference, and a tool marker
that follows the time cursor."""

from __future__ import annotations

import numpy as np
import rerun as rr

from twin.machining.part import MachinedPart
from twin.outcome import RunOutcome

#: Colours: reference grey, actual blue, magnified error red, tool yellow.
REFERENCE_COLOR, ACTUAL_COLOR, ERROR_COLOR, TOOL_COLOR = (150, 150, 150), (30, 140, 255), (230, 60, 60), (255, 220, 0)
#: Colours of a program's stock outline (light grey) and machined outline (white).
STOCK_COLOR, MACHINED_COLOR = (110, 110, 110), (235, 235, 235)
#: The contour-error colour scale, low to high: blue, green, yellow, red.
SCALE_STOPS = np.array([[40, 90, 220], [40, 190, 90], [250, 220, 40], [230, 40, 40]], float)
#: The wall error's colours: overcut blue, exact violet (apart from the white machined outline
#: it is drawn over), material left red.
OVERCUT_COLOR, EXACT_COLOR, LEFT_COLOR = (
    np.array([40, 90, 220.0]),
    np.array([190, 140, 255.0]),
    np.array([230, 40, 40.0]),
)
#: The inspection's labels are this share of the part's height apart.
LABEL_SPACING = 0.12
#: Segments of the colour scale drawn beside the part.
SCALE_STEPS = 10


def scale_colors(values: np.ndarray, top: float) -> np.ndarray:
    """RGB (uint8) of ``values`` on :data:`SCALE_STOPS` from 0 to ``top``."""
    x = np.clip(np.asarray(values, float) / top if top > 0 else 0.0, 0.0, 1.0) * (len(SCALE_STOPS) - 1)
    lo = np.minimum(x.astype(int), len(SCALE_STOPS) - 2)
    frac = (x - lo)[..., None]
    return ((1 - frac) * SCALE_STOPS[lo] + frac * SCALE_STOPS[lo + 1]).astype(np.uint8)


def wall_colors(error_um: np.ndarray) -> np.ndarray:
    """RGB (uint8) of signed wall errors: violet at 0, red (material left) or blue (overcut) at
    the largest magnitude of either sign."""
    top = float(np.abs(error_um).max()) if error_um.size else 0.0
    frac = (np.abs(error_um) / top if top > 0 else np.zeros_like(error_um))[:, None]
    end = np.where((error_um >= 0)[:, None], LEFT_COLOR, OVERCUT_COLOR)
    return ((1 - frac) * EXACT_COLOR + frac * end).astype(np.uint8)


def _xyz(xy_mm: np.ndarray) -> np.ndarray:
    return np.column_stack([xy_mm, np.zeros(len(xy_mm))])


def log_contour(rec, outcome: RunOutcome, *, prefix: str, rows: slice, gain: int) -> None:
    """``contour/reference``, ``contour/actual`` (a program's: ``contour/path_by_contour_error``,
    see :func:`log_program`), ``contour/error_x<gain>`` (static line strips) and ``contour/tool``
    (a point over time), all in mm."""
    result = outcome.run
    ref = result.ref[rows, :, 0] * 1e3
    act = result.table_position_m()[rows] * 1e3
    root = f"{prefix}contour"
    rec.log(root, rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
    rec.log(f"{root}/reference", rr.LineStrips3D([_xyz(ref)], colors=[REFERENCE_COLOR], radii=[-1.0]), static=True)
    is_program = result.program is not None and result.program.lines.size > 0
    if not is_program:  # a program's actual path is drawn coloured by its error
        rec.log(f"{root}/actual", rr.LineStrips3D([_xyz(act)], colors=[ACTUAL_COLOR], radii=[-3.0]), static=True)
    rec.log(
        f"{root}/error_x{gain}",
        rr.LineStrips3D([_xyz(ref + gain * (act - ref))], colors=[ERROR_COLOR], radii=[-1.5]),
        static=True,
    )
    if is_program:
        log_program(rec, outcome, root=root, rows=rows, ref=ref, act=act)
    rec.log(f"{root}/tool", rr.Points3D.from_fields(colors=[TOOL_COLOR], radii=[-8.0]), static=True)
    rec.send_columns(
        f"{root}/tool",
        indexes=[rr.TimeColumn("sim_time", duration=result.t_s[rows])],
        columns=rr.Points3D.columns(positions=_xyz(act)),
    )


def log_program(rec, outcome: RunOutcome, *, root: str, rows: slice, ref: np.ndarray, act: np.ndarray) -> None:
    """A program's part: the stock and machined outlines, the path coloured by its contour error
    (``path_by_contour_error``) and the colour scale beside it with its ends labelled (µm)."""
    result = outcome.run
    from twin.metrics import contour_error, run_contour_error

    for name, color in (("stock", STOCK_COLOR), ("machined", MACHINED_COLOR)):
        rings = outcome.outlines.get(name, [])
        if rings:
            rec.log(
                f"{root}/{name}", rr.LineStrips3D([_xyz(r) for r in rings], colors=[color], radii=[-1.0]), static=True
            )
    ce = run_contour_error(result)  # the per-line table's own (None: a path that is not 2-D)
    error_um = (contour_error(act * 1e-3, ref * 1e-3) if ce is None else ce[rows]) * 1e6
    top = float(error_um.max()) if error_um.size else 0.0
    segments = np.stack([_xyz(act[:-1]), _xyz(act[1:])], axis=1)
    rec.log(
        f"{root}/path_by_contour_error",
        rr.LineStrips3D(segments, colors=scale_colors(error_um[1:], top), radii=[-4.0]),
        static=True,
    )
    if outcome.part is not None and len(outcome.part.walls):
        log_part(rec, outcome, outcome.part, root)
    every = [*(r for rings in outcome.outlines.values() for r in rings), act]  # the scale right of all
    x_max, y_min, y_max = (
        max(r[:, 0].max() for r in every),
        min(r[:, 1].min() for r in every),
        max(r[:, 1].max() for r in every),
    )
    x = x_max + 0.05 * (y_max - y_min) + 1.0
    ys = np.linspace(y_min, y_max, SCALE_STEPS + 1)
    bars = [np.array([[x, ys[i], 0.0], [x, ys[i + 1], 0.0]]) for i in range(SCALE_STEPS)]
    levels = (np.arange(SCALE_STEPS) + 0.5) / SCALE_STEPS * top
    rec.log(f"{root}/scale", rr.LineStrips3D(bars, colors=scale_colors(levels, top), radii=[-10.0]), static=True)
    rec.log(
        f"{root}/scale/labels",
        rr.Points3D([[x, y_min, 0.0], [x, y_max, 0.0]], labels=["0 µm", f"{top:.1f} µm contour error"], radii=[-1.0]),
        static=True,
    )


def log_part(rec, outcome: RunOutcome, part: MachinedPart, root: str) -> None:
    """The virtual part: its wall points at their heights coloured by the signed wall error
    (``part_walls``, mm, :func:`wall_colors`) and each measured feature's result as a label
    at its measured centre or position (``inspection``)."""
    walls = part.walls
    rec.log(
        f"{root}/part_walls",
        rr.Points3D(walls[:, :3], colors=wall_colors(walls[:, 3]), radii=[-3.0]),
        static=True,
    )
    outline = [ring for rings in outcome.outlines.values() for ring in rings]
    span = float(np.ptp(np.concatenate([walls[:, 1], *(ring[:, 1] for ring in outline)]))) if len(walls) else 1.0
    places: list[list[float]] = []
    labels: list[str] = []
    for feature in outcome.inspection:
        place = feature.place_mm
        if place is not None:  # each label a line lower than the last: features share centres
            places.append([place[0], place[1] - LABEL_SPACING * span * len(places), feature.z_mm])
            labels.append(feature.label())
    if places:
        rec.log(f"{root}/inspection", rr.Points3D(places, labels=labels, radii=[-6.0]), static=True)
