"""Crashes and misuse of a part program through its stock, per program line, from the
engagement along the planned path (:func:`twin.machining.engagement.engagement_table`): a rapid
through material, the spindle off in material, the tip below the stock's bottom in material,
material above the flute length (the shank or holder rubs), a descent into material steeper
than the tool's ``max_ramp_deg``, a feed per tooth outside the tool's ``feed_per_tooth_mm``.

Each is a warning with the line, its text and the worst value on that line; ``twin run
--strict`` turns any warning into exit code 4.
"""

from __future__ import annotations

import numpy as np

from twin.machining.engagement import COLUMNS, StockSpec, ToolSpec
from twin.records import MachiningWarning

#: Warnings kept (the first by line); the count of all is reported beside them.
MAX_WARNINGS = 1000
#: Material thinner than this (mm) is not a crash: slivers of the planner's blends (a corner
#: rounded within its tolerance as the tool starts down leaves micrometres standing).
MIN_MATERIAL_MM = 0.01
#: Degrees a descent may exceed the tool's max_ramp_deg by (the planner's rounding of a corner).
RAMP_SLACK_DEG = 0.5

_COLUMN = {name: i for i, name in enumerate(COLUMNS)}

#: Each warning's kind: its unit and message (``{value}`` the worst value on the line).
KINDS = {
    "rapid_through_material": ("mm", "a rapid (G0) moves through material {value:.3f} mm deep"),
    "spindle_off_in_material": ("mm", "the spindle is off with the tool {value:.3f} mm in material"),
    "below_stock_bottom": ("mm", "the tool's tip is {value:.3f} mm below the stock's bottom (bottom_mm) in material"),
    "deeper_than_flutes": ("mm", "material stands {value:.3f} mm above the flute length (the shank or holder rubs)"),
    "plunge_too_steep": ("deg", "goes down into material at {value:.1f} deg, steeper than the tool's max_ramp_deg"),
    "feed_per_tooth": ("mm", "feed per tooth {value:.4f} mm outside the tool's feed_per_tooth_mm"),
}


def machining_warnings(
    plan, *, table: np.ndarray, tools: list[ToolSpec], tool_index: np.ndarray, spindle_rpm: np.ndarray, stock: StockSpec
):
    """The warnings of a program through its stock, and how many there are in all.

    Parameters
    ----------
    plan : twin.gcode.planner.Plan
    table : ndarray (n, len(COLUMNS))
        The engagement along ``plan`` (:func:`twin.machining.engagement.engagement_table`).
    tools : list of ToolSpec
        The tools in use; ``tool_index`` (n,) says which at each sample.
    spindle_rpm : ndarray (n,)
        The spindle speed at each sample (rev/min, 0 stopped).
    stock : StockSpec

    Returns
    -------
    warnings : list of twin.records.MachiningWarning
        By line, at most :data:`MAX_WARNINGS`.
    total : int
        Every warning (over :data:`MAX_WARNINGS` some are not listed).
    """
    depth = np.maximum(table[:, _COLUMN["max_depth_mm"]], table[:, _COLUMN["under_tip_mm"]])
    touched = depth > MIN_MATERIAL_MM
    z_mm = plan.position[:, 2] * 1e3
    feed = plan.per_sample(plan.feeds, 0.0)
    moving = np.linalg.norm(plan.velocity, axis=1) > 1e-9
    flutes = np.array([t.n_flutes for t in tools])[tool_index]
    over = table[:, _COLUMN["over_flutes_mm"]]
    below = stock.bottom_mm - z_mm
    # each kind: where, the value reported, and how bad (the worst of a line is listed)
    found: dict[str, tuple[np.ndarray, np.ndarray, np.ndarray]] = {
        "rapid_through_material": (touched & moving & (feed == 0), depth, depth),
        "spindle_off_in_material": (touched & (spindle_rpm == 0), depth, depth),
        "below_stock_bottom": (touched & (below > MIN_MATERIAL_MM), below, below),
        "deeper_than_flutes": (over > MIN_MATERIAL_MM, over, over),
    }
    descent = np.degrees(np.arctan2(-plan.velocity[:, 2], np.hypot(plan.velocity[:, 0], plan.velocity[:, 1])))
    limit = np.array([t.max_ramp_deg for t in tools])[tool_index]
    down = table[:, _COLUMN["under_tip_mm"]] > MIN_MATERIAL_MM
    found["plunge_too_steep"] = (down & (descent > limit + RAMP_SLACK_DEG), descent, descent)
    with np.errstate(divide="ignore", invalid="ignore"):
        per_tooth = np.where(spindle_rpm > 0, feed / (spindle_rpm * flutes), 0.0)
    lo = np.array([-np.inf if t.feed_per_tooth_mm is None else t.feed_per_tooth_mm[0] for t in tools])[tool_index]
    hi = np.array([np.inf if t.feed_per_tooth_mm is None else t.feed_per_tooth_mm[1] for t in tools])[tool_index]
    outside = touched & (spindle_rpm > 0) & (feed > 0) & ((per_tooth < lo) | (per_tooth > hi))
    # the worst is the farthest outside the range, in the range's own terms
    found["feed_per_tooth"] = (outside, per_tooth, np.maximum(lo - per_tooth, per_tooth - hi))
    rows = []
    for kind, (mask, value, badness) in found.items():
        if not mask.any():
            continue
        score = badness[mask]
        lines, values = plan.line[mask], value[mask]
        order = np.lexsort((-score, lines))  # by line, the worst first
        lines, values = lines[order], values[order]
        first = np.flatnonzero(np.concatenate([[True], lines[1:] != lines[:-1]]))
        unit, message = KINDS[kind]
        for line, worst in zip(lines[first].tolist(), values[first].tolist()):
            rows.append(
                MachiningWarning(
                    line=int(line),
                    text=plan.texts.get(int(line), ""),
                    kind=kind,
                    value=round(float(worst), 4),
                    unit=unit,
                    message=message.format(value=worst),
                )
            )
    rows.sort(key=lambda row: (row.line, row.kind))
    return rows[:MAX_WARNINGS], len(rows)
