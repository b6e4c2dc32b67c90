"""What ``twin gcode`` and :func:`twin.api.program` report of a program: its moves as read and,
for a machine, the planned reference's cycle time, limits and largest values per axis, the
limits it could not keep, and how far it leaves the programmed path (the exact distance of each
sample to the nearest programmed line or arc, against the tolerance in force there)."""

from __future__ import annotations

import numpy as np

from twin.gcode.path import SegmentKind
from twin.gcode.planned import Limits
from twin.gcode.planner import Plan

#: Spacing (m) of the points of the programmed path that find each sample's nearest segments.
PATH_SPACING_M = 2e-4
#: Most points of that sampling (coarser spacing beyond).
MAX_PATH_POINTS = 2_000_000
#: Nearest path points whose segments each sample is measured against exactly.
NEAREST = 6


def path_deviation_m(plan: Plan) -> np.ndarray:
    """The exact distance (m) of every sample of the planned reference to the programmed path
    (unblended): to the nearest of the segments whose points lie nearest it."""
    from scipy.spatial import cKDTree

    drawn = [seg for seg in plan.segments if seg.kind != SegmentKind.DWELL]
    if not drawn:
        return np.linalg.norm(plan.position - plan.position[:1], axis=1)
    total = sum(seg.length for seg in drawn)
    spacing = max(PATH_SPACING_M, total / MAX_PATH_POINTS)
    points, owner = [], []
    for i, seg in enumerate(drawn):
        s = np.linspace(0.0, seg.length, max(2, int(seg.length / spacing) + 2))
        points.append(seg.points(s))
        owner.append(np.full(s.size, i))
    path, owners = np.concatenate(points), np.concatenate(owner)
    tree = cKDTree(path)
    best = np.full(len(plan.position), np.inf)
    rows = np.arange(len(plan.position))
    for k in (NEAREST, 8 * NEAREST, 64 * NEAREST):
        # where the path passes near itself the nearest points can all be another segment's:
        # the samples not yet within their tolerance are looked at again with more of them
        k = min(k, len(path))
        _, nearest = tree.query(plan.position[rows], k=k)
        candidates = owners[nearest.reshape(len(rows), k)]
        # each (segment, sample) pair once, by segment: time linear in the samples (a pass over
        # every sample per segment made a 16 000-line program's check take minutes)
        pair = np.unique(candidates.astype(np.int64) * len(plan.position) + rows[:, None])
        segment, sample = pair // len(plan.position), pair % len(plan.position)
        starts = np.flatnonzero(np.concatenate([[True], segment[1:] != segment[:-1]]))
        for lo, hi in zip(starts, [*starts[1:], len(pair)]):
            mine = sample[lo:hi]
            best[mine] = np.minimum(best[mine], drawn[int(segment[lo])].distance(plan.position[mine]))
        rows = rows[best[rows] > plan.sample_tolerance_m[rows]]
        if rows.size == 0 or k == len(path):
            break
    return best


def max_path_deviation_m(plan: Plan) -> float:
    """The largest distance (m) from a sample of the planned reference to the programmed path."""
    return float(path_deviation_m(plan).max())


def planned_summary(plan: Plan, limits: Limits) -> dict:
    """The ``planned`` table of ``twin gcode --json``."""
    deviation = path_deviation_m(plan)
    tolerance = np.where(plan.sample_tolerance_m > 0, plan.sample_tolerance_m, np.inf)
    return {
        "cycle_time_s": round(plan.cycle_time_s, 6),
        "feed_only_time_s": round(plan.feed_only_time_s, 6),
        "time_scale": round(plan.time_scale, 6),
        "filter_s": plan.filter_s,
        "tolerance_mm": plan.tolerance_m * 1e3,
        "limits": limits.as_dict(),
        "max": plan.max_abs(),
        "max_path_deviation_mm": round(float(deviation.max()) * 1e3, 6),
        "max_deviation_over_tolerance": round(float((deviation / tolerance).max()), 6),
        "violations": [v.as_dict() for v in plan.violations],
        "notes": list(plan.notes),
    }
