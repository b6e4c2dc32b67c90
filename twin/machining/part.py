"""The virtual part: the stock cut a second time where the twin actually moved the tool, and
its walls against the nominal part's, at a cost set by the part, not by the run's samples.

At a height z the material is the stock's outline less every capsule the tool swept there: the
segment between two samples of the tool's axis widened by the tool's radius at that height (the
full radius above a ball or bull-nose corner, the corner's circle within it).  Where the tip
moves along the segment (a ramp, a helix, a plunge reaching the level) the radius changes along
it: the part of the segment where the tool reaches the level is swept in :data:`RAMP_PIECES`
pieces spaced as the squares of their index from its shallow end (a corner's radius grows as
the square root of the depth), each the hull of its end discs (within 0.5 µm of the continuous
sweep on a 20 mm ramp in one segment, 0.01 µm on a sampled one: a brute force in
``tests/test_part_bruteforce.py``).

- The **nominal** part's section is exact polygons (shapely): the planned reference (the
  program within the planner's path tolerance) is smooth, so each run of one radius is
  simplified within :data:`NOMINAL_SIMPLIFY_MM` (0.01 µm) before it is swept, and its cost is
  the path's geometry, whatever its sample count.
- The **actual** part (the table's measured path at the recorded ticks, with the planned Z: this
  twin moves X and Y) is never built as a polygon: a path with micrometre jitter at one sample
  per tick made gigabytes of polygons.  Instead each wall point is a probe, and the actual
  samples stream once past the probes (:func:`nearest_cuts`, compiled, the probes bucketed on a
  grid): each probe keeps the smallest signed distance ``|p - q| - r`` to a swept capsule (q the
  nearest point of its axis segment, r its radius there), the capsule's axis point and the
  program line of its sample.  Outside every capsule (material left) that minimum is the exact
  distance to the cut; inside (overcut) it is the depth in the deepest capsule, which is the
  exact depth wherever the cut's boundary is smooth (one capsule's arc: every wall the tool's
  side forms).  Memory: the probes (at most :data:`MAX_WALL_POINTS`) and their grid; time:
  linear in the samples.

Along the nominal section's machined boundary (not the stock's own outline), every
:data:`WALL_STEP_MM` (each point then moved onto the plan's exact sweep by the same probes,
:func:`_onto_sweep`), that signed distance is the wall error: positive where material is left,
negative where the tool overcut, clipped at :data:`WALL_WINDOW_MM` (no actual capsule within a
millimetre: at least that much material left).  Each wall point is credited to the program line
of the actual sample whose capsule is nearest it: the pass that formed that wall.

The sections are taken at :func:`wall_levels`: the middle of each band between the heights the
tool cut at (the floors of a 2.5-D part), so that each wall is read once per step-down.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np
import shapely
from numba import njit

from twin.machining.engagement import StockSpec
from twin.machining.part_map import PartMap, part_map
from twin.machining.sweep import ToolSweep
from twin.numba_cache import configure as configure_numba_cache

configure_numba_cache()  # before the first @njit(cache=True): see twin.numba_cache

#: The sections' circles are polygons within this of the true circle (mm): 1 µm (their wall points
#: are then moved onto the exact sweep).
CIRCLE_TOLERANCE_MM = 1e-3
#: The planned path is simplified within this (mm) before it is swept: 0.01 µm.
NOMINAL_SIMPLIFY_MM = 1e-5
#: Vertices of one simplified run swept at once: GEOS buffers a line that overlaps itself (a
#: helix's turns over one another) slowly, its short pieces fast, and unions them.
RUN_PIECE_VERTICES = 256
#: Spacing of the wall points along the nominal part's machined boundary (mm).
WALL_STEP_MM = 0.05
#: Wall points at most over all levels (the spacing grows past it: memory stays bounded).
MAX_WALL_POINTS = 200_000
#: Wall levels at most (a 3-D program cut at many heights gets this many, evenly spaced).
MAX_WALL_LEVELS = 16
#: A height the tool cut at counts as a floor with at least this many samples moving in XY.
MIN_FLOOR_SAMPLES = 10
#: Consecutive samples whose swept radius falls in one step of this (mm) are swept as one line,
#: at the run's smallest radius (the sample it joins included) rounded down to it: the section
#: lies within the exact sweep and only places the wall points, which are then moved onto it
#: (:func:`machined_part`).
SAME_RADIUS_MM = 1e-3
#: A nominal boundary point this near the stock's own outline (mm) is not machined.
ON_STOCK_MM = 1e-4
#: The wall error is resolved within this of the nominal wall (mm): a probe no actual capsule
#: comes this near reads it (material left, at least this much).
WALL_WINDOW_MM = 1.0
#: Samples of the actual path offered to the probes together, within a box this wide (mm).
CHUNK_SAMPLES = 256
CHUNK_MM = 0.2
#: Pieces of a segment along which the tool's radius at a level changes (a ramp, a plunge
#: reaching the level), each swept as the hull of its end discs.
RAMP_PIECES = 64
#: Even pieces of a section's sample pair whose radius changes (chords of the tool's concave
#: profile: inside the probes' :data:`RAMP_PIECES`).
SECTION_RAMP_PIECES = 4
#: Sample pairs whose hulls a section makes at once (their points: about 30 MB).
HULL_PAIRS = 2_000
#: Passes of a section's wall points onto the exact sweep at most, and the move (mm) under which
#: a point has arrived.
PROJECTIONS = 8
PROJECTED_MM = 1e-7
#: Cells of the probes' grid at most (4 million: 32 MB of cell starts).
MAX_BINS = 4_000_000
#: Runs of one radius a nominal section sweeps at most (about 5 s of GEOS buffering and union).
#: A tool that moves in Z through a level (a 3-D surface, a long ramp) sweeps a new radius at
#: every sample there: such a level is not sectioned, and its surface is in the height maps'
#: floor error instead (:mod:`twin.machining.part_map`).
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


def _swept(shapes: list, radius: float) -> shapely.Geometry:
    """The union of ``shapes`` (lines and points, mm) widened by ``radius`` (mm)."""
    # each piece apart, then their cascaded union: faster than a collection's buffer where the
    # pieces overlap (passes over one path at several depths)
    return shapely.union_all(shapely.buffer(np.array(shapes, dtype=object), radius, quad_segs=quad_segs(radius)))


def section(stock: shapely.Geometry, sweep: ToolSweep, z_mm: float) -> shapely.Geometry:
    """The material a smooth path (the plan; an actual path is probed, :func:`nearest_cuts`)
    leaves at height ``z_mm``: ``stock`` less the tool's sweep
    there, inside it by at most :func:`_section_slack_mm`: each run of samples at one radius (a
    step of :data:`SAME_RADIUS_MM`) a line simplified within :data:`NOMINAL_SIMPLIFY_MM` and
    widened by the run's smallest radius, each pair of samples between which the radius changes
    the hull of their discs (:func:`_disc_hulls`).

    Parameters
    ----------
    stock : shapely geometry
        The stock's outline less its islands (mm).
    sweep : ToolSweep
        The tool's axis in time order, its tip height, radius and corner radius at each sample (mm).
    z_mm : float

    Raises
    ------
    SectionTooComplex
        More than :data:`MAX_SECTION_RUNS` runs and pairs.
    """
    xy_mm = np.asarray(sweep.xy_mm, float)
    tool = (np.asarray(sweep.tip_mm), np.asarray(sweep.radius_mm), np.asarray(sweep.corner_mm))
    r = swept_radius_mm(*tool, z_mm)
    on = r > 0.0
    if len(r) == 1:
        return shapely.difference(stock, _swept([shapely.Point(xy_mm[0])], float(r[0]))) if on[0] else stock
    # a pair of consecutive samples is steady where the tool sweeps one radius (within a step of
    # SAME_RADIUS_MM) at both; else, where it reaches the level at either, the radius changes
    step = np.floor(r / SAME_RADIUS_MM)
    steady = on[:-1] & on[1:] & (step[:-1] == step[1:])
    changing = (on[:-1] | on[1:]) & ~steady
    edges = np.diff(np.concatenate([[0], steady.astype(int), [0]]))
    starts, ends = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)  # runs of steady pairs
    pieces = len(starts) + int(np.count_nonzero(changing))
    if pieces > MAX_SECTION_RUNS:
        raise SectionTooComplex(
            f"the tool sweeps {pieces} radii at Z {z_mm:g} mm (it moves in Z there), over {MAX_SECTION_RUNS}"
        )
    by_radius: dict[float, list] = {}
    for a, b in zip(starts, ends):  # pairs a..b-1: samples a..b, one line
        key = math.floor(float(r[a : b + 1].min()) / SAME_RADIUS_MM) * SAME_RADIUS_MM  # within the sweep
        line = shapely.simplify(shapely.LineString(xy_mm[a : b + 1]), NOMINAL_SIMPLIFY_MM, preserve_topology=False)
        coords = shapely.get_coordinates(line)
        by_radius.setdefault(key, []).extend(
            shapely.LineString(coords[i : i + RUN_PIECE_VERTICES + 1])
            for i in range(0, max(len(coords) - 1, 1), RUN_PIECE_VERTICES)
        )
    swept = [_swept(shapes, radius) for radius, shapes in by_radius.items()]
    pairs = np.flatnonzero(changing)
    for start in range(0, len(pairs), HULL_PAIRS):  # in blocks: memory stays bounded
        discs = _ramp_discs(xy_mm, *tool, pairs=pairs[start : start + HULL_PAIRS], z_mm=z_mm)
        swept.append(shapely.union_all(_disc_hulls(*discs)))
    return shapely.difference(stock, shapely.union_all(swept)) if swept else stock


def _ramp_discs(xy_mm, tip_mm, radius_mm, corner_mm, *, pairs: np.ndarray, z_mm: float) -> tuple[np.ndarray, ...]:
    """The discs a section sweeps between the samples of ``pairs`` (index k: samples k, k + 1)
    whose radius at ``z_mm`` changes: :data:`SECTION_RAMP_PIECES` even pieces each, a piece's end
    where the tool does not reach the level moved to where the tip crosses it (with the radius
    just over the tip): chords of the tool's concave profile, inside the sweep; the wall points
    are then moved onto it.  Returns the start discs' centres and radii and the end discs', (m,
    2), (m,), (m, 2), (m,).
    """
    t = np.linspace(0.0, 1.0, SECTION_RAMP_PIECES + 1)
    k = pairs[:, None]
    tips = tip_mm[k] + t * (tip_mm[k + 1] - tip_mm[k])  # (pairs, pieces + 1)
    centres = xy_mm[pairs][:, None, :] + t[None, :, None] * (xy_mm[pairs + 1] - xy_mm[pairs])[:, None, :]
    radii = swept_radius_mm(tips, radius_mm[k], corner_mm[k], z_mm)
    a_xy, a_r, b_xy, b_r = (part.copy() for part in (centres[:, :-1], radii[:, :-1], centres[:, 1:], radii[:, 1:]))
    enter, leave = (a_r <= 0.0) & (b_r > 0.0), (a_r > 0.0) & (b_r <= 0.0)
    with np.errstate(invalid="ignore", divide="ignore"):
        cross = (z_mm - tips[:, :-1]) / (tips[:, 1:] - tips[:, :-1])
    at = a_xy + cross[..., None] * (b_xy - a_xy)
    flat = np.broadcast_to((radius_mm - corner_mm)[k], a_r.shape)
    a_xy[enter], a_r[enter] = at[enter], flat[enter]
    b_xy[leave], b_r[leave] = at[leave], flat[leave]
    keep = (a_r > 0.0) | (b_r > 0.0)
    return a_xy[keep], a_r[keep], b_xy[keep], b_r[keep]


def _disc_hulls(a_xy: np.ndarray, a_r: np.ndarray, b_xy: np.ndarray, b_r: np.ndarray) -> np.ndarray:
    """The convex hull of each pair of discs (centres (m, 2), radii (m,), mm; a radius 0 is a
    point): polygons inside it within :data:`CIRCLE_TOLERANCE_MM`, drawn directly: the arc of disc a
    facing away from b between the outer tangents' points, then b's facing away from a (the
    tangents touch at angles ``+-acos((r_a - r_b) / h)`` from the direction a to b)."""
    # a disc holding the other stands for both
    h = np.hypot(*(b_xy - a_xy).T)
    a_holds, b_holds = h <= a_r - b_r, h <= b_r - a_r
    a_xy, a_r = np.where(b_holds[:, None], b_xy, a_xy), np.where(b_holds, b_r, a_r)
    b_xy, b_r = np.where(a_holds[:, None], a_xy, b_xy), np.where(a_holds, a_r, b_r)
    away = b_xy - a_xy
    h = np.hypot(*away.T)
    heading = np.arctan2(away[:, 1], away[:, 0])
    with np.errstate(invalid="ignore", divide="ignore"):
        touch = np.where(h > 0.0, np.arccos(np.clip((a_r - b_r) / h, -1.0, 1.0)), 0.5 * np.pi)
    k = 2 + 4 * quad_segs(float(max(a_r.max(), b_r.max())))  # points an arc: a whole circle's at most
    t = np.linspace(0.0, 1.0, k)
    on_a = (heading + touch)[:, None] + t * (2 * np.pi - 2 * touch)[:, None]
    on_b = (heading - touch)[:, None] + t * (2 * touch)[:, None]
    ring = np.concatenate(
        [
            a_xy[:, None, :] + a_r[:, None, None] * np.stack([np.cos(on_a), np.sin(on_a)], -1),
            b_xy[:, None, :] + b_r[:, None, None] * np.stack([np.cos(on_b), np.sin(on_b)], -1),
        ],
        axis=1,
    )
    return shapely.make_valid(shapely.polygons(ring))


def points_along(lines: shapely.Geometry, step_mm: float) -> np.ndarray:
    """Points every ``step_mm`` along each line of ``lines`` (a line, rings, a collection: mm),
    shape (m, 2); the points and polygons in it are left out."""
    out = []
    for line in shapely.get_parts(lines):
        if line.geom_type not in ("LineString", "LinearRing") or line.length == 0.0:
            continue
        xy = shapely.get_coordinates(line)
        along = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(xy, axis=0).T))])
        at = np.arange(0.0, along[-1], step_mm)
        out.append(np.column_stack([np.interp(at, along, xy[:, 0]), np.interp(at, along, xy[:, 1])]))
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


class Probes(NamedTuple):
    """Probe points and what :func:`nearest_cuts` finds for each, all in mm.

    Attributes
    ----------
    xy : ndarray (m, 2)
        The points.
    z : ndarray (m,)
        The height each is probed at.
    distance : ndarray (m,)
        The signed distance to the nearest swept capsule (positive outside every capsule, in
        the material), clipped at the window it was probed within.
    axis : ndarray (m, 2)
        That capsule's nearest axis point (NaN: none within the window).
    reach : ndarray (m,)
        That capsule's radius at ``z``.
    line : ndarray (m,) of int
        The program line of that capsule's sample (-1: none).
    """

    xy: np.ndarray
    z: np.ndarray
    distance: np.ndarray
    axis: np.ndarray
    reach: np.ndarray
    line: np.ndarray

    def surface(self) -> np.ndarray:
        """Each probe's nearest point of the cut's boundary (m, 2; NaN where none): the point of
        the nearest capsule's side on the line from its axis through the probe."""
        away = self.xy - self.axis
        norm = np.hypot(away[:, 0], away[:, 1])
        with np.errstate(invalid="ignore", divide="ignore"):
            return self.axis + away * (self.reach / norm)[:, None]


