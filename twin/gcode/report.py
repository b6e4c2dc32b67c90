"""What ``twin gcode`` and :func:`twin.api.program` report of a program: its moves as read and,
for a machine, the planned reference's cycle time, limits and largest values per axis, the
limits it could not keep, and how far it leaves the programmed path (the exact distance of each
sample to the nearest programmed line or arc, against the tolerance in force there)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from twin.gcode.path import SegmentKind
from twin.gcode.planned import Limits, Violation
from twin.gcode.planner import Plan
from twin.records import PlanWarning

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


@dataclass(frozen=True, kw_only=True)
class PlannedSummary:
    """A program planned for a machine as ``twin gcode --machine`` reports it (``planned``).

    Attributes
    ----------
    cycle_time_s, feed_only_time_s : float
        The planned reference's duration (s) and that of its feed moves alone (s), to 1 µs.
    time_scale : float
        How much the plan was slowed to keep its limits (1: not), to 6 decimals.
    filter_s : float
        The smoothing filter's length (s).
    tolerance_mm : float
        The path tolerance (mm).
    limits : Limits
        The axes' limits planned to.
    max_abs : dict of str to dict of str to float
        Per axis, the largest ``velocity_m_per_s``, ``acceleration_m_per_s2`` and
        ``jerk_m_per_s3`` of the samples (:meth:`twin.gcode.planner.Plan.max_abs`).
    max_path_deviation_mm : float
        The largest distance of a sample to the programmed path (mm, to 1 nm).
    max_deviation_over_tolerance : float
        The largest ratio of that distance to the tolerance in force there.
    violations : tuple of Violation
        The limits the reference still exceeds.
    notes : tuple of str
        What the planner says of the program.
    warnings : tuple of TravelWarning or DriveWarning
        The first warnings against the machine (:func:`twin.gcode.checks.plan_warnings`).
    warnings_total : int
        How many warnings there are in all, listed or not.
    """

    cycle_time_s: float
    feed_only_time_s: float
    time_scale: float
    filter_s: float
    tolerance_mm: float
    limits: Limits
    max_abs: dict[str, dict[str, float]]
    max_path_deviation_mm: float
    max_deviation_over_tolerance: float
    violations: tuple[Violation, ...]
    notes: tuple[str, ...]
    warnings: tuple[PlanWarning, ...] = ()
    warnings_total: int = 0

    def headline(self) -> dict[str, float]:
        """The plan's single values, as the text report lists them: times (s), time scale,
        filter (s), tolerance (mm) and path deviation (mm, and over the tolerance)."""
        return {
            "cycle_time_s": self.cycle_time_s,
            "feed_only_time_s": self.feed_only_time_s,
            "time_scale": self.time_scale,
            "filter_s": self.filter_s,
            "tolerance_mm": self.tolerance_mm,
            "max_path_deviation_mm": self.max_path_deviation_mm,
            "max_deviation_over_tolerance": self.max_deviation_over_tolerance,
        }

    def axis_line(self, axis: str) -> str:
        """An axis's largest velocity, acceleration and jerk against its limits, as the text
        report gives them (``axis``: x, y or z)."""
        limit, top = self.limits.as_dict()[axis], self.max_abs[axis]
        return (
            f"{axis}: v {top['velocity_m_per_s']:.4g}/{limit['velocity_m_per_s']:.4g} m/s, "
            f"a {top['acceleration_m_per_s2']:.4g}/{limit['acceleration_m_per_s2']:.4g} m/s^2, "
            f"j {top['jerk_m_per_s3']:.4g}/{limit['jerk_m_per_s3']:.4g} m/s^3 (largest/limit)"
        )

    def to_json(self) -> dict[str, Any]:
        """What ``twin gcode --machine --json`` prints as ``planned``: the attributes in their
        order, ``max_abs`` as ``max``, ``warnings_total`` only where more than listed."""
        out: dict[str, Any] = {
            "cycle_time_s": self.cycle_time_s,
            "feed_only_time_s": self.feed_only_time_s,
            "time_scale": self.time_scale,
            "filter_s": self.filter_s,
            "tolerance_mm": self.tolerance_mm,
            "limits": self.limits.as_dict(),
            "max": self.max_abs,
            "max_path_deviation_mm": self.max_path_deviation_mm,
            "max_deviation_over_tolerance": self.max_deviation_over_tolerance,
            "violations": [v.as_dict() for v in self.violations],
            "notes": list(self.notes),
            "warnings": [w.to_json() for w in self.warnings],
        }
        if self.warnings_total > len(self.warnings):
            out["warnings_total"] = self.warnings_total
        return out


def planned_summary(
    plan: Plan, limits: Limits, *, warnings: Sequence[PlanWarning] = (), warnings_total: int = 0
) -> PlannedSummary:
    """The ``planned`` table of ``twin gcode --json``: ``plan`` of a program planned to
    ``limits``, with the first ``warnings`` against the machine and how many there are in all
    (``warnings_total``)."""
    deviation = path_deviation_m(plan)
    tolerance = np.where(plan.sample_tolerance_m > 0, plan.sample_tolerance_m, np.inf)
    return PlannedSummary(
        cycle_time_s=round(plan.cycle_time_s, 6),
        feed_only_time_s=round(plan.feed_only_time_s, 6),
        time_scale=round(plan.time_scale, 6),
        filter_s=plan.filter_s,
        tolerance_mm=plan.tolerance_m * 1e3,
        limits=limits,
        max_abs=plan.max_abs(),
        max_path_deviation_mm=round(float(deviation.max()) * 1e3, 6),
        max_deviation_over_tolerance=round(float((deviation / tolerance).max()), 6),
        violations=tuple(plan.violations),
        notes=tuple(plan.notes),
        warnings=tuple(warnings),
        warnings_total=warnings_total,
    )
