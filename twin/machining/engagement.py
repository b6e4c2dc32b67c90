"""Virtual machining: a 2.5-D stock the part program cuts, so that the material decides the
cutting force.

The stock is an outline polygon (shapely) between ``bottom_mm`` and ``top_mm``, with optional
islands (openings through it), held as a height map (a Z-map) on a square grid of
``resolution_mm``.  Along the planned reference, sample by sample (every 1 ms), the edge at each
angle of the tool's leading half circle (immersion angles clockwise from the feed normal on the
left, as :func:`twin.machining.cutting.immersion_angles`) is read against the height map where it
will be a little further along the path (:data:`TEST_MARGIN_CELLS` outside the tool's surface
now, or where the tool stops if sooner): the engaged axial extent there is the material left
between the tip (or the stock's bottom) and the flute length, a flat tool in one reading, a ball
or bull-nose corner in :data:`CORNER_DISCS` discs.  The engaged arcs (up to two, their ends by
bisection) carry the mean extent over each; then the tool's surface is cut into the map.  This
is computed once along the nominal path (the table follows it within micrometres), and the
mechanistic force kernel reads it by time each physics step
(:class:`~twin.machining.program_cut.ProgramMilling`), with the spindle turning at the
programmed S between M3/M4 and M5.

Resolution (ours): 0.05 mm cells by default and 1 degree steps on the tool's circle (read every
:data:`COARSE_STEPS`, the steps between where readings differ); against closed forms and a
brute-force reference the arcs' ends agree within a degree and the depths within 1 % (tested).
"""

from __future__ import annotations

import math
from typing import Annotated, NamedTuple

import numpy as np
import shapely
from numba import njit
from pydantic import Field, PositiveFloat, model_validator

from twin.errors import TwinInputError
from twin.machining.cutting import MAX_FLUTES, MAX_HELIX_DEG, WorkMaterialSpec
from twin.machining.tool_dynamics import ToolDynamicsSpec
from twin.numba_cache import configure as configure_numba_cache
from twin.spec import MAX_MM, Millimetres, StrictSpec

configure_numba_cache()  # before the first @njit(cache=True): see twin.numba_cache

#: Points of a stock polygon at most.
MAX_POLYGON_POINTS = 100_000
#: Height-map cells at most: 4e7 float64 is 320 MB (a 300 x 300 mm stock at 0.05 mm).
MAX_CELLS = 40_000_000
#: Angular step of the engagement test on the tool's leading half circle (degrees).
ANGLE_STEP_DEG = 1.0
#: XY speed (m/s) over which the tool moves (a side cut, a feed direction).
MOVING_M_PER_S = 1e-6
#: A cutter's or shank's diameter at least (mm): the finest micro end mills made are 10 um.
MIN_TOOL_MM = 0.01
#: Material thinner than this above the tool tip (mm) is not cut (rounding of heights).
MIN_DEPTH_MM = 1e-6
#: Columns of the engagement table, per sample of the planned reference: two engaged arcs
#: (entry and exit, rad) each with the mean axial extent of the edge over it (mm), the largest
#: extent at any angle (mm), the tool's radius (mm), the material beside the tool above its
#: flute length (mm: the shank or holder rubs) and the material under the tool's tip where it
#: goes down (mm: a plunge or ramp into material), both before the sample's cut.
COLUMNS = (
    *("phi_st1", "phi_ex1", "depth1_mm", "phi_st2", "phi_ex2", "depth2_mm", "max_depth_mm", "radius_mm"),
    *("over_flutes_mm", "under_tip_mm"),
)
# the kernels' column indices, from the names (module constants: numba freezes them)
PHI_ST1, PHI_EX1, DEPTH1 = COLUMNS.index("phi_st1"), COLUMNS.index("phi_ex1"), COLUMNS.index("depth1_mm")
MAX_DEPTH, RADIUS = COLUMNS.index("max_depth_mm"), COLUMNS.index("radius_mm")
OVER_FLUTES, UNDER_TIP = COLUMNS.index("over_flutes_mm"), COLUMNS.index("under_tip_mm")
#: Columns from one engaged arc's to the next's (phi_st1 to phi_st2).
ARC_STRIDE = COLUMNS.index("phi_st2") - PHI_ST1


class Grid(NamedTuple):
    """A height map as the kernels read it: the heights (m, -inf where there is no material) on
    square cells of ``res_m`` from (``x0_m``, ``y0_m``), and the stock's top and bottom (m)."""

    heights: np.ndarray
    x0_m: float
    y0_m: float
    res_m: float
    top_m: float
    bottom_m: float


class ToolPath(NamedTuple):
    """What :func:`_along` walks (:func:`_path_arrays`): the tips (n, 3, m), the XY distance
    travelled to each (m), the feed direction held through stops, and the last sample of the
    motion each one belongs to."""

    pos: np.ndarray
    travelled: np.ndarray
    dir_x: np.ndarray
    dir_y: np.ndarray
    run_end: np.ndarray


class Pose(NamedTuple):
    """The tool at one sample: its :class:`ToolPath`, the sample and its tip height (m)."""

    path: ToolPath
    k: int
    cz: float