class _Bins(NamedTuple):
    """Probes bucketed on a square grid (mm): ``order[start[c]:start[c + 1]]`` are cell c's."""

    x0: float
    y0: float
    cell: float
    nx: int
    ny: int
    start: np.ndarray
    order: np.ndarray


def _bins(xy: np.ndarray, cell_mm: float) -> _Bins:
    """``xy`` (m, 2) bucketed in cells of ``cell_mm`` (larger where there would be over
    :data:`MAX_BINS` cells)."""
    span = np.ptp(xy, axis=0) + 3 * cell_mm
    cell_mm = max(cell_mm, math.sqrt(float(span[0] * span[1]) / MAX_BINS))
    x0, y0 = xy.min(axis=0) - cell_mm
    nx = int((xy[:, 0].max() - x0) / cell_mm) + 2
    ny = int((xy[:, 1].max() - y0) / cell_mm) + 2
    index = ((xy[:, 0] - x0) / cell_mm).astype(np.int64) * ny + ((xy[:, 1] - y0) / cell_mm).astype(np.int64)
    order = np.argsort(index, kind="stable")
    start = np.searchsorted(index[order], np.arange(nx * ny + 1))
    return _Bins(float(x0), float(y0), float(cell_mm), nx, ny, start, order)


@njit(cache=True)
def _radius_at(tip, radius, corner, z):  # pragma: no cover - compiled
    """:func:`swept_radius_mm` of one sample."""
    h = z - tip
    if h <= 0.0:
        return 0.0
    within = min(max(corner - h, 0.0), corner)
    return radius - corner + math.sqrt(max(corner * corner - within * within, 0.0))


