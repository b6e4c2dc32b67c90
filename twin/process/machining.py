"""Virtual machining: a 2.5-D stock the part program cuts, so that the material decides the
cutting force.

The stock is an outline polygon (shapely) between ``bottom_mm`` and ``top_mm``, with optional
islands (openings through it), held as a height map (a Z-map) on a square grid of
``resolution_mm``.  Along the planned reference, sample by sample (every 1 ms), the tool's
leading half circle is tested against the height map: the engaged arcs (entry and exit
immersion angles, clockwise from the feed normal on the left, as
:func:`twin.process.cutting.immersion_angles`; up to two arcs) and the axial depth (the
material's height above the tool tip, within the stock); then the tool's disc is cut to its tip
height.  This is computed once along the nominal path (the table follows it within
micrometres), and the mechanistic force kernel reads it by time each physics step
(:class:`ProgramMilling`), with the spindle turning at the programmed S between M3/M4 and M5.

Resolution (ours): 0.05 mm cells and 1 degree steps on the tool's circle, so that the circle's
points (0.052 mm apart on a 6 mm tool) and the cells are of one size, and a side cut's exit
angle ``arccos(1 - 2 a/D)`` comes out within about a degree (tested).
"""

from __future__ import annotations

import math
from typing import Annotated, Literal

import numpy as np
import shapely
from numba import njit
from pydantic import Field, PositiveFloat, model_validator

from twin.errors import TwinInputError
from twin.numba_cache import configure as configure_numba_cache
from twin.process.cutting import MATERIALS, MAX_FLUTES
from twin.spec import StrictSpec

configure_numba_cache()  # before the first @njit(cache=True): see twin.numba_cache

#: Points of a stock polygon at most.
MAX_POLYGON_POINTS = 100_000
#: Height-map cells at most: 4e7 float64 is 320 MB (a 300 x 300 mm stock at 0.05 mm).
MAX_CELLS = 40_000_000
#: Angular step of the engagement test on the tool's leading half circle (degrees).
ANGLE_STEP_DEG = 1.0
#: Material thinner than this above the tool tip (mm) is not cut (rounding of heights).
MIN_DEPTH_MM = 1e-6
#: Columns of the engagement table, per sample of the planned reference.
COLUMNS = ("phi_st1", "phi_ex1", "phi_st2", "phi_ex2", "axial_depth_mm", "radius_mm")


class StockSpec(StrictSpec):
    """The ``[stock]`` table: a 2.5-D workpiece, machine coordinates (mm)."""

    outline_mm: list[tuple[float, float]] | None = Field(
        None, min_length=3, max_length=MAX_POLYGON_POINTS, description="outline polygon [[x, y], ...]"
    )
    corners_mm: tuple[tuple[float, float], tuple[float, float]] | None = Field(
        None, description="a rectangle [[x0, y0], [x1, y1]] instead of an outline"
    )
    top_mm: float = Field(description="top of the stock (Z, mm)")
    bottom_mm: float = Field(description="bottom of the stock (Z, mm)")
    islands_mm: list[Annotated[list[tuple[float, float]], Field(min_length=3, max_length=MAX_POLYGON_POINTS)]] = Field(
        default_factory=list, max_length=1000, description="openings through the stock, each a polygon"
    )
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
        return outline


class ToolSpec(StrictSpec):
    """A cutter: the ``[tool]`` table, or an entry of ``[[tools]]`` with its ``number``."""

    number: int | None = Field(None, ge=0, description="T number ([[tools]] only)")
    diameter_mm: PositiveFloat = Field(description="cutter diameter (mm)")
    n_flutes: int = Field(ge=1, le=MAX_FLUTES, description="teeth")
    helix_deg: float = Field(
        0.0, ge=0.0, lt=60.0, description="helix angle (deg); the straight-flute force kernel does not use it yet"
    )
    # the names of the materials table (pydantic evaluates the Literal at run time; mypy cannot)
    material: Literal[tuple(MATERIALS)] = Field(  # type: ignore[valid-type]
        "aluminium_7075_t6", description="cutting coefficients of: " + ", ".join(MATERIALS)
    )