class Edge(NamedTuple):
    """The cutter at one sample: its radius, corner radius and flute length (m)."""

    radius_m: float
    corner_m: float
    flute_m: float


class Tools(NamedTuple):
    """The cutter at every sample (n, m): radius, corner radius, flute length and shank radius
    (0: the cutter's)."""

    radius_m: np.ndarray
    corner_m: np.ndarray
    flute_m: np.ndarray
    shank_m: np.ndarray


#: The map is cut this many cells beyond the tool's radius (half a cell's diagonal): a cell any
#: part of which the tool passes over is cut, so that a wall the tool left reads as cut at the
#: tool's own radius whichever way the cells fall.
CUT_MARGIN_CELLS = 0.71
#: A sample whose next one is straight below it within this many cells leaves its cut to it
#: (a plunge, the actual path's micrometre jitter included: 0.02 cells is 1 µm at 0.05 mm).
SAME_AXIS_CELLS = 0.02
#: Room around the stock in its height map (mm): off the map reads "no material" as well.
MAP_MARGIN_MM = 1.0
#: The engagement reads the map this many cells outside the tool's surface, just ahead of it
#: along the feed: beyond the cells the tool's own cut (with its margin) has reached.
TEST_MARGIN_CELLS = 1.5
#: Feed directions whose cosine is over this are one straight line (0.08 degrees).
STRAIGHT_COS = 1.0 - 1e-6
#: The leading half circle is read every this many angle steps; the steps between are read too
#: where the two readings differ (an edge of the material, a change of depth over
#: :data:`SMOOTH_EXTENT_M`), else filled in between them.  A feature narrower than the stride
#: (3 degrees: 0.16 mm on a 6 mm tool) between two like readings is missed.
COARSE_STEPS = 3
#: Extents (m) at two readings this close are filled in linearly between them.
SMOOTH_EXTENT_M = 1e-6
#: Axial discs over a ball or bull-nose tool's corner.
CORNER_DISCS = 16
#: Halvings of an interval where the engagement changes (an arc's end between two angle
#: steps, a corner's material between two discs): 1/64 of the step.
BISECTIONS = 6


class StockSpec(StrictSpec):
    """The ``[stock]`` table: a 2.5-D workpiece, machine coordinates (mm)."""

    outline_mm: list[tuple[Millimetres, Millimetres]] | None = Field(
        None, min_length=3, max_length=MAX_POLYGON_POINTS, description="outline polygon [[x, y], ...]"
    )
    corners_mm: tuple[tuple[Millimetres, Millimetres], tuple[Millimetres, Millimetres]] | None = Field(
        None, description="a rectangle [[x0, y0], [x1, y1]] instead of an outline"
    )
    top_mm: Millimetres = Field(description="top of the stock (Z, mm)")
    bottom_mm: Millimetres = Field(description="bottom of the stock (Z, mm)")
    islands_mm: list[
        Annotated[list[tuple[Millimetres, Millimetres]], Field(min_length=3, max_length=MAX_POLYGON_POINTS)]
    ] = Field(default_factory=list, max_length=1000, description="openings through the stock, each a polygon")
    resolution_mm: float = Field(0.05, ge=0.005, le=1.0, description="height-map cell (mm)")

    @model_validator(mode="after")
    def _shape(self):
        if (self.outline_mm is None) == (self.corners_mm is None):
            raise ValueError("give outline_mm or corners_mm")
        if not self.top_mm > self.bottom_mm:
            raise ValueError(f"top_mm = {self.top_mm} is not above bottom_mm = {self.bottom_mm}")
        return self

    def polygon(self) -> shapely.Polygon:
        """The stock's outline less its islands.

        Raises
        ------
        TwinInputError
            A self-intersecting or empty outline or island.
        """
        if self.corners_mm is not None:
            (x0, y0), (x1, y1) = self.corners_mm
            outline = shapely.box(min(x0, x1), min(y0, y1), max(x0, x1), max(y0, y1))
        else:
            outline = shapely.Polygon(self.outline_mm)
        for field, shape in (
            ("stock.outline_mm", outline),
            *((f"stock.islands_mm.{i}", shapely.Polygon(p)) for i, p in enumerate(self.islands_mm)),
        ):
            if not shape.is_valid:
                raise TwinInputError(field, shapely.get_coordinates(shape).tolist(), shapely.is_valid_reason(shape))
            if shape.is_empty or shape.area <= 0:
                raise TwinInputError(field, shapely.get_coordinates(shape).tolist(), "encloses no area")
        for island in self.islands_mm:
            outline = outline.difference(shapely.Polygon(island))
        if outline.is_empty or outline.area <= 0:
            raise TwinInputError("stock.islands_mm", f"{len(self.islands_mm)} island(s)", "leave no material")
        return outline