@njit(cache=True)
def _keep(probes, m, d, qx, qy, r, line):  # pragma: no cover - compiled
    """Probe ``m`` keeps a capsule at signed distance ``d`` whose side nearest it is on the disc
    about (qx, qy) of radius ``r``, if it is the nearest yet."""
    if d < probes.distance[m]:
        probes.distance[m] = d
        probes.axis[m, 0], probes.axis[m, 1] = qx, qy
        probes.reach[m] = r
        probes.line[m] = line


@njit(cache=True)
def _offer(probes, m, a, b, line):  # pragma: no cover - compiled
    """Offer probe ``m`` the tool's sweep from disc ``a`` to disc ``b`` (each ``(x, y, radius)``,
    mm): the convex hull of the two discs (the radius changes along a ramp; a capsule where it
    does not), its signed distance as for a round cone (the end disc nearest, or the straight
    side, touched by the disc between them along the probe's normal)."""
    px, py = probes.xy[m, 0], probes.xy[m, 1]
    ax, ay, ra = a
    bx, by, rb = b
    h = math.hypot(bx - ax, by - ay)
    if h <= abs(ra - rb):  # one disc holds the other: the larger alone
        qx, qy, r = (ax, ay, ra) if ra >= rb else (bx, by, rb)
        _keep(probes, m, math.hypot(px - qx, py - qy) - r, qx, qy, r, line)
        return
    ux, uy = (bx - ax) / h, (by - ay) / h
    along = (px - ax) * ux + (py - ay) * uy
    across = abs((px - ax) * uy - (py - ay) * ux)
    slope = (ra - rb) / h  # the sides' tilt: sine of their angle to the axis
    cosine = math.sqrt(1.0 - slope * slope)
    k = -slope * across + cosine * along
    if k < 0.0:
        _keep(probes, m, math.hypot(px - ax, py - ay) - ra, ax, ay, ra, line)
    elif k > cosine * h:
        _keep(probes, m, math.hypot(px - bx, py - by) - rb, bx, by, rb, line)
    else:
        d = across * cosine + along * slope - ra
        r = across / cosine - d  # the disc touching the side where the probe's normal meets it
        t = along - d * slope - r * slope  # its centre along the axis
        _keep(probes, m, d, ax + t * ux, ay + t * uy, r, line)


