"""The machined part as files for the user's own tools: the height map of the nominal and the
actual part on the stock's grid (Parquet) and a closed triangle mesh of the actual part (STL).

Both maps are the stock's :class:`~twin.machining.engagement.HeightMap` cut by
:func:`~twin.machining.engagement.cut_path` (the engagement's own cut) along a
:class:`~twin.machining.sweep.ToolSweep`: the nominal one along the plan, the actual one where the
twin moved the tool.  A cell's height is the material's top at its centre, so a wall is placed
to the cell (``stock.resolution_mm``); the walls to a micrometre are
:class:`~twin.machining.part.MachinedPart`'s exact sections.  What the map adds is the floors and
3-D surfaces: a ball tool's scallops, a floor left by a pass that went elsewhere.

The mesh is the actual map's top surface (a vertex at each cell centre, two triangles per
square of four; the stock's bounding box at its edges, at the edge cells' heights), four sides
down to the stock's bottom and a bottom fan: closed, each edge shared by two triangles.  Cells
outside a non-rectangular stock, or cut through, lie at the bottom (no thickness there).  A map
of more than :data:`MAX_MESH_CELLS` cells is meshed on every k-th cell each way.
"""

from __future__ import annotations

import math
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from typing import NamedTuple

import numpy as np

from twin.machining.engagement import MAP_MARGIN_MM, HeightMap, StockSpec, cut_path
from twin.machining.sweep import ToolSweep

#: Cells the mesh takes at most (every k-th cell each way beyond it): about a million
#: triangles, a 50 MB binary STL.
MAX_MESH_CELLS = 500_000
#: Cells per Parquet row group: what the writer holds in memory at once.
ROW_GROUP_CELLS = 1_000_000
#: A cell is on a floor or a 3-D surface where the material's top differs from each of its four
#: neighbours' by at most this many cells' width (45 deg) in both maps, and the two maps by at
#: most as much: else it is at a wall, or a wall moved across it (the walls' exact error).
MAX_FLOOR_SLOPE = 1.0
#: Columns of the Parquet map.
MAP_COLUMNS = ("x_mm", "y_mm", "nominal_mm", "actual_mm", "error_um")


def cut_height_map(stock: StockSpec, sweep: ToolSweep, margin_mm: float) -> HeightMap:
    """The stock's height map, ``margin_mm`` around it, cut along ``sweep`` (mm)."""
    height_map = HeightMap(stock, margin_mm)
    tips = np.column_stack([sweep.xy_mm, sweep.tip_mm]) * 1e-3
    cut_path(
        height_map.grid(),
        np.ascontiguousarray(tips),
        np.ascontiguousarray(sweep.radius_mm * 1e-3),
        np.ascontiguousarray(sweep.corner_mm * 1e-3),
    )
    return height_map


class Mesh(NamedTuple):
    """A triangle mesh: ``vertices`` (v, 3) in mm and ``faces`` (f, 3) of vertex indices."""

    vertices: np.ndarray
    faces: np.ndarray