def tool_for(tools: dict[int, ToolSpec], number: int, line: int) -> ToolSpec:
    """The tool ``number`` (a program's T word) from ``tools``.

    Raises
    ------
    TwinInputError
        No such tool.
    """
    if number not in tools:
        raise TwinInputError(f"program line {line}", f"T{number}", f"no such tool (tools: {sorted(tools)})")
    return tools[number]


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

    def outlines(self) -> dict[str, list[np.ndarray]]:
        """The stock's outline and the outline of the material left at its full height (the
        part's top as machined), each a list of closed polylines (n, 2) in mm."""
        import contourpy

        stock = [np.asarray(self.stock_polygon.exterior.coords)] + [
            np.asarray(ring.coords) for ring in self.stock_polygon.interiors
        ]
        nx, ny = self.heights.shape
        xs = (self.x0_m + (np.arange(nx) + 0.5) * self.res_m) * 1e3
        ys = (self.y0_m + (np.arange(ny) + 0.5) * self.res_m) * 1e3
        z = np.where(np.isfinite(self.heights), self.heights, self.bottom_m - 1.0).T
        lines = contourpy.contour_generator(xs, ys, z).lines(self.top_m - 1e-6)
        return {"stock": stock, "machined": [np.asarray(line) for line in lines]}


@njit(cache=True)
def _side_engagement(cx, cy, cz, r, ux, uy, heights, x0, y0, res, top, bottom, n_steps, step, row):  # pragma: no cover
    """One sample's engaged arcs and axial depth into ``row`` (see :func:`_engage`)."""
    nx, ny = heights.shape
    # the leading half circle: phi from 0 (feed normal, left) through pi/2 (ahead) to pi
    runs = 0
    in_run = False
    max_h = -np.inf
    last = 0.0
    # the circle is read three quarters of a cell outside the tool: the cells there are
    # beyond the discs it has cut (their centres are over r from its path), while the tool's
    # own edge would fall in cells it has just cut
    reach = r + 0.75 * res
    for s in range(n_steps):
        phi = s * step
        qx = cx + reach * (math.sin(phi) * ux - math.cos(phi) * uy)
        qy = cy + reach * (math.sin(phi) * uy + math.cos(phi) * ux)
        i = int((qx - x0) / res)
        j = int((qy - y0) / res)
        present = False
        if 0 <= i < nx and 0 <= j < ny:
            h = heights[i, j]
            if h > cz + 1e-9:
                present = True
                if h > max_h:
                    max_h = h
        if present and not in_run:
            in_run = True
            if runs < 2:
                row[2 * runs] = phi
        elif not present and in_run:
            in_run = False
            if runs < 2:
                row[2 * runs + 1] = last
            runs += 1
        last = phi
    if in_run:
        if runs < 2:
            row[2 * runs + 1] = last
        runs += 1
    if runs > 0:
        depth = min(max_h, top) - max(cz, bottom)
        row[4] = max(0.0, min(depth, top - bottom)) * 1e3