@njit(cache=True)
def _ramp_disc(path, k, t, z):  # pragma: no cover - compiled
    """The tool's disc at height ``z`` a fraction ``t`` along from sample k - 1 to k (the tip
    linear between them): ``(x, y, radius)``, mm; where the tip is at z, the radius just over
    it (the flat part's: 0 for a ball, the full radius for a flat end mill)."""
    xy, tip, radius, corner = path.xy, path.tip, path.radius, path.corner
    at = tip[k - 1] + t * (tip[k] - tip[k - 1])
    r = radius[k] - corner[k] if at == z else _radius_at(at, radius[k], corner[k], z)
    return (xy[k - 1, 0] + t * (xy[k, 0] - xy[k - 1, 0]), xy[k - 1, 1] + t * (xy[k, 1] - xy[k - 1, 1]), r)


@njit(cache=True)
def _offer_ramp(probes, m, path, k, z, line):  # pragma: no cover - compiled
    """Offer probe ``m`` the sweep from sample k - 1 to k of a tool whose tip moves (its radius at
    height ``z`` changes along the segment): the part of the segment where the tool reaches z
    (from where the tip crosses it), in :data:`RAMP_PIECES` pieces spaced as the square of their
    index from the shallow end (a corner's radius grows as the square root of the depth there),
    each the hull of its end discs (:func:`_ramp_disc`)."""
    tip = path.tip
    h_a, h_b = z - tip[k - 1], z - tip[k]  # the depth of the level over the tip at each end
    if h_a <= 0.0 and h_b <= 0.0:
        return
    t0 = h_a / (h_a - h_b) if h_a <= 0.0 else 0.0  # where the tip crosses z
    t1 = h_a / (h_a - h_b) if h_b <= 0.0 else 1.0
    before = _ramp_disc(path, k, t0 if h_a < h_b else t1, z)  # from the shallow end
    for j in range(1, RAMP_PIECES + 1):
        s = (j / RAMP_PIECES) ** 2
        t = t0 + s * (t1 - t0) if h_a < h_b else t1 - s * (t1 - t0)
        here = _ramp_disc(path, k, t, z)
        _offer(probes, m, before, here, line)
        before = here