class ToolSpec(WorkMaterialSpec):
    """A cutter: the ``[tool]`` table, or an entry of ``[[tools]]`` with its ``number``."""

    number: int | None = Field(None, ge=0, description="T number ([[tools]] only)")
    diameter_mm: float = Field(ge=MIN_TOOL_MM, le=MAX_MM, description="cutter diameter (mm)")
    n_flutes: int = Field(ge=1, le=MAX_FLUTES, description="teeth")
    corner_radius_mm: float = Field(
        0.0, ge=0.0, le=MAX_MM, description="corner radius (mm): 0 a flat end mill, half the diameter a ball end mill"
    )
    flute_length_mm: PositiveFloat | None = Field(
        None,
        le=MAX_MM,
        description="length of the cutting edge from the tip (mm); material above it is not cut by the flutes",
    )
    shank_diameter_mm: float | None = Field(
        None,
        ge=MIN_TOOL_MM,
        le=MAX_MM,
        description="diameter of the shank above the flutes (mm; default the cutter's): material within it above "
        "the flute length rubs",
    )
    max_ramp_deg: float = Field(
        90.0, ge=0.0, le=90.0, description="steepest descent into material (deg): 90 plunges (centre cutting), 0 none"
    )
    feed_per_tooth_mm: tuple[PositiveFloat, PositiveFloat] | None = Field(
        None, description="the tool maker's feed per tooth range [min, max] (mm); outside it is a warning"
    )
    helix_deg: float = Field(
        0.0, ge=0.0, lt=MAX_HELIX_DEG, description="helix angle of the flutes (deg); 0: straight flutes"
    )
    dynamics: ToolDynamicsSpec | None = Field(
        None, description="the structure at the tool tip: modes in X/Y or a measured FRF (twin.machining.tool_dynamics)"
    )

    @model_validator(mode="after")
    def _corner(self):
        if self.feed_per_tooth_mm is not None and self.feed_per_tooth_mm[0] > self.feed_per_tooth_mm[1]:
            raise ValueError(f"feed_per_tooth_mm = {list(self.feed_per_tooth_mm)}: give [min, max]")
        if self.corner_radius_mm > self.diameter_mm / 2:
            raise ValueError(
                f"corner_radius_mm = {self.corner_radius_mm} is over half the diameter ({self.diameter_mm / 2}: a ball)"
            )
        return self


