"""The machined part's height maps and mesh: volumes of slots against closed forms (a flat end
mill's rectangle, a ball's circular segment), a closed mesh (trimesh's own checks), and the
error map's material left and overcut where the actual path moved."""

import math

import numpy as np
import pyarrow.parquet as pq
import pytest
import trimesh

import twin.machining.part_map as part_map_module
from twin.machining.engagement import StockSpec
from twin.machining.part_map import part_map
from twin.machining.sweep import ToolSweep

RES = 0.05
STOCK = StockSpec(corners_mm=[[0.0, 0.0], [30.0, 20.0]], top_mm=0.0, bottom_mm=-10.0, resolution_mm=RES)
BLOCK_MM3 = 30.0 * 20.0 * 10.0


def slot(
    y_mm: float, depth_mm: float = 2.0, corner_mm: float = 0.0, n: int = 2000, radius_mm: float = 3.0
) -> ToolSweep:
    """A tool (6 mm unless told) along X right across the stock (from X -5 to X 35) at Y ``y_mm``."""
    x = np.linspace(-5.0, 35.0, n)
    return ToolSweep(
        np.column_stack([x, np.full(n, y_mm)]),
        np.full(n, -depth_mm),
        np.full(n, radius_mm),
        np.full(n, corner_mm),
        np.full(n, 7),
    )


def volume(maps) -> float:
    mesh = trimesh.Trimesh(*maps.mesh(), process=False)
    assert mesh.is_watertight
    assert mesh.is_winding_consistent
    assert mesh.volume > 0
    return float(mesh.volume)


def test_flat_slot_volume_and_closed_mesh():
    # a 6.02 x 2 mm slot 30 mm long, walls at Y 7.003 and 13.023: the surface ramps between the
    # cell centres either side of a wall, which holds the material of a step at the cells' common
    # edge (7.0, 13.0): 0.003 mm less below the lower wall, 0.023 more above the upper one
    maps = part_map(STOCK, slot(10.013, radius_mm=3.01), slot(10.013, radius_mm=3.01))
    ramps = 2.0 * 30.0 * (0.023 - 0.003)
    assert volume(maps) == pytest.approx(BLOCK_MM3 - 6.02 * 2.0 * 30.0 + ramps, abs=1e-6)


def test_ball_slot_volume_is_the_circular_segment():
    # a ball of radius 3 mm, 2 mm deep: the section R^2 acos((R - d)/R) - (R - d) sqrt(2 R d - d^2)
    r, d = 3.0, 2.0
    segment = r**2 * math.acos((r - d) / r) - (r - d) * math.sqrt(2 * r * d - d**2)
    maps = part_map(STOCK, slot(10.0, d, r), slot(10.0, d, r))
    assert BLOCK_MM3 - volume(maps) == pytest.approx(segment * 30.0, rel=5e-3)


def test_error_map_signs_where_the_path_moved(tmp_path):
    # the actual slot 0.2 mm towards +Y: a band 0.2 mm wide left (+2000 µm) along the lower wall
    # and one overcut (-2000 µm) along the upper, each 30 mm long
    maps = part_map(STOCK, slot(10.0), slot(10.2))
    table = pq.read_table(maps.to_parquet(tmp_path / "map.parquet")).to_pandas()
    assert len(table) == 600 * 400  # the cells inside the stock
    left, over = table[table.error_um > 1.0], table[table.error_um < -1.0]
    np.testing.assert_allclose(left.error_um, 2000.0)
    np.testing.assert_allclose(over.error_um, -2000.0)
    assert len(left) * RES**2 == pytest.approx(0.2 * 30.0, abs=RES * 30.0)
    assert len(over) * RES**2 == pytest.approx(0.2 * 30.0, abs=RES * 30.0)
    assert left.y_mm.between(7.0, 7.2).all()
    assert over.y_mm.between(13.0, 13.2).all()


