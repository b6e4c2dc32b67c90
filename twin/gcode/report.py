"""What ``twin gcode`` and :func:`twin.api.gcode` report of a program: its moves as read and,
for a machine, the planned reference's cycle time, limits and largest values per axis, and how
far it leaves the programmed path."""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from twin.gcode.planner import Limits, Plan

#: Spacing (m) of the points the programmed path is sampled at for the deviation check.
PATH_SPACING_M = 2e-5
#: Most points of that sampling (coarser spacing beyond).
MAX_PATH_POINTS = 5_000_000


def programmed_points(plan: Plan) -> np.ndarray:
    """The programmed path (unblended) as a dense polyline (m), shape (n, 3)."""
    drawn = [seg for seg in plan.segments if seg.kind != "dwell"]
    total = sum(seg.length for seg in drawn)
    spacing = max(PATH_SPACING_M, total / MAX_PATH_POINTS)
    parts = [seg.points(np.linspace(0.0, seg.length, max(2, int(seg.length / spacing) + 2))) for seg in drawn]
    return np.concatenate(parts) if parts else plan.position[:1]


def max_path_deviation_m(plan: Plan) -> float:
    """The largest distance (m) from a sample of the planned reference to the programmed path:
    the nearest point of :func:`programmed_points` refined onto the chords around it."""
    path = programmed_points(plan)
    if len(path) < 2:
        return float(np.linalg.norm(plan.position - path[0], axis=1).max())
    _, nearest = cKDTree(path).query(plan.position)
    best = np.full(len(plan.position), np.inf)
    for lo in (nearest - 2, nearest - 1, nearest, nearest + 1):  # junction points appear twice
        lo = np.clip(lo, 0, len(path) - 2)
        a, b = path[lo], path[lo + 1]
        d = b - a
        length2 = np.einsum("ij,ij->i", d, d)
        f = np.clip(np.einsum("ij,ij->i", plan.position - a, d) / np.where(length2 > 0, length2, 1.0), 0.0, 1.0)
        best = np.minimum(best, np.linalg.norm(plan.position - (a + f[:, None] * d), axis=1))
    return float(best.max())


def planned_summary(plan: Plan, limits: Limits) -> dict:
    """The ``planned`` table of ``twin gcode --json``."""
    return {
        "cycle_time_s": round(plan.cycle_time_s, 6),
        "feed_only_time_s": round(plan.feed_only_time_s, 6),
        "time_scale": round(plan.time_scale, 6),
        "filter_s": plan.filter_s,
        "tolerance_mm": plan.tolerance_m * 1e3,
        "limits": limits.as_dict(),
        "max": plan.max_abs(),
        "max_path_deviation_mm": round(max_path_deviation_m(plan) * 1e3, 6),
    }