@njit(cache=True)
def _stream(probes, level_of, bins, levels, path, window):  # pragma: no cover - compiled
    """Every capsule of a path offered to the probes (:func:`nearest_cuts`): at each level, the
    capsule between consecutive samples of one radius there, :func:`_offer_ramp`'s pieces where
    the radius changes along the segment (the tool reaching the level included).

    The samples go in chunks of at most :data:`CHUNK_SAMPLES` within :data:`CHUNK_MM`: a probe
    whose distance to the chunk's box, less the chunk's widest radius at its level, is no nearer
    than what it holds skips the chunk's capsules (most probes, once a pass went by)."""
    xy, tip, radius, corner, line = path
    n, n_levels = xy.shape[0], len(levels)
    rad = np.zeros((CHUNK_SAMPLES + 1, n_levels))  # the chunk's radii, the sample before it first
    widest = np.zeros(n_levels)
    k0 = 0
    while k0 < n:
        x_lo, x_hi, y_lo, y_hi = (
            xy[max(k0 - 1, 0), 0],
            xy[max(k0 - 1, 0), 0],
            xy[max(k0 - 1, 0), 1],
            xy[max(k0 - 1, 0), 1],
        )
        k1 = k0
        while k1 < n and k1 - k0 < CHUNK_SAMPLES:
            x_lo, x_hi = min(x_lo, xy[k1, 0]), max(x_hi, xy[k1, 0])
            y_lo, y_hi = min(y_lo, xy[k1, 1]), max(y_hi, xy[k1, 1])
            k1 += 1
            if x_hi - x_lo > CHUNK_MM or y_hi - y_lo > CHUNK_MM:
                break
        for s in range(k0 - 1, k1):  # rad[0]: the sample before the chunk (none: nothing)
            for level in range(n_levels):
                rad[s - k0 + 1, level] = _radius_at(tip[s], radius[s], corner[s], levels[level]) if s >= 0 else 0.0
        reach = 0.0
        for level in range(n_levels):
            widest[level] = 0.0
            for s in range(k1 - k0 + 1):
                widest[level] = max(widest[level], rad[s, level])
            reach = max(reach, widest[level])
        if reach > 0.0:
            reach += window
            i0 = max(int((x_lo - reach - bins.x0) / bins.cell), 0)
            i1 = min(int((x_hi + reach - bins.x0) / bins.cell), bins.nx - 1)
            j0 = max(int((y_lo - reach - bins.y0) / bins.cell), 0)
            j1 = min(int((y_hi + reach - bins.y0) / bins.cell), bins.ny - 1)
            for i in range(i0, i1 + 1):
                for j in range(j0, j1 + 1):
                    c = i * bins.ny + j
                    for at in range(bins.start[c], bins.start[c + 1]):
                        m = bins.order[at]
                        level = level_of[m]
                        if widest[level] <= 0.0:
                            continue
                        px, py = probes.xy[m, 0], probes.xy[m, 1]
                        gap_x = max(x_lo - px, 0.0, px - x_hi)
                        gap_y = max(y_lo - py, 0.0, py - y_hi)
                        if math.hypot(gap_x, gap_y) - widest[level] >= probes.distance[m]:
                            continue
                        for s in range(1, k1 - k0 + 1):
                            k = k0 + s - 1
                            now, before = rad[s, level], rad[s - 1, level]
                            if now <= 0.0 and before <= 0.0:
                                continue
                            if s == 1 and k0 == 0:  # the path's first sample: its disc
                                _offer(probes, m, (xy[k, 0], xy[k, 1], now), (xy[k, 0], xy[k, 1], now), line[k])
                            elif now == before:
                                _offer(probes, m, (xy[k - 1, 0], xy[k - 1, 1], now), (xy[k, 0], xy[k, 1], now), line[k])
                            else:
                                _offer_ramp(probes, m, path, k, levels[level], line[k])
        k0 = k1