def test_a_large_map_is_meshed_coarser_and_still_closed(monkeypatch, tmp_path):
    monkeypatch.setattr(part_map_module, "MAX_MESH_CELLS", 10_000)
    maps = part_map(STOCK, slot(10.0), slot(10.0))
    assert len(maps.mesh().faces) < 3 * 10_000
    assert volume(maps) == pytest.approx(BLOCK_MM3 - 6.0 * 2.0 * 30.0, rel=0.01)
    mesh = trimesh.load(maps.to_stl(tmp_path / "part.stl"))  # read back from the file
    assert mesh.is_watertight
    assert mesh.volume == pytest.approx(volume(maps), rel=1e-6)


def test_ball_scallop_between_two_passes():
    # two passes of a 6 mm ball 0.2 mm deep, 1.6 mm apart: between them the floor rises to the
    # ball's circle, z = tip + R - sqrt(R^2 - dy^2) from the nearer pass, at each cell centre
    r, tip = 3.0, -0.2
    first, second = slot(10.0, 0.2, r), slot(11.6, 0.2, r)
    both = ToolSweep(**{k: np.concatenate([getattr(first, k), getattr(second, k)]) for k in vars(first)})
    maps = part_map(STOCK, both, both)
    hm = maps.actual
    ys = (hm.y0_m + (np.arange(hm.heights.shape[1]) + 0.5) * hm.res_m) * 1e3
    between = (ys > 10.0) & (ys < 11.6)
    column = hm.heights[hm.heights.shape[0] // 2, between] * 1e3
    dy = np.minimum(ys[between] - 10.0, 11.6 - ys[between])
    # (to 20 nm: the passes are sampled every 0.02 mm, and between samples the sphere stands up
    # to dx^2 / 2 rho higher over the cell, dx 0.01 mm and rho its radius there)
    np.testing.assert_allclose(column, tip + r - np.sqrt(r**2 - dy**2), rtol=0, atol=2e-5)
    cusp = tip + r - math.sqrt(r**2 - 0.8**2)  # the scallop's top, 0.109 mm over the tip
    assert column.max() == pytest.approx(cusp, abs=0.3 * RES)


def test_floor_error_leaves_walls_out_and_reads_scallops_moved():
    # a flat slot moved 0.2 mm: its floor is exact (the walls' ±2000 µm cells are not floors)
    moved = part_map(STOCK, slot(10.0), slot(10.2)).floor_error()
    assert moved["cells"] > 0.9 * 30.0 * 5.6 / RES**2
    assert moved["min"] == moved["max"] == 0.0
    # two 6 mm ball passes 1.6 mm apart, 0.2 mm deep, the actual ones 3 µm towards +Y: at each
    # cell the floor is the nearer pass's sphere, z(y) = tip + R - sqrt(R^2 - dy^2), up to the
    # top; its error z_actual - z_nominal at the cell centres the nominal passes cut: the most
    # on the outer flanks, where the sphere is steepest (0.39)
    r, tip = 3.0, -0.2

    def passes(shift):
        first, second = slot(10.0 + shift, 0.2, r), slot(11.6 + shift, 0.2, r)
        return ToolSweep(**{k: np.concatenate([getattr(first, k), getattr(second, k)]) for k in vars(first)})

    def floor(y, shift):
        dy = np.minimum(np.abs(y - 10.0 - shift), np.abs(y - 11.6 - shift))
        return np.minimum(tip + r - np.sqrt(np.maximum(r**2 - dy**2, 0.0)), 0.0)

    got = part_map(STOCK, passes(0.0), passes(0.003)).floor_error()
    y = np.arange(0.025, 20.0, RES)
    err = (floor(y, 0.003) - floor(y, 0.0)) * 1e3
    cut = floor(y, 0.0) < 0.0
    assert got["max"] == pytest.approx(err[cut].max(), abs=0.02)
    assert got["min"] == pytest.approx(err[cut].min(), abs=0.02)
    assert got["rms"] == pytest.approx(np.sqrt(np.mean(err[cut] ** 2)), rel=0.01)
    assert got["cells"] == (600 - 2) * cut.sum()  # the stock's edge columns are at its wall