@njit(cache=True)
def _engage(pos, vel, radius, cutting, heights, x0, y0, res, top, bottom, step, out):  # pragma: no cover
    """The engagement table ``out`` (n, 6: :data:`COLUMNS`, angles in rad, depth in mm) along
    tool centres ``pos`` (n, 3, m) moving at ``vel`` (n, 3), tool radius ``radius`` (n, m),
    cutting where ``cutting`` (n) is true; cuts ``heights`` (m) as it goes."""
    nx, ny = heights.shape
    n = pos.shape[0]
    ux, uy = 1.0, 0.0
    n_steps = round(math.pi / step) + 1
    have_prev = False
    px_prev = py_prev = pz_prev = r_prev = 0.0
    for k in range(n):
        cx, cy, cz, r = pos[k, 0], pos[k, 1], pos[k, 2], radius[k]
        speed = math.hypot(vel[k, 0], vel[k, 1])
        if speed > 1e-6:
            ux, uy = vel[k, 0] / speed, vel[k, 1] / speed
        for c in range(6):
            out[k, c] = 0.0
        out[k, 5] = r * 1e3
        if not cutting[k] or cz >= top:
            continue
        # side milling: the tool must move in XY (a plunge's bottom cutting is not modelled,
        # though it removes the material under the tool)
        if speed > 1e-6:
            _side_engagement(cx, cy, cz, r, ux, uy, heights, x0, y0, res, top, bottom, n_steps, step, out[k])
        # cut the tool's disc to its tip height: the whole disc where the tool went deeper or
        # changed, else only the cells the disc newly covers on each row (a crescent)
        full = (not have_prev) or cz < pz_prev - 1e-12 or r != r_prev
        j_lo = max(int((cy - r - y0) / res), 0)
        j_hi = min(int((cy + r - y0) / res) + 1, ny)
        for j in range(j_lo, j_hi):
            yc = y0 + (j + 0.5) * res
            dy = yc - cy
            if abs(dy) > r:
                continue
            w = math.sqrt(r * r - dy * dy)
            a = max(math.ceil((cx - w - x0) / res - 0.5), 0)
            b = min(math.floor((cx + w - x0) / res - 0.5), nx - 1)
            if b < a:
                continue
            old_a, old_b = 1, 0  # empty
            if not full:
                dyo = yc - py_prev
                if abs(dyo) <= r_prev:
                    wo = math.sqrt(r_prev * r_prev - dyo * dyo)
                    old_a = math.ceil((px_prev - wo - x0) / res - 0.5)
                    old_b = math.floor((px_prev + wo - x0) / res - 0.5)
            for i in range(a, b + 1):
                if old_a <= i <= old_b:
                    continue
                if heights[i, j] > cz:
                    heights[i, j] = cz
        have_prev = True
        px_prev, py_prev, pz_prev, r_prev = cx, cy, cz, r


def engagement_table(position_m, velocity_m_per_s, radius_m, cutting, height_map: HeightMap) -> np.ndarray:
    """The engagement along a planned path (see the module docstring), shape (n, 6):
    :data:`COLUMNS`, angles in rad, depth and radius in mm.  Cuts ``height_map`` as it goes."""
    out = np.zeros((len(position_m), len(COLUMNS)))
    _engage(
        np.ascontiguousarray(position_m, float),
        np.ascontiguousarray(velocity_m_per_s, float),
        np.ascontiguousarray(radius_m, float),
        np.ascontiguousarray(cutting, np.bool_),
        height_map.heights,
        height_map.x0_m,
        height_map.y0_m,
        height_map.res_m,
        height_map.top_m,
        height_map.bottom_m,
        math.radians(ANGLE_STEP_DEG),
        out,
    )
    return out


def engaged_degrees(table: np.ndarray) -> np.ndarray:
    """The engaged angle of each row (degrees, both arcs together)."""
    return np.degrees((table[:, 1] - table[:, 0]) + (table[:, 3] - table[:, 2]))