class _Path(NamedTuple):
    """A :class:`ToolSweep`'s arrays as the compiled stream reads them."""

    xy: np.ndarray
    tip: np.ndarray
    radius: np.ndarray
    corner: np.ndarray
    line: np.ndarray


def nearest_cuts(xy_mm: np.ndarray, z_mm: np.ndarray, sweep: ToolSweep, window_mm: float = WALL_WINDOW_MM) -> Probes:
    """Probe points against the capsules a path sweeps: for each point, the nearest capsule at
    its height within ``window_mm`` (:class:`Probes`), the path's samples streamed once.

    Parameters
    ----------
    xy_mm : ndarray (m, 2)
        The probe points (mm).
    z_mm : ndarray (m,)
        Their heights (mm): a few distinct values (the wall levels, at most
        :data:`MAX_WALL_LEVELS` and the inspected features').
    sweep : ToolSweep
        The path (its samples in time order).
    window_mm : float
        Capsules further than this from a probe are not looked at (mm).
    """
    m = len(xy_mm)
    probes = Probes(
        np.ascontiguousarray(xy_mm, float).reshape(m, 2),
        np.ascontiguousarray(z_mm, float).reshape(m),
        np.full(m, float(window_mm)),
        np.full((m, 2), np.nan),
        np.zeros(m),
        np.full(m, -1, np.int64),
    )
    if m == 0 or len(sweep.line) == 0:
        return probes
    levels, level_of = np.unique(probes.z, return_inverse=True)
    widest = float(sweep.radius_mm.max())
    path = _Path(
        np.ascontiguousarray(sweep.xy_mm, float),
        np.ascontiguousarray(sweep.tip_mm, float),
        np.ascontiguousarray(sweep.radius_mm, float),
        np.ascontiguousarray(sweep.corner_mm, float),
        np.ascontiguousarray(sweep.line, np.int64),
    )
    bins = _bins(probes.xy, max((widest + window_mm) / 2.0, 0.05))
    _stream(probes, level_of.astype(np.int64), bins, levels, path, float(window_mm))
    return probes


