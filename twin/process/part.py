"""The virtual part: the stock cut a second time where the twin actually moved the tool, and
its walls against the nominal part's.

A wall's place must be known to a micrometre whatever the height map's cell, so the part is
held here as exact sections: at a height z the material is the stock's outline less every disc
the tool swept at that height (its radius there: the full radius above a ball or bull-nose
corner, the corner's circle within it), a shapely polygon whose circles are drawn within
:data:`CIRCLE_TOLERANCE_MM`.  The nominal section is swept along the planned reference (the
program within the planner's path tolerance); the actual one along the table's measured path
at the recorded ticks, with the planned Z (this twin moves X and Y).  Along the nominal
section's machined boundary (not the stock's own outline), every :data:`WALL_STEP_MM`, the
signed distance to the actual section's boundary is the wall error: positive where material is
left (the actual wall stands in what the program removes), negative where the tool overcut.
Each wall point is credited to the program line of the nearest nominal tool position.

The sections are taken at :func:`wall_levels`: the middle of each band between the heights the
tool cut at (the floors of a 2.5-D part), so that each wall is read once per step-down.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
import shapely
from scipy.spatial import cKDTree

if TYPE_CHECKING:
    from twin.process.part_map import PartMap

#: The tool's circles are polygons within this of the true circle (mm): 0.05 µm.
CIRCLE_TOLERANCE_MM = 5e-5
#: Spacing of the wall points along the nominal part's machined boundary (mm).
WALL_STEP_MM = 0.05
#: Wall points at most over all levels (the spacing grows past it: memory stays bounded).
MAX_WALL_POINTS = 200_000
#: Wall levels at most (a 3-D program cut at many heights gets this many, evenly spaced).
MAX_WALL_LEVELS = 16
#: A height the tool cut at counts as a floor with at least this many samples moving in XY.
MIN_FLOOR_SAMPLES = 10
#: Samples whose swept radius differs by less than this (mm) are swept as one line.
SAME_RADIUS_MM = 1e-6
#: A nominal boundary point this near the stock's own outline (mm) is not machined.
ON_STOCK_MM = 1e-4
#: Runs of one radius a section sweeps at most (about 5 s of GEOS buffering and union).  A
#: tool that moves in Z through a level (a 3-D surface, a long ramp) sweeps a new radius at
#: every sample there: such a level is not sectioned, and its surface is in the height maps'
#: floor error instead (:mod:`twin.process.part_map`).
MAX_SECTION_RUNS = 20_000


class SectionTooComplex(ValueError):
    """A section would sweep more than :data:`MAX_SECTION_RUNS` runs of one radius."""


def quad_segs(radius_mm: float) -> int:
    """Segments per quarter circle so that a polygon of the circle of ``radius_mm`` lies within
    :data:`CIRCLE_TOLERANCE_MM` of it (the sagitta of each segment)."""
    if radius_mm <= CIRCLE_TOLERANCE_MM:
        return 1
    return max(1, math.ceil((math.pi / 2) / (2 * math.acos(1 - CIRCLE_TOLERANCE_MM / radius_mm))))


def swept_radius_mm(tip_mm: np.ndarray, radius_mm: np.ndarray, corner_mm: np.ndarray, z_mm: float) -> np.ndarray:
    """The tool's radius at height ``z_mm`` over tips at ``tip_mm`` (mm; 0 at or under the tip):
    the full radius above the corner, ``r - rc + sqrt(rc^2 - (rc - h)^2)`` at a height h within it."""
    h = z_mm - tip_mm
    within = np.clip(corner_mm - h, 0.0, corner_mm)
    out = radius_mm - corner_mm + np.sqrt(np.maximum(corner_mm**2 - within**2, 0.0))
    return np.where(h > 0.0, out, 0.0)


def section(stock: shapely.Geometry, xy_mm, tip_mm, radius_mm, corner_mm, z_mm: float) -> shapely.Geometry:
    """The material at height ``z_mm``: ``stock`` less the tool's discs at that height.

    Parameters
    ----------
    stock : shapely geometry
        The stock's outline less its islands (mm).
    xy_mm : ndarray (n, 2)
        The tool's axis in time order (mm).
    tip_mm, radius_mm, corner_mm : ndarray (n,)
        The tool's tip height, radius and corner radius at each sample (mm).
    z_mm : float

    Raises
    ------
    SectionTooComplex
        More than :data:`MAX_SECTION_RUNS` runs of one radius.
    """
    r = swept_radius_mm(np.asarray(tip_mm), np.asarray(radius_mm), np.asarray(corner_mm), z_mm)
    on = r > 0.0
    # runs of samples the tool sweeps at one radius: each a line (one sample: a point)
    change = np.flatnonzero(np.diff(on.astype(int)) != 0) + 1
    change = np.union1d(change, np.flatnonzero(np.abs(np.diff(r)) > SAME_RADIUS_MM) + 1)
    starts = np.concatenate([[0], change])
    ends = np.concatenate([change, [len(r)]])
    runs = int(np.count_nonzero(on[starts]))
    if runs > MAX_SECTION_RUNS:
        raise SectionTooComplex(
            f"the tool sweeps {runs} radii at Z {z_mm:g} mm (it moves in Z there), over {MAX_SECTION_RUNS}"
        )
    by_radius: dict[float, list] = {}
    for a, b in zip(starts, ends):
        if not on[a]:
            continue
        # a run is joined to the sample before it, so that the sweep has no gap between runs
        pts = xy_mm[max(a - 1, 0) if a > 0 and on[a - 1] else a : b]
        shape = shapely.LineString(pts) if len(pts) > 1 else shapely.Point(pts[0])
        by_radius.setdefault(round(float(r[a:b].min()), 9), []).append(shape)
    swept = [
        shapely.buffer(shapely.GeometryCollection(shapes), radius, quad_segs=quad_segs(radius))
        for radius, shapes in by_radius.items()
    ]
    return shapely.difference(stock, shapely.union_all(swept)) if swept else stock


def points_along(lines: shapely.Geometry, step_mm: float) -> np.ndarray:
    """Points every ``step_mm`` along each line of ``lines`` (a line, rings, a collection: mm),
    shape (m, 2); the points and polygons in it are left out."""
    out = []
    for line in shapely.get_parts(lines):
        if line.geom_type not in ("LineString", "LinearRing") or line.length == 0.0:
            continue
        at = np.arange(0.0, line.length, step_mm)
        out.append(shapely.get_coordinates(shapely.line_interpolate_point(line, at)))
    return np.concatenate(out) if out else np.zeros((0, 2))


def wall_levels(tip_mm: np.ndarray, moving: np.ndarray, top_mm: float, bottom_mm: float) -> list[float]:
    """The heights (mm) the part's walls are read at: the middle of each band between the
    stock's top and the heights the tool cut at moving in XY (floors, with at least
    :data:`MIN_FLOOR_SAMPLES` samples), the lowest clipped at the stock's bottom; more than
    :data:`MAX_WALL_LEVELS` bands (a 3-D program): that many evenly from the top to the lowest."""
    cut = moving & (tip_mm < top_mm)
    heights, counts = np.unique(np.round(np.maximum(tip_mm[cut], bottom_mm), 4), return_counts=True)
    floors = np.sort(heights[counts >= MIN_FLOOR_SAMPLES])[::-1]
    if len(floors) == 0:
        return []
    edges = np.concatenate([[top_mm], floors])
    if len(floors) > MAX_WALL_LEVELS:
        edges = np.linspace(top_mm, floors[-1], MAX_WALL_LEVELS + 1)
    return [float(z) for z in 0.5 * (edges[:-1] + edges[1:])]


@dataclass
class Sweep:
    """A tool path through the stock, all in mm.

    Attributes
    ----------
    xy_mm : ndarray (n, 2)
        The tool's axis relative to the stock.
    tip_mm, radius_mm, corner_mm : ndarray (n,)
        Its tip height, radius and corner radius.
    line : ndarray (n,) of int
        The program line at each sample.
    """

    xy_mm: np.ndarray
    tip_mm: np.ndarray
    radius_mm: np.ndarray
    corner_mm: np.ndarray
    line: np.ndarray

    def section(self, stock: shapely.Geometry, z_mm: float) -> shapely.Geometry:
        """The material this sweep leaves of ``stock`` at ``z_mm`` (:func:`section`)."""
        return section(stock, self.xy_mm, self.tip_mm, self.radius_mm, self.corner_mm, z_mm)


@dataclass
class MachinedPart:
    """The part the twin's actual motion cut, against the nominal one (:func:`machined_part`).

    Attributes
    ----------
    stock : shapely geometry
        The stock's outline less its islands (mm).
    nominal, actual : Sweep
        The planned and the measured tool paths.
    levels_mm : list of float
        The heights the walls were read at (:func:`wall_levels`).
    walls : ndarray (m, 5)
        Wall points: x, y, z (mm), signed error (µm: material left positive, overcut negative)
        and the program line that formed them.
    skipped_levels_mm : list of float
        Levels not read: the tool moves in Z through them (:class:`SectionTooComplex`).
    maps : PartMap or None
        The nominal and actual height maps (:mod:`twin.process.part_map`), when computed.
    floor_error_um : dict
        Their error on the floors and 3-D surfaces (:meth:`PartMap.floor_error`).
    """

    stock: shapely.Geometry
    nominal: Sweep
    actual: Sweep
    levels_mm: list[float]
    walls: np.ndarray
    skipped_levels_mm: list[float] = field(default_factory=list)
    maps: PartMap | None = None
    floor_error_um: dict = field(default_factory=dict)

    def sections(self, z_mm: float) -> tuple[shapely.Geometry, shapely.Geometry]:
        """The nominal and the actual material at ``z_mm``."""
        return self.nominal.section(self.stock, z_mm), self.actual.section(self.stock, z_mm)

    def summary(self) -> dict:
        """``part`` of ``twin run --json``: the wall error's min, max and RMS (µm), the levels
        read and the points, the floors' error and the levels skipped, where there are."""
        err = self.walls[:, 3]
        stats = (
            {
                "min": round(float(err.min()), 3),
                "max": round(float(err.max()), 3),
                "rms": round(float(np.sqrt(np.mean(err**2))), 3),
            }
            if err.size
            else {}
        )
        out = {
            "surface_error_um": stats,
            "wall_levels_mm": [round(z, 4) for z in self.levels_mm],
            "wall_points": int(err.size),
        }
        if self.floor_error_um:
            out["floor_error_um"] = self.floor_error_um
        if self.skipped_levels_mm:
            out["skipped_levels_mm"] = [round(z, 4) for z in self.skipped_levels_mm]
            out["skipped_note"] = (
                f"the tool moves in Z through these levels (over {MAX_SECTION_RUNS} swept radii): "
                "their surfaces are in floor_error_um"
            )
        return out

    def line_errors(self) -> dict[int, float]:
        """Per program line, its wall points' error furthest from zero (µm, signed)."""
        out: dict[int, float] = {}
        for line in np.unique(self.walls[:, 4]).astype(int):
            err = self.walls[self.walls[:, 4] == line, 3]
            out[int(line)] = round(float(err[np.argmax(np.abs(err))]), 3)
        return out