class ProgramMilling:
    """The milling force of a part program through a stock, for the compiled loop: the
    engagement table (:func:`engagement_table`) with the spindle speed, its angle and the tool
    at each sample, read by :func:`twin.process.cutting._program_milling` each physics step.

    Parameters
    ----------
    table : ndarray (n, 6)
        The engagement (:data:`COLUMNS`) every ``period_s``.
    spindle_rpm : ndarray (n,)
        Spindle speed at each sample (0: stopped).
    tool_index : ndarray (n,) of int
        Index into ``tools`` at each sample.
    tools : list of ToolSpec
    period_s : float
        The table's sample period (s).
    spindle_phase_rad : float
        Flute 0's angle at t = 0.
    """

    def __init__(self, table, spindle_rpm, tool_index, tools, period_s, spindle_phase_rad=0.0):
        self.table, self.spindle_rpm, self.tool_index = table, spindle_rpm, tool_index
        self.tools, self.period_s, self.spindle_phase_rad = list(tools), period_s, spindle_phase_rad

    def kernel_arrays(self, machine) -> tuple[int, np.ndarray, np.ndarray]:
        """``(PROGRAM_MILLING, params, state)`` for :func:`twin.process.cutting.workpiece_forces`."""
        from twin.process.cutting import MIN_SPINDLE_RPM, PM_COLUMNS, PROGRAM_MILLING, PROGRAM_MILLING_SLOTS

        dt = machine.model.opt.timestep
        omega = 2.0 * math.pi * self.spindle_rpm / 60.0
        angle = self.spindle_phase_rad + np.concatenate([[0.0], np.cumsum(omega[:-1] * self.period_s)])
        flutes = np.array([t.n_flutes for t in self.tools])[self.tool_index]
        turning = self.spindle_rpm >= MIN_SPINDLE_RPM
        lag = np.max(2.0 * math.pi / (omega[turning] * flutes[turning]) / dt) if turning.any() else 1.0
        n_hist = int(lag) + 2
        rows = np.column_stack([self.table[:, :5], omega, angle, self.tool_index]).astype(float)
        assert rows.shape[1] == len(PM_COLUMNS)
        tools = [np.concatenate([MATERIALS[t.material].as_array(), [t.n_flutes]]) for t in self.tools]
        jacobian = np.asarray(machine.workpiece_jacobian(), float).ravel()
        head = dict(zip(PROGRAM_MILLING_SLOTS, (len(self.tools), self.period_s, len(rows), dt, n_hist, jacobian.size)))
        params = np.concatenate([[float(head[name]) for name in PROGRAM_MILLING_SLOTS], jacobian, *tools, rows.ravel()])
        return PROGRAM_MILLING, params, np.zeros(3 + 2 * n_hist)


def program_milling(plan, stock: StockSpec, tool: ToolSpec | None, tools: list[ToolSpec], seed: int):
    """The stock cut by a planned program: the force model and its engagement table.

    Parameters
    ----------
    plan : twin.gcode.planner.Plan
    stock : StockSpec
    tool : ToolSpec or None
        The tool of a program without T words.
    tools : list of ToolSpec
        The tools of a program that changes them, by ``number``.
    seed : int
        Seeds the spindle's angle at t = 0.

    Raises
    ------
    TwinInputError
        No tool given, a tool without a number in ``[[tools]]`` or a number twice, or a T word
        with no such tool (naming the program line).
    """
    from twin.process.cutting import _spindle_phase

    if tool is None and not tools:
        raise TwinInputError("tool", None, "a stock is cut by a tool: give [tool] or [[tools]]")
    by_number: dict[int, ToolSpec] = {}
    for i, t in enumerate(tools):
        if t.number is None:
            raise TwinInputError(f"tools.{i}.number", None, "each of [[tools]] needs its T number")
        if t.number in by_number:
            raise TwinInputError(f"tools.{i}.number", t.number, "two tools with one number")
        by_number[t.number] = t
    numbers = plan.per_sample(plan.tools, 0)
    chosen: list[ToolSpec] = []
    index = np.zeros(len(numbers), int)
    for number in np.unique(numbers):
        if int(number) in by_number:
            spec = by_number[int(number)]
        elif tool is not None and (number == 0 or not by_number):
            spec = tool
        else:
            line = next(line for line, t in plan.tools.items() if t == number)
            raise TwinInputError(
                f"program line {line}", f"T{int(number)}", f"no such tool (tools: {sorted(by_number)})"
            )
        chosen.append(spec)
        index[numbers == number] = len(chosen) - 1
    radius = np.array([t.diameter_mm for t in chosen])[index] * 0.5e-3
    rpm = plan.per_sample(plan.spindle_rpm, 0.0)
    height_map = HeightMap(stock, max(t.diameter_mm for t in chosen) + 1.0)
    table = engagement_table(plan.position, plan.velocity, radius, rpm > 0, height_map)
    model = ProgramMilling(table, rpm, index, chosen, plan.period_s, _spindle_phase(None, seed))
    return model, table, height_map