@dataclass
class MachinedPart:
    """The part the twin's actual motion cut, against the nominal one (:func:`machined_part`).

    Attributes
    ----------
    stock : shapely geometry
        The stock's outline less its islands (mm).
    nominal, actual : ToolSweep
        The planned and the measured tool paths.
    levels_mm : list of float
        The heights the walls were read at (:func:`wall_levels`).
    walls : ndarray (m, 5)
        Wall points: x, y, z (mm), signed error (µm: material left positive, overcut negative)
        and the program line that formed them.
    skipped_levels_mm : list of float
        Levels not read: the tool moves in Z through them (:class:`SectionTooComplex`).
    maps : PartMap or None
        The nominal and actual height maps (:mod:`twin.machining.part_map`), when computed.
    floor_error_um : dict
        Their error on the floors and 3-D surfaces (:meth:`PartMap.floor_error`).
    """

    stock: shapely.Geometry
    nominal: ToolSweep
    actual: ToolSweep
    levels_mm: list[float]
    walls: np.ndarray
    skipped_levels_mm: list[float] = field(default_factory=list)
    maps: PartMap | None = None
    floor_error_um: dict = field(default_factory=dict)

    def probe(self, xy_mm: np.ndarray, z_mm: float, window_mm: float = WALL_WINDOW_MM) -> Probes:
        """Points at height ``z_mm`` probed against the actual cut (:func:`nearest_cuts`)."""
        return nearest_cuts(xy_mm, np.full(len(xy_mm), z_mm), self.actual, window_mm)

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
        lines = self.walls[:, 4].astype(int)
        for line in np.unique(lines):
            err = self.walls[lines == line, 3]
            out[int(line)] = round(float(err[np.argmax(np.abs(err))]), 3)
        return out


def wall_points(stock, nominal: ToolSweep, levels_mm: list[float]) -> tuple[np.ndarray, list[float]]:
    """Points every :data:`WALL_STEP_MM` (more where there would be over
    :data:`MAX_WALL_POINTS`) along the nominal part's machined boundary at each of ``levels_mm``,
    shape (m, 3): x, y, z (mm); and the levels not read (:class:`SectionTooComplex`)."""
    outline = stock.boundary
    boundaries, skipped = {}, []
    for z in levels_mm:
        try:
            boundaries[z] = section(stock, nominal, z).boundary
        except SectionTooComplex:
            skipped.append(z)
    step = max(WALL_STEP_MM, sum(b.length for b in boundaries.values()) / MAX_WALL_POINTS)
    rows = []
    for z, boundary in boundaries.items():
        pts = points_along(boundary, step)
        pts = pts[shapely.distance(shapely.points(pts), outline) > ON_STOCK_MM] if len(pts) else pts
        rows.append(np.column_stack([pts, np.full(len(pts), z)]))
    return (np.concatenate(rows) if rows else np.zeros((0, 3))), skipped


def _section_slack_mm(sweep: ToolSweep, levels_mm: list[float]) -> float:
    """How far inside the exact sweep a section's boundary may lie (mm, :func:`section`): the
    largest change of the swept radius between two samples at any of ``levels_mm`` (a run is
    swept at its smallest), its rounding and the polygons' tolerance, with room; at most
    :data:`WALL_WINDOW_MM`."""
    step = 0.0
    for z in levels_mm:
        r = swept_radius_mm(sweep.tip_mm, sweep.radius_mm, sweep.corner_mm, z)
        both = (r[1:] > 0.0) & (r[:-1] > 0.0)
        step = max(step, float(np.abs(np.diff(r))[both].max(initial=0.0)))
    return min(step + 2 * SAME_RADIUS_MM + 10 * CIRCLE_TOLERANCE_MM, WALL_WINDOW_MM)