def wall_errors(stock, nominal: Sweep, actual: Sweep, levels_mm: list[float]) -> tuple[np.ndarray, list[float]]:
    """Wall points of the nominal part at each of ``levels_mm`` with their signed error against
    the actual part (µm) and line, shape (m, 5): see :class:`MachinedPart`; and the levels not
    read (:class:`SectionTooComplex`)."""
    outline = stock.boundary
    sections, skipped = {}, []
    for z in levels_mm:
        try:
            sections[z] = (nominal.section(stock, z), actual.section(stock, z))
        except SectionTooComplex:
            skipped.append(z)
    length = sum(want.boundary.length for want, _ in sections.values())
    step = max(WALL_STEP_MM, length / MAX_WALL_POINTS)
    rows = []
    for z, (want, got) in sections.items():
        pts = points_along(want.boundary, step)
        if len(pts) == 0:
            continue
        pts = pts[shapely.distance(shapely.points(pts), outline) > ON_STOCK_MM]
        if len(pts) == 0:
            continue
        distance = (
            shapely.distance(shapely.points(pts), got.boundary) if not got.is_empty else np.full(len(pts), np.inf)
        )
        sign = np.where(shapely.contains_xy(got, pts[:, 0], pts[:, 1]), 1.0, -1.0)
        below = swept_radius_mm(nominal.tip_mm, nominal.radius_mm, nominal.corner_mm, z) > 0.0
        _, nearest = cKDTree(nominal.xy_mm[below]).query(pts)
        line = nominal.line[below][nearest]
        rows.append(np.column_stack([pts, np.full(len(pts), z), sign * distance * 1e3, line]))
    return (np.concatenate(rows) if rows else np.zeros((0, 5))), skipped


def machined_part(stock, nominal: Sweep, actual: Sweep, top_mm: float, bottom_mm: float) -> MachinedPart:
    """The virtual part of a run: the walls of the nominal sweep's part read against the actual
    sweep's at :func:`wall_levels` of the nominal path."""
    step = np.diff(nominal.xy_mm, axis=0, prepend=nominal.xy_mm[:1])
    moving = np.hypot(step[:, 0], step[:, 1]) > 1e-6
    levels = wall_levels(nominal.tip_mm, moving, top_mm, bottom_mm)
    walls, skipped = wall_errors(stock, nominal, actual, levels)
    return MachinedPart(stock, nominal, actual, [z for z in levels if z not in skipped], walls, skipped)