class HeightMap:
    """The stock as heights (m) on a grid of square cells: -inf where there is no material.

    Parameters
    ----------
    stock : StockSpec
    margin_mm : float
        Room around the stock (mm), so that a tool beside it reads "no material".
    """

    def __init__(self, stock: StockSpec, margin_mm: float):
        poly = stock.polygon()
        self.stock_polygon = poly
        res = stock.resolution_mm
        x0, y0, x1, y1 = poly.bounds
        x0, y0, x1, y1 = x0 - margin_mm, y0 - margin_mm, x1 + margin_mm, y1 + margin_mm
        nx, ny = math.ceil((x1 - x0) / res), math.ceil((y1 - y0) / res)
        if nx * ny > MAX_CELLS:
            raise TwinInputError(
                "stock.resolution_mm", res, f"the stock needs {nx * ny:.3g} cells at it, over {MAX_CELLS:.0e}: coarser"
            )
        xs = x0 + (np.arange(nx) + 0.5) * res
        ys = y0 + (np.arange(ny) + 0.5) * res
        self.heights = np.full((nx, ny), -np.inf)
        shapely.prepare(poly)
        rows = max(1, 1_000_000 // ny)  # a million cells at a time: memory stays small
        for i in range(0, nx, rows):
            gx, gy = np.meshgrid(xs[i : i + rows], ys, indexing="ij")
            self.heights[i : i + rows][shapely.contains_xy(poly, gx, gy)] = stock.top_mm * 1e-3
        self.x0_m, self.y0_m, self.res_m = x0 * 1e-3, y0 * 1e-3, res * 1e-3
        self.top_m, self.bottom_m = stock.top_mm * 1e-3, stock.bottom_mm * 1e-3

    def grid(self) -> Grid:
        """The map as the kernels read it (its heights shared, not copied)."""
        return Grid(self.heights, self.x0_m, self.y0_m, self.res_m, self.top_m, self.bottom_m)

    def centres_mm(self) -> tuple[np.ndarray, np.ndarray]:
        """The cells' centres along X and along Y (mm)."""
        nx, ny = self.heights.shape
        return (
            (self.x0_m + (np.arange(nx) + 0.5) * self.res_m) * 1e3,
            (self.y0_m + (np.arange(ny) + 0.5) * self.res_m) * 1e3,
        )

    def outlines(self) -> dict[str, list[np.ndarray]]:
        """The stock's outline and the outline of the material left at its full height (the
        part's top as machined), each a list of closed polylines (n, 2) in mm."""
        import contourpy

        stock = [np.asarray(self.stock_polygon.exterior.coords)] + [
            np.asarray(ring.coords) for ring in self.stock_polygon.interiors
        ]
        xs, ys = self.centres_mm()
        z = np.where(np.isfinite(self.heights), self.heights, self.bottom_m - 1.0).T
        lines = contourpy.contour_generator(xs, ys, z).lines(self.top_m - 1e-6)
        return {"stock": stock, "machined": [np.asarray(line) for line in lines]}


@njit(cache=True)
def _height_at(grid, x, y):  # pragma: no cover - compiled
    """The height (m) in the cell holding the point (x, y) (m) of ``grid`` (a :class:`Grid`); -inf
    off the map."""
    heights, x0, y0, res = grid.heights, grid.x0_m, grid.y0_m, grid.res_m
    i = math.floor((x - x0) / res)
    j = math.floor((y - y0) / res)
    if 0 <= i < heights.shape[0] and 0 <= j < heights.shape[1]:
        return heights[i, j]
    return -np.inf


@njit(cache=True)
def _ahead(rho, sin_phi, margin):  # pragma: no cover - compiled
    """How far ahead along the feed (m) the test point on the circle of radius ``rho`` at angle
    phi is moved so that it lies ``margin`` outside that circle: ``e`` with
    ``rho^2 + 2 rho e sin(phi) + e^2 = (rho + margin)^2``."""
    b = rho * sin_phi
    return -b + math.sqrt(b * b + 2.0 * rho * margin + margin * margin)


@njit(cache=True)
def _along(path, k, distance):  # pragma: no cover - compiled
    """The tool's tip (x, y, z, m) and feed direction ``distance`` (m) along the path in XY from
    sample ``k`` (linear between samples), on the :class:`ToolPath` ``path``.  Past the place
    where the tool next stops, when it comes to the stop straight (its feed direction at k and
    there within :data:`STRAIGHT_COS`), the point goes on straight at the stop's height: the
    material ahead of a tool that stops is still there up to the stop; else it is the stop.
    Last, how far (m) the point went on past the stop (0 short of it or at it)."""
    pos, travelled, dir_x, dir_y, run_end = path.pos, path.travelled, path.dir_x, path.dir_y, path.run_end
    goal = travelled[k] + distance
    end = run_end[k]
    if travelled[end] <= goal:
        # straight on past the stop where the tool comes to it straight (a slot's end); a curve's
        # tangent would leave the material it cut, so there the read stays at the stop
        beyond = goal - travelled[end]
        # the sample as far before the stop as the read goes past it: the path straight from it
        lo, hi = 0, end
        while hi - lo > 1:
            mid = (lo + hi) // 2
            if travelled[end] - travelled[mid] >= beyond:
                lo = mid
            else:
                hi = mid
        for j in (k, lo):
            if dir_x[j] * dir_x[end] + dir_y[j] * dir_y[end] <= STRAIGHT_COS:
                beyond = 0.0
        x, y = pos[end, 0] + beyond * dir_x[end], pos[end, 1] + beyond * dir_y[end]
        return x, y, pos[end, 2], dir_x[end], dir_y[end], beyond
    lo, step = k, 1
    hi = min(k + step, end)
    while travelled[hi] <= goal:  # galloping: the place is a few samples on, as a rule
        lo = hi
        step *= 2
        hi = min(k + step, end)
    while hi - lo > 1:  # travelled[lo] <= goal < travelled[hi]
        mid = (lo + hi) // 2
        if travelled[mid] <= goal:
            lo = mid
        else:
            hi = mid
    w = (goal - travelled[lo]) / (travelled[hi] - travelled[lo])
    x = pos[lo, 0] + w * (pos[hi, 0] - pos[lo, 0])
    y = pos[lo, 1] + w * (pos[hi, 1] - pos[lo, 1])
    z = pos[lo, 2] + w * (pos[hi, 2] - pos[lo, 2])
    return x, y, z, dir_x[lo], dir_y[lo], 0.0


@njit(cache=True)
def _path_arrays(pos, vel):  # pragma: no cover - compiled
    """What :func:`_along` walks: the XY distance travelled to each sample (m), the unit feed
    direction (held through stops, +x before the first motion) and the last sample of each
    motion (a run of samples moving in XY; a sample at rest is its own)."""
    n = pos.shape[0]
    travelled = np.zeros(n)
    dir_x, dir_y = np.ones(n), np.zeros(n)
    run_end = np.arange(n)
    ux, uy = 1.0, 0.0
    for k in range(n):
        if k > 0:
            travelled[k] = travelled[k - 1] + math.hypot(pos[k, 0] - pos[k - 1, 0], pos[k, 1] - pos[k - 1, 1])
        speed = math.hypot(vel[k, 0], vel[k, 1])
        if speed > MOVING_M_PER_S:
            ux, uy = vel[k, 0] / speed, vel[k, 1] / speed
        dir_x[k], dir_y[k] = ux, uy
    for k in range(n - 2, -1, -1):
        if math.hypot(vel[k + 1, 0], vel[k + 1, 1]) > MOVING_M_PER_S:
            run_end[k] = run_end[k + 1]
    return travelled, dir_x, dir_y, run_end


@njit(cache=True)
def _corner_has_material(u, ahead, tool, sp, cp, cz, grid):  # pragma: no cover - compiled
    """Whether there is material at the corner's surface a fraction ``u`` of its height up, at
    the angle of sine ``sp`` and cosine ``cp`` of the tool at ``ahead`` (x, y, ux, uy)."""
    fx, fy, ux, uy = ahead
    r, rc = tool.radius_m, tool.corner_m
    rho = r - rc + math.sqrt(max(rc * rc - (rc - u * rc) ** 2, 0.0))
    nx_, ny_ = sp * ux - cp * uy, sp * uy + cp * ux
    return _height_at(grid, fx + rho * nx_, fy + rho * ny_) > cz + u * rc


@njit(cache=True)
def _extent_at(phi, pose, tool, grid):  # pragma: no cover - compiled
    """The engaged axial extent (m) of the edge at angle ``phi`` and the material above the flute
    length there (m): the material at the edge's place a little further along the path (where
    that place lies :data:`TEST_MARGIN_CELLS` outside the tool's surface now, straight on past
    a stop; where the tool moves in Z, carried back to the edge now along the material's slope
    from a second read twice as far), between the tool's tip now, the stock's bottom and the
    flute length; the material above the flutes from the tip now, at the stop
    rather than past it.  The cylinder
    takes one reading; a corner (ball or bull nose) :data:`CORNER_DISCS` discs, each change
    between two discs found by bisection.  ``pose`` is a :class:`Pose`, ``tool`` an :class:`Edge`,
    ``grid`` a :class:`Grid`."""
    path, k, tip = pose.path, pose.k, pose.cz
    r, rc, flute = tool.radius_m, tool.corner_m, tool.flute_m
    top, bottom = grid.top_m, grid.bottom_m
    margin = TEST_MARGIN_CELLS * grid.res_m
    sp, cp = math.sin(phi), math.cos(phi)
    # the corner's discs are nearer the axis: at the cylinder's distance ahead they are as far
    # outside the tool now, or further
    distance = _ahead(r, sp, margin)
    fx, fy, cz, ux, uy, beyond = _along(path, k, distance)
    ahead = (fx, fy, ux, uy)
    nx_, ny_ = sp * ux - cp * uy, sp * uy + cp * ux  # the edge's direction at phi there
    h = _height_at(grid, fx + r * nx_, fy + r * ny_)
    if cz != tip and h > -np.inf:
        # the tool moves in Z (a helix, a ramp): the material read ahead is where the edge will
        # be; back at the edge now it is as far again the other way as a second read, twice as
        # far, says it slopes (a helix's last turn: as the tip; flat stock: not at all), by no
        # more than the tip's own change over the distance
        gx, gy, _, gux, guy, _ = _along(path, k, 2.0 * distance)
        further = _height_at(grid, gx + r * (sp * gux - cp * guy), gy + r * (sp * guy + cp * gux))
        change = abs(tip - cz)
        h += min(max(h - further, -change), change)
    total = max(min(h, top, tip + flute) - max(tip + rc, bottom), 0.0)
    # the material above the flutes is the shank's, which is where it is now: from the tip now
    # (a slot's end blending into a plunge reads a lower tip ahead), and none past a stop: what
    # the read past it stands for is the sliver in front of the edge, thinner than a cell as the
    # tool comes to the stop (going down into a plunge, it stood 0.028 mm over 2 mm flutes)
    if beyond > 0.0:
        h = _height_at(grid, fx - beyond * ux + r * nx_, fy - beyond * uy + r * ny_)
    over = max(min(h, top) - max(tip + flute, bottom), 0.0)
    if rc > 0.0:
        # the corner's height fractions that count: above the stock's bottom, under the flutes
        u_lo = min(max((bottom - cz) / rc, 0.0), 1.0)
        u_hi = min(max(flute / rc, 0.0), 1.0)
        if u_hi > u_lo:
            n = CORNER_DISCS
            du = (u_hi - u_lo) / n
            prev = _corner_has_material(u_lo + 0.5 * du, ahead, tool, sp, cp, cz, grid)
            start = u_lo  # where the current run of material (if any) began
            for disc in range(1, n + 1):
                if disc < n:
                    u = u_lo + (disc + 0.5) * du
                    now = _corner_has_material(u, ahead, tool, sp, cp, cz, grid)
                else:
                    now = not prev  # the corner's top closes a run
                if now == prev:
                    continue
                if disc < n:
                    a, b = u - du, u  # bisect between the two discs' centres
                    for _ in range(BISECTIONS):
                        m = 0.5 * (a + b)
                        if _corner_has_material(m, ahead, tool, sp, cp, cz, grid) == prev:
                            a = m
                        else:
                            b = m
                    edge = 0.5 * (a + b)
                else:
                    edge = u_hi
                if prev:
                    total += (edge - start) * rc
                else:
                    start = edge
                prev = now
    if total <= MIN_DEPTH_MM * 1e-3:
        total = 0.0  # rounding of heights: no material
    return total, over


@njit(cache=True)
def _edge_angle(lo, hi, engaged_at_lo, pose, tool, grid):  # pragma: no cover - compiled
    """The angle (rad) between ``lo`` and ``hi`` where the engagement changes, by bisection."""
    for _ in range(BISECTIONS):
        m = 0.5 * (lo + hi)
        if (_extent_at(m, pose, tool, grid)[0] > 0.0) == engaged_at_lo:
            lo = m
        else:
            hi = m
    return 0.5 * (lo + hi)


@njit(cache=True)
def _side_engagement(pose, tool, grid, n_steps, step, extent, row):  # pragma: no cover - compiled
    """One sample's engagement into ``row`` (:data:`COLUMNS`): the extent at each angle step of
    the leading half circle (into ``extent``), the engaged arcs (up to two) with their ends found
    by bisection and the mean extent over each (mm), the largest extent (mm) and the largest
    material above the flute length (mm)."""
    last = n_steps - 1
    extent[0], over = _extent_at(0.0, pose, tool, grid)
    for lo in range(0, last, COARSE_STEPS):
        hi = min(lo + COARSE_STEPS, last)
        extent[hi], over_hi = _extent_at(hi * step, pose, tool, grid)
        over = max(over, over_hi)
        a, b = extent[lo], extent[hi]
        if (a > 0.0) == (b > 0.0) and abs(b - a) <= SMOOTH_EXTENT_M:
            for s in range(lo + 1, hi):  # alike at both ends: the steps between filled in
                extent[s] = a + (b - a) * (s - lo) / (hi - lo)
        else:
            for s in range(lo + 1, hi):
                extent[s], over_s = _extent_at(s * step, pose, tool, grid)
                over = max(over, over_s)
    largest = 0.0
    for s in range(n_steps):
        largest = max(largest, extent[s])
    row[MAX_DEPTH] = largest * 1e3
    row[OVER_FLUTES] = over * 1e3
    runs = 0
    start = 0
    for s in range(n_steps + 1):
        engaged = s < n_steps and extent[s] > 0.0
        was = s > 0 and extent[s - 1] > 0.0
        if engaged and not was:
            start = s
        elif was and not engaged:
            if runs < 2:
                total = 0.0
                for q in range(start, s):
                    total += extent[q]
                entry = 0.0
                if start > 0:
                    entry = _edge_angle((start - 1) * step, start * step, False, pose, tool, grid)
                leave = (n_steps - 1) * step
                if s < n_steps:
                    leave = _edge_angle((s - 1) * step, s * step, True, pose, tool, grid)
                row[PHI_ST1 + ARC_STRIDE * runs] = entry
                row[PHI_EX1 + ARC_STRIDE * runs] = leave
                row[DEPTH1 + ARC_STRIDE * runs] = total / (s - start) * 1e3
            runs += 1


@njit(cache=True)
def _disc_rows(y0, res, ny, cy, reach):  # pragma: no cover - compiled
    """The rows ``range(lo, hi)`` of a map (origin ``y0``, cells of ``res``, ``ny`` rows, m) a
    disc of radius ``reach`` about ``cy`` may hold cell centres of."""
    return max(int((cy - reach - y0) / res), 0), min(int((cy + reach - y0) / res) + 1, ny)


@njit(cache=True)
def _disc_columns(x0, res, nx, cx, dy, reach):  # pragma: no cover - compiled
    """The columns ``a..b`` (inclusive; ``a > b``: none) of the cells on a row ``dy`` (m) from
    a disc's centre ``cx`` whose centres lie within ``reach`` of it."""
    if abs(dy) > reach:
        return 1, 0
    w = math.sqrt(reach * reach - dy * dy)
    return max(math.ceil((cx - w - x0) / res - 0.5), 0), min(math.floor((cx + w - x0) / res - 0.5), nx - 1)


@njit(cache=True)
def _lower_row(grid, j, i_lo, i_hi, cx, cy, cz, r, rc):  # pragma: no cover - compiled
    """Lower row ``j``'s cells ``i_lo..i_hi`` of ``grid`` to the tool's bottom at (cx, cy) with
    tip cz (m): flat inside ``r - rc``, the corner's arc outside it, the corner's top beyond r."""
    heights, x0, y0, res = grid.heights, grid.x0_m, grid.y0_m, grid.res_m
    dy = y0 + (j + 0.5) * res - cy
    for i in range(i_lo, i_hi + 1):
        if heights[i, j] <= cz:  # no lower than the tip already: nothing to cut
            continue
        floor = cz
        if rc > 0.0:
            dx = x0 + (i + 0.5) * res - cx
            rho = math.sqrt(dx * dx + dy * dy)
            out = min(max(rho - (r - rc), 0.0), rc)
            floor = cz + rc - math.sqrt(rc * rc - out * out)
        if heights[i, j] > floor:
            heights[i, j] = floor


@njit(cache=True)
def _nearer_columns(x0, res, yc, a, b, cx, cy, px, py):  # pragma: no cover - compiled
    """Columns ``a..b`` of a row at ``yc`` (m) narrowed to the cells whose centres lie nearer
    (cx, cy) than (px, py), one cell to spare each way: ``|c - p_new|^2 < |c - p_old|^2`` is
    ``2 x (px - cx) < |p|^2 - |c|^2 - 2 yc (py - cy)`` along the row."""
    d = 2.0 * (px - cx)
    k = (px * px + py * py) - (cx * cx + cy * cy) - 2.0 * yc * (py - cy)
    if d == 0.0:
        return (a, b) if k > 0.0 else (1, 0)
    edge = (k / d - x0) / res - 0.5  # the bisector's column
    if d > 0.0:
        return a, min(b, math.floor(edge) + 1)
    return max(a, math.ceil(edge) - 1), b


@njit(cache=True)
def _cut(grid, margin, cx, cy, cz, r, rc, crescent, px, py, pr, lead=False):  # pragma: no cover - compiled
    """Lower ``grid``'s heights to the tool's surface at (cx, cy) with tip cz (m): every cell whose
    centre lies within the tool's radius and ``margin`` cells (the engagement's
    :data:`CUT_MARGIN_CELLS`) goes down to the tool's bottom there (:func:`_lower_row`).  With
    ``crescent`` (a flat tool at the height of its last cut, at (px, py) with radius pr) only the
    cells the disc newly covers on each row are visited: O(r) a sample, not O(r^2).  With
    ``lead`` (a ball or bull-nose tool of the same size at the height of its last cut, at
    (px, py)) only the cells nearer (cx, cy) than (px, py): the tool's bottom rises with the
    distance from its axis, so elsewhere the last cut went as deep (half the disc)."""
    x0, y0, res = grid.x0_m, grid.y0_m, grid.res_m
    nx, ny = grid.heights.shape
    reach = r + margin * res
    j_lo, j_hi = _disc_rows(y0, res, ny, cy, reach)
    for j in range(j_lo, j_hi):
        yc = y0 + (j + 0.5) * res
        a, b = _disc_columns(x0, res, nx, cx, yc - cy, reach)
        if lead:  # a corner tool at its last cut's height: only cells nearer the new centre
            a, b = _nearer_columns(x0, res, yc, a, b, cx, cy, px, py)
        if not crescent:
            _lower_row(grid, j, a, b, cx, cy, cz, r, rc)
            continue
        old_a, old_b = _disc_columns(x0, res, nx, px, yc - py, pr + margin * res)
        if old_a > old_b:  # the old disc is not on this row
            _lower_row(grid, j, a, b, cx, cy, cz, r, rc)
            continue
        _lower_row(grid, j, a, min(b, old_a - 1), cx, cy, cz, r, rc)
        _lower_row(grid, j, max(a, old_b + 1), b, cx, cy, cz, r, rc)


@njit(cache=True)
def _covered_by_next(grid, pos, radius, corner, k):  # pragma: no cover - compiled
    """Whether sample k + 1 is the same tool straight below sample ``k`` (within
    :data:`SAME_AXIS_CELLS`): its cut then covers k's, which is left to it (a plunge cuts the
    tool's disc once, at its bottom, not at every sample on the way down)."""
    if k + 1 >= pos.shape[0] or radius[k + 1] != radius[k] or corner[k + 1] != corner[k]:
        return False
    moved = math.hypot(pos[k + 1, 0] - pos[k, 0], pos[k + 1, 1] - pos[k, 1])
    # lower by more than the crescent's allowance: the next sample cuts its whole disc
    return pos[k + 1, 2] < pos[k, 2] - 1e-12 and moved <= SAME_AXIS_CELLS * grid.res_m


@njit(cache=True)
def _cut_sample(grid, margin, pos, radius, corner, k):  # pragma: no cover - compiled
    """:func:`_cut` for sample ``k`` of tips ``pos`` (n, 3, m) with tools ``radius``, ``corner``
    (n, m): a flat tool no lower than at sample k - 1 and of its radius cuts only the crescent
    that sample's disc left, a ball or bull-nose tool at its height only the half nearer it."""
    cx, cy, cz, r, rc = pos[k, 0], pos[k, 1], pos[k, 2], radius[k], corner[k]
    crescent = k > 0 and rc == 0.0 and cz >= pos[k - 1, 2] - 1e-12 and r == radius[k - 1]
    lead = k > 0 and rc > 0.0 and cz == pos[k - 1, 2] and r == radius[k - 1] and rc == corner[k - 1]
    px, py = (pos[k - 1, 0], pos[k - 1, 1]) if k > 0 else (cx, cy)
    _cut(grid, margin, cx, cy, cz, r, rc, crescent, px, py, radius[k - 1] if k > 0 else r, lead)


@njit(cache=True, nogil=True)
def cut_path(grid, pos, radius, corner):  # pragma: no cover - compiled
    """Cut ``grid``'s heights (a :class:`Grid`) along tool tips ``pos`` (n, 3, m)
    with tool radius and corner radius ``radius``, ``corner`` (n, m): each cell whose centre
    the tool's surface passes over goes down to it (no margin: the part as it is)."""
    for k in range(pos.shape[0]):
        if not _covered_by_next(grid, pos, radius, corner, k):
            _cut_sample(grid, 0.0, pos, radius, corner, k)


@njit(cache=True)
def _highest_in_disc(grid, cx, cy, r):  # pragma: no cover - compiled
    """The highest material (m) of the cells of ``grid`` whose centres lie within ``r`` (m) of
    (cx, cy); -inf if none."""
    heights, x0, y0, res = grid.heights, grid.x0_m, grid.y0_m, grid.res_m
    nx, ny = heights.shape
    best = -np.inf
    j_lo, j_hi = _disc_rows(y0, res, ny, cy, r)
    for j in range(j_lo, j_hi):
        a, b = _disc_columns(x0, res, nx, cx, y0 + (j + 0.5) * res - cy, r)
        for i in range(a, b + 1):
            best = max(best, heights[i, j])
    return best


@njit(cache=True)
def _engage(pos, vel, tools, grid, step, out):  # pragma: no cover - compiled
    """The engagement table ``out`` (n, :data:`COLUMNS`, angles in rad, lengths in mm) along
    tool tips ``pos`` (n, 3, m) moving at ``vel`` (n, 3) with the cutters ``tools`` (a
    :class:`Tools`), the spindle turning or not, every angle ``step`` (rad); cuts ``grid``'s
    heights as it goes: each sample is read before the tool's surface there is cut."""
    radius, corner, flute, shank = tools.radius_m, tools.corner_m, tools.flute_m, tools.shank_m
    top, bottom = grid.top_m, grid.bottom_m
    n = pos.shape[0]
    n_steps = round(math.pi / step) + 1
    extent = np.zeros(n_steps)
    travelled, dir_x, dir_y, run_end = _path_arrays(pos, vel)
    path = ToolPath(pos, travelled, dir_x, dir_y, run_end)
    under = 0.0  # the depth (m) the tip has gone down into material, to the last sample
    for k in range(n):
        cx, cy, cz, r, rc = pos[k, 0], pos[k, 1], pos[k, 2], radius[k], corner[k]
        for c in range(out.shape[1]):
            out[k, c] = 0.0
        out[k, RADIUS] = r * 1e3
        if cz >= top:
            under = 0.0
            continue
        if vel[k, 2] < 0.0:  # going down: the material under the tip, before this cut
            fresh = min(_height_at(grid, cx, cy), top) - max(cz, bottom)
            # straight down, the cell under the axis was cut to the last tip: the depth gone into
            # the material adds up; moving sideways, each new cell gives the depth itself
            if fresh > 0.0:
                out[k, UNDER_TIP] = max(fresh, under + (pos[k - 1, 2] - cz) if under > 0.0 else 0.0) * 1e3
        under = out[k, UNDER_TIP] * 1e-3
        # side milling: the tool must move in XY (a plunge's bottom cutting is not modelled,
        # though it removes the material under the tool)
        if math.hypot(vel[k, 0], vel[k, 1]) > MOVING_M_PER_S:
            _side_engagement(Pose(path, k, cz), Edge(r, rc, flute[k]), grid, n_steps, step, extent, out[k])
        if shank[k] > 0.0 and cz + flute[k] < top:  # a shank of its own: the material within it
            highest = _highest_in_disc(grid, cx, cy, shank[k])
            out[k, OVER_FLUTES] = max(out[k, OVER_FLUTES], (highest - cz - flute[k]) * 1e3)
        # a plunge's disc is cut at its bottom, unless the next sample reads the map sideways
        if not (
            _covered_by_next(grid, pos, radius, corner, k)
            and math.hypot(vel[k + 1, 0], vel[k + 1, 1]) <= MOVING_M_PER_S
        ):
            _cut_sample(grid, CUT_MARGIN_CELLS, pos, radius, corner, k)


def engagement_table(
    position_m, velocity_m_per_s, *, radius_m, height_map: HeightMap, corner_m=None, flute_m=None, shank_m=None
) -> np.ndarray:
    """The engagement along a planned path (see the module docstring), shape (n, 10):
    :data:`COLUMNS`, angles in rad, lengths in mm.  Cuts ``height_map`` as it goes, whether the
    spindle turns or not (a tool that does not turn still goes where the program moves it).

    Parameters
    ----------
    position_m, velocity_m_per_s : ndarray (n, 3)
        The tool tip's path and velocity relative to the stock (m, m/s).
    radius_m : ndarray (n,)
        The tool's radius at each sample (m).
    height_map : HeightMap
    corner_m, flute_m : ndarray (n,) or None
        The tool's corner radius (m; 0 a flat end mill, the radius a ball) and flute length
        (m); None: flat, and flutes longer than any depth.
    shank_m : ndarray (n,) or None
        The radius of the tool's shank above the flutes (m; 0 or None: the cutter's radius).
        Material within it above the flute length is ``over_flutes_mm``.
    """
    n = len(position_m)
    radius = np.ascontiguousarray(radius_m, float)
    corner = np.zeros(n) if corner_m is None else np.ascontiguousarray(corner_m, float)
    flute = np.full(n, np.inf) if flute_m is None else np.ascontiguousarray(flute_m, float)
    shank = np.zeros(n) if shank_m is None else np.ascontiguousarray(shank_m, float)
    out = np.zeros((n, len(COLUMNS)))
    _engage(
        np.ascontiguousarray(position_m, float),
        np.ascontiguousarray(velocity_m_per_s, float),
        Tools(radius_m=radius, corner_m=corner, flute_m=flute, shank_m=shank),
        height_map.grid(),
        math.radians(ANGLE_STEP_DEG),
        out,
    )
    return out


def engaged_degrees(table: np.ndarray) -> np.ndarray:
    """The engaged angle of each row (degrees, both arcs together)."""
    column = {name: table[:, COLUMNS.index(name)] for name in ("phi_st1", "phi_ex1", "phi_st2", "phi_ex2")}
    return np.degrees((column["phi_ex1"] - column["phi_st1"]) + (column["phi_ex2"] - column["phi_st2"]))