def _onto_sweep(points: np.ndarray, sweep: ToolSweep, slack_mm: float) -> None:
    """Move ``points`` (m, 3: x, y, z in mm; in place), which lie on a section's boundary within
    ``slack_mm`` inside the exact sweep, onto the sweep's boundary: each onto the side of the
    capsule it lies deepest in, again while that side lies in another (a ramp's pieces), at most
    :data:`PROJECTIONS` times; a point within :data:`PROJECTED_MM` of its last place stays."""
    active = np.arange(len(points))
    for _ in range(PROJECTIONS):
        if not len(active):
            return
        surface = nearest_cuts(points[active, :2], points[active, 2], sweep, slack_mm).surface()
        moved = np.isfinite(surface[:, 0])
        step = np.where(moved, np.hypot(*(surface - points[active, :2]).T), 0.0)
        points[active[moved], :2] = surface[moved]
        active = active[step > PROJECTED_MM]


def machined_part(stock, nominal: ToolSweep, actual: ToolSweep, *, top_mm: float, bottom_mm: float) -> MachinedPart:
    """The virtual part of a run: the walls of the nominal sweep's part (exact sections at
    :func:`wall_levels` of the nominal path) probed against the actual sweep's capsules."""
    step = np.diff(nominal.xy_mm, axis=0, prepend=nominal.xy_mm[:1])
    moving = np.hypot(step[:, 0], step[:, 1]) > 1e-6
    levels = wall_levels(nominal.tip_mm, moving, top_mm, bottom_mm)
    points, skipped = wall_points(stock, nominal, levels)
    _onto_sweep(points, nominal, _section_slack_mm(nominal, levels))
    found = nearest_cuts(points[:, :2], points[:, 2], actual)
    walls = np.column_stack([points, found.distance * 1e3, found.line]) if len(points) else np.zeros((0, 5))
    return MachinedPart(stock, nominal, actual, [z for z in levels if z not in skipped], walls, skipped)


def virtual_part(stock: StockSpec, nominal: ToolSweep, actual: ToolSweep) -> MachinedPart:
    """The part ``actual`` cut against the one ``nominal`` cuts: the walls
    (:func:`machined_part`) with both height maps (:func:`~twin.machining.part_map.part_map`)
    and their floor error."""
    part = machined_part(stock.polygon(), nominal, actual, top_mm=stock.top_mm, bottom_mm=stock.bottom_mm)
    part.maps = part_map(stock, nominal, actual)
    part.floor_error_um = part.maps.floor_error()
    return part


def part_cut_by_motion(
    stock: StockSpec,
    planned: ToolSweep,
    *,
    period_s: float,
    t_s: np.ndarray,
    table_xy_mm: np.ndarray,
    lines: np.ndarray,
) -> MachinedPart:
    """The part a run's actual motion cut (:func:`virtual_part`), against the nominal part of
    the program as far as the run went (a run stopped before the program's end, by its duration
    or a divergence, is compared with what the program had cut by then, not with material it
    never reached).

    Parameters
    ----------
    stock : StockSpec
    planned : ToolSweep
        The program's planned path through the stock, one sample every ``period_s`` (s)
        (:meth:`~twin.machining.sweep.ToolSweep.planned`).
    period_s : float
        The plan's sample period (s).
    t_s : ndarray (n,)
        The run's recorded times (s).
    table_xy_mm : ndarray (n, 2)
        The table's measured XY path at those times (mm): the tool's actual axis; its tip
        height and tool are those of the planned sample at each time.
    lines : ndarray (n,) of int
        The program line at each recorded time.
    """
    k = np.clip(np.rint(t_s / period_s).astype(int), 0, len(planned.line) - 1)
    reached = slice(0, int(k[-1]) + 1 if k.size else 0)
    nominal = ToolSweep(
        planned.xy_mm[reached],
        planned.tip_mm[reached],
        planned.radius_mm[reached],
        planned.corner_mm[reached],
        planned.line[reached],
    )
    actual = ToolSweep(table_xy_mm, nominal.tip_mm[k], nominal.radius_mm[k], nominal.corner_mm[k], lines)
    return virtual_part(stock, nominal, actual)