@dataclass
class PartMap:
    """The nominal and the actual part as height maps on one grid (:func:`part_map`).

    Attributes
    ----------
    stock : StockSpec
    nominal, actual : HeightMap
    """

    stock: StockSpec
    nominal: HeightMap
    actual: HeightMap

    def _inside(self) -> tuple[slice, slice]:
        """The map's cells whose centres lie within the stock's bounding box."""
        hm = self.actual
        x0, y0, x1, y1 = (b * 1e-3 for b in hm.stock_polygon.bounds)
        nx, ny = hm.heights.shape
        i = max(math.ceil((x0 - hm.x0_m) / hm.res_m - 0.5), 0), min(math.floor((x1 - hm.x0_m) / hm.res_m - 0.5), nx - 1)
        j = max(math.ceil((y0 - hm.y0_m) / hm.res_m - 0.5), 0), min(math.floor((y1 - hm.y0_m) / hm.res_m - 0.5), ny - 1)
        return slice(i[0], i[1] + 1), slice(j[0], j[1] + 1)

    def _material_mm(self, heights: np.ndarray) -> np.ndarray:
        """Heights (m) as the material's top (mm): at most the stock's top, at least its bottom
        (a cell cut through or outside the stock: the bottom)."""
        return np.clip(
            np.nan_to_num(heights * 1e3, neginf=self.stock.bottom_mm), self.stock.bottom_mm, self.stock.top_mm
        )

    def floor_error(self) -> dict:
        """The error of the machined floors and 3-D surfaces (µm, actual less nominal, material
        left positive): ``{min, max, rms, cells}`` over the cells the nominal part cut that are
        not at a wall (:data:`MAX_FLOOR_SLOPE`: at 0.05 mm cells, an error up to 50 µm), in
        blocks of rows (memory stays bounded); empty
        when there is no such cell.  The height at a cell centre is exact, so this resolves a
        micrometre on a surface whatever the cell."""
        nx, ny = self.actual.heights.shape
        rows = max(1, ROW_GROUP_CELLS // ny)
        low, high, squares, count = math.inf, -math.inf, 0.0, 0
        step = MAX_FLOOR_SLOPE * self.stock.resolution_mm
        for i in range(0, nx, rows):
            block = slice(max(i - 1, 0), min(i + rows + 1, nx))  # a row each side: the neighbours
            nominal = self._material_mm(self.nominal.heights[block])
            actual = self._material_mm(self.actual.heights[block])
            floor = np.isfinite(self.nominal.heights[block]) & (nominal < self.stock.top_mm - 1e-9)
            for heights in (nominal, actual):
                padded = np.pad(heights, 1, mode="edge")
                for di, dj in ((0, 1), (2, 1), (1, 0), (1, 2)):
                    shifted = padded[di : di + heights.shape[0], dj : dj + heights.shape[1]]
                    floor &= np.abs(shifted - heights) <= step
            floor &= np.abs(actual - nominal) <= step  # more: a wall moved across the cell
            inner = slice(i - block.start, i - block.start + min(rows, nx - i))  # this block's own rows
            err = ((actual - nominal) * 1e3)[inner][floor[inner]]
            if err.size:
                low, high = min(low, float(err.min())), max(high, float(err.max()))
                squares, count = squares + float(np.sum(err**2)), count + int(err.size)
        if not count:
            return {}
        return {
            "min": round(low, 3),
            "max": round(high, 3),
            "rms": round(math.sqrt(squares / count), 3),
            "cells": count,
        }

    def to_parquet(self, path: str | Path) -> Path:
        """Write the cells inside the stock, one row each (:data:`MAP_COLUMNS`: the centre, the
        nominal and actual material top in mm, and their difference in µm, positive where
        material is left), in row groups of :data:`ROW_GROUP_CELLS`."""
        import pyarrow as pa
        import pyarrow.parquet as pq

        hm = self.actual
        nx, ny = hm.heights.shape
        all_xs, ys = hm.centres_mm()
        rows = max(1, ROW_GROUP_CELLS // ny)
        schema = pa.schema([(name, pa.float64()) for name in MAP_COLUMNS])
        with pq.ParquetWriter(Path(path), schema) as writer:
            for i in range(0, nx, rows):
                stock = np.isfinite(self.nominal.heights[i : i + rows])  # -inf: no stock there
                nominal = self._material_mm(self.nominal.heights[i : i + rows])
                actual = self._material_mm(hm.heights[i : i + rows])
                gx, gy = np.meshgrid(all_xs[i : i + len(stock)], ys, indexing="ij")
                columns = (gx, gy, nominal, actual, (actual - nominal) * 1e3)
                writer.write_table(
                    pa.table({name: col[stock] for name, col in zip(MAP_COLUMNS, columns)}, schema=schema)
                )
        return Path(path)

    def mesh(self) -> Mesh:
        """The actual part as a closed triangle mesh, outward normals by the right-hand rule
        (see the module docstring)."""
        rows, cols = self._inside()
        cells = self.actual.heights[rows, cols]
        stride = max(1, math.ceil(math.sqrt(cells.size / MAX_MESH_CELLS)))
        z = np.pad(self._material_mm(cells[::stride, ::stride]), 1, mode="edge")
        hm = self.actual
        bx0, by0, bx1, by1 = hm.stock_polygon.bounds
        centres_x, centres_y = hm.centres_mm()
        xs = np.concatenate([[bx0], centres_x[rows][::stride], [bx1]])
        ys = np.concatenate([[by0], centres_y[cols][::stride], [by1]])
        mx, my = z.shape
        gx, gy = np.meshgrid(xs, ys, indexing="ij")
        top = np.column_stack([gx.ravel(), gy.ravel(), z.ravel()])
        index = np.arange(mx * my).reshape(mx, my)
        v00, v10, v01, v11 = index[:-1, :-1], index[1:, :-1], index[:-1, 1:], index[1:, 1:]
        surface = np.concatenate(
            [np.stack([v00, v10, v11], -1).reshape(-1, 3), np.stack([v00, v11, v01], -1).reshape(-1, 3)]
        )
        # the top's outline, counter-clockwise seen from above, each corner once
        ring = np.concatenate([index[:, 0], index[-1, 1:], index[-2::-1, -1], index[0, -2:0:-1]])
        base = len(top) + np.arange(len(ring))  # the outline again, at the bottom
        centre = len(top) + len(ring)
        a, b = ring, np.roll(ring, -1)
        a_low, b_low = base, np.roll(base, -1)
        sides = np.concatenate([np.column_stack([a, a_low, b_low]), np.column_stack([a, b_low, b])])
        bottom = np.column_stack([np.full(len(ring), centre), b_low, a_low])
        low = top[ring].copy()
        low[:, 2] = self.stock.bottom_mm
        middle = [0.5 * (bx0 + bx1), 0.5 * (by0 + by1), self.stock.bottom_mm]
        vertices = np.concatenate([top, low, [middle]])
        return Mesh(vertices, np.concatenate([surface, sides, bottom]))

    def to_stl(self, path: str | Path) -> Path:
        """Write :meth:`mesh` as a binary STL (mm)."""
        import trimesh

        mesh = self.mesh()
        trimesh.Trimesh(mesh.vertices, mesh.faces, process=False).export(Path(path), file_type="stl")
        return Path(path)


def part_map(stock: StockSpec, nominal: ToolSweep, actual: ToolSweep) -> PartMap:
    """The nominal and the actual part's height maps: ``stock`` cut along each sweep, on one
    grid with the engagement's margin (:data:`~twin.machining.engagement.MAP_MARGIN_MM`) rounded up
    to whole cells, so that the cells' edges fall on the stock's corner."""
    margin_mm = math.ceil(MAP_MARGIN_MM / stock.resolution_mm) * stock.resolution_mm
    # the two maps at once, a thread each (the compiled cut releases the GIL)
    with ThreadPoolExecutor(max_workers=2) as pool:
        maps = list(pool.map(lambda sweep: cut_height_map(stock, sweep, margin_mm), (nominal, actual)))
    return PartMap(stock, *maps)
