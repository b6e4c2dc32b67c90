"""The virtual part and its inspection: walls to a fraction of a micrometre whatever the height
map's cell (closed forms of straight slots), a ball tool's radius by height, and a bore cut by
the twin's actual motion measured against the envelope of that motion computed here."""

import math

import numpy as np
import pytest
import shapely

from twin import api
from twin.errors import TwinInputError
from twin.machining.inspection import CircleFeature, LineFeature, WidthFeature, measure
from twin.machining.part import machined_part, section, swept_radius_mm, wall_levels
from twin.machining.sweep import ToolSweep
from twin.records import CircleMeasured, FeatureNotFound, FeatureType, WidthMeasured

STOCK = shapely.box(0.0, 0.0, 30.0, 20.0)
R = 3.0  # a 6 mm flat end mill


def slot(offset_y_mm: float, n: int = 400) -> ToolSweep:
    """A slot 2 mm deep along X at Y 10 (+ offset) from X 5 to X 25."""
    x = np.linspace(5.0, 25.0, n)
    return ToolSweep(
        np.column_stack([x, np.full(n, 10.0 + offset_y_mm)]),
        np.full(n, -2.0),
        np.full(n, R),
        np.zeros(n),
        np.full(n, 7),
    )


def test_wall_error_is_the_path_offset_on_each_wall():
    # the actual path 3 µm towards +Y: the upper wall overcut by 3 µm, the lower one left 3 µm
    part = machined_part(STOCK, slot(0.0), slot(0.003), top_mm=0.0, bottom_mm=-10.0)
    assert part.levels_mm == [-1.0]
    walls = part.walls
    straight = (walls[:, 0] > 5.5) & (walls[:, 0] < 24.5)  # the walls, not the slot's round ends
    upper, lower = straight & (walls[:, 1] > 10.0), straight & (walls[:, 1] < 10.0)
    assert upper.sum() > 300
    assert lower.sum() > 300
    np.testing.assert_allclose(walls[upper, 3], -3.0, atol=0.01)
    np.testing.assert_allclose(walls[lower, 3], 3.0, atol=0.01)
    assert set(walls[:, 4]) == {7.0}
    assert abs(part.line_errors()[7]) == pytest.approx(3.0, abs=0.05)


def test_a_perfect_path_leaves_no_error():
    part = machined_part(STOCK, slot(0.0), slot(0.0), top_mm=0.0, bottom_mm=-10.0)
    assert np.abs(part.walls[:, 3]).max() < 1e-3
    assert part.summary()["surface_error_um"]["rms"] < 1e-3


def test_line_and_width_of_a_slot():
    actual = machined_part(STOCK, slot(0.0), slot(0.003), top_mm=0.0, bottom_mm=-10.0)
    width = measure(
        WidthFeature(type="width", name="slot", from_mm=(15, 5), to_mm=(15, 15), width_mm=6.0, z_mm=-1.0), actual
    )
    assert width.width_mm == pytest.approx(6.0, abs=1e-5)
    assert width.deviation_um == pytest.approx(0.0, abs=0.01)
    # the slot's upper wall (material above it) 3 µm further into the material: overcut
    upper = measure(
        LineFeature(type="line", name="upper", from_mm=(8, 13), to_mm=(22, 13), z_mm=-1.0, tolerance_um=2.0), actual
    )
    assert upper.deviation_um == pytest.approx(-3.0, abs=0.01)
    assert upper.passed is False
    assert upper.position_mm[1] == pytest.approx(13.003, abs=1e-5)
    assert upper.straightness_um < 0.01
    lower = measure(LineFeature(type="line", name="lower", from_mm=(22, 7), to_mm=(8, 7), z_mm=-1.0), actual)
    assert lower.deviation_um == pytest.approx(3.0, abs=0.01)
    assert lower.passed is None


def test_a_feature_not_on_the_part_says_so():
    part = machined_part(STOCK, slot(0.0), slot(0.0), top_mm=0.0, bottom_mm=-10.0)
    row = measure(CircleFeature(type="circle", name="none", center_mm=(5, 5), diameter_mm=1.0, z_mm=-1.0), part)
    assert isinstance(row, FeatureNotFound)
    assert row.to_json()["found"] is False
    assert row.to_json()["pass"] is False


def test_ball_radius_by_height_and_levels():
    # a 6 mm ball: at height h over its tip the radius is sqrt(2 R h - h^2), the full radius over R
    h = np.array([0.0, 0.5, 1.0, 3.0, 4.0])
    got = swept_radius_mm(-h, np.full(5, 3.0), np.full(5, 3.0), 0.0)
    np.testing.assert_allclose(got, [0.0, math.sqrt(2.75), math.sqrt(5.0), 3.0, 3.0])
    tips = np.concatenate([np.full(20, -0.5), np.full(20, -2.0), [-1.3] * 3])  # a ramp's few samples: no floor
    assert wall_levels(tips, np.ones(43, bool), 0.0, -10.0) == [-0.25, -1.25]


@pytest.fixture(scope="module")
def bore():
    scn = api.load("gcode_choi1999_circle_stock")
    features = [
        CircleFeature(type="circle", name="bore", center_mm=(-28, 0), diameter_mm=66.0, z_mm=-1.5, tolerance_um=10)
    ]
    return api.run(scn.model_copy(update={"inspect": features})).outcome


def test_bore_diameter_is_the_envelope_of_the_actual_motion(bore):
    # independent of the polygons: the wall's radius at each angle is the furthest reach of the
    # tool's discs (radius 5 mm) along that ray from the centre, over the actual path cut below
    # Z -1.5; the diameter twice its mean over 1440 angles
    xy = bore.run.table_position_m() * 1e3 - [-28.0, 0.0]
    cut = bore.run.program.extra_axes["z"] * 1e3 < -1.5
    rho, angle = np.hypot(*xy[cut].T), np.arctan2(xy[cut, 1], xy[cut, 0])
    theta = np.linspace(-np.pi, np.pi, 1440, endpoint=False)[:, None]
    along, across = rho * np.cos(angle - theta), rho * np.sin(angle - theta)
    reach = np.where(np.abs(across) < 5.0, along + np.sqrt(np.maximum(25.0 - across**2, 0.0)), -np.inf).max(axis=1)
    row = bore.inspection[0]
    assert isinstance(row, CircleMeasured)
    assert row.diameter_mm == pytest.approx(2 * reach.mean(), abs=1e-4)  # 0.1 µm
    assert row.roundness_um == pytest.approx(np.ptp(reach) * 1e3, abs=1.5)
    assert row.deviation_um == pytest.approx((row.diameter_mm - 66.0) * 1e3, abs=1e-3)
    assert row.passed is (abs(row.deviation_um) <= 10)


def test_a_run_stopped_halfway_is_compared_with_what_the_program_had_cut_by_then(bore):
    """The bore's run stopped at 1.5 s of its 2.9 s moves as the whole run did, and its part is
    the nominal part as far as the run went: its surface error within the whole run's (61 um)
    plus the tool's lag behind the plan where it stopped (26 um: material the nominal part as far
    as then has cut and the tool had not yet reached); against the whole program's part it read
    the half of the bore never reached as material left (3 mm)."""
    run = api.run("gcode_choi1999_circle_stock", duration_s=1.5)
    moved = run.result.table_position_m()
    assert np.array_equal(moved, bore.run.table_position_m()[: len(moved)])
    lag_um = float(np.hypot(*run.result.error_m()[-1])) * 1e6
    half = run.summary["part"]["surface_error_um"]
    whole = bore.part.summary()["surface_error_um"]
    assert half["max"] <= whole["max"] + lag_um
    assert half["min"] >= whole["min"] - 1.0


def test_bore_cut_by_the_perfect_loop_measures_its_size(bore):
    # an exact circle of radius 28 mm with the 5 mm tool: a 66 mm bore
    turn = np.linspace(0.0, 2 * np.pi, 20_001)
    n = len(turn)
    loop = ToolSweep(
        np.column_stack([28 * np.cos(turn) - 28, 28 * np.sin(turn)]),
        np.full(n, -3.0),
        np.full(n, 5.0),
        np.zeros(n),
        np.ones(n),
    )
    stock = bore.part.stock
    feature = CircleFeature(type="circle", name="bore", center_mm=(-28, 0), diameter_mm=66.0, z_mm=-1.5)
    row = measure(feature, machined_part(stock, loop, loop, top_mm=0.0, bottom_mm=-10.0))
    assert isinstance(row, CircleMeasured)
    assert row.diameter_mm == pytest.approx(66.0, abs=5e-5)
    assert row.roundness_um < 0.2
    # the planned reference runs inside the programmed circle (by its mean radius here): the
    # nominal part measures what it sweeps
    plan = bore.part.nominal
    on = plan.line == 12
    radius = np.hypot(plan.xy_mm[on, 0] + 28, plan.xy_mm[on, 1]).mean()
    row = measure(feature, machined_part(stock, plan, plan, top_mm=0.0, bottom_mm=-10.0))
    assert isinstance(row, CircleMeasured)
    assert row.diameter_mm == pytest.approx(2 * (radius + 5.0), abs=1e-4)


def test_per_line_wall_error_is_the_run_s(bore):
    lines = {row["line"]: row for row in api.Run(api.load("gcode_choi1999_circle_stock"), bore).summary["lines"]}
    walls = bore.part.walls
    circle = walls[walls[:, 4] == 12, 3]  # the G3 line cuts the bore's wall
    assert lines[12]["max_wall_error_um"] == pytest.approx(circle[np.argmax(np.abs(circle))], abs=1e-3)
    assert bore.part.summary()["surface_error_um"]["max"] == pytest.approx(walls[:, 3].max(), abs=1e-3)


def test_inspection_needs_a_stock():
    scn = api.load("gcode_test_piece")
    feature = CircleFeature(type="circle", name="b", center_mm=(0, 0), diameter_mm=1.0, z_mm=0.0)
    with pytest.raises(TwinInputError, match="inspect"):
        api.run(scn.model_copy(update={"inspect": [feature], "stock": None}))


def test_the_part_is_recorded_and_plotted(bore, tmp_path):
    from twin.recording import read_back

    run = api.Run(api.load("gcode_choi1999_circle_stock"), bore)
    counts = read_back(run.record(tmp_path / "part.rrd"))
    assert counts.get("/contour/part_walls", 0) > 0
    assert counts.get("/contour/inspection", 0) > 0
    assert "gcode_choi1999_circle_stock_walls.png" in {p.name for p in run.plots(tmp_path / "plots")}


def test_the_part_s_files_hold_the_cut(bore, tmp_path):
    # the mesh's volume less the uncut stock's is the material the actual motion removed: the
    # exact actual section's cut area (3 mm deep, one flat pass) times its depth
    import pyarrow.parquet as pq
    import trimesh

    from twin.machining.engagement import HeightMap
    from twin.machining.part_map import PartMap

    run = api.Run(api.load("gcode_choi1999_circle_stock"), bore)
    stl, parquet = run.write_part(tmp_path / "part")
    assert [stl.name, parquet.name] == [
        "gcode_choi1999_circle_stock_part.stl",
        "gcode_choi1999_circle_stock_part_map.parquet",
    ]
    part = trimesh.load(stl)
    stock = run.scenario.stock
    uncut = HeightMap(stock, 1.0)
    mesh = trimesh.Trimesh(*PartMap(stock, uncut, uncut).mesh(), process=False)
    assert part.is_watertight
    assert mesh.is_watertight
    area = bore.part.stock.area - section(bore.part.stock, bore.part.actual, -1.5).area
    assert mesh.volume - part.volume == pytest.approx(3.0 * area, abs=3.0)  # mm³, of 1 783
    table = pq.read_table(parquet).to_pandas()
    assert len(table) == np.isfinite(uncut.heights).sum()  # one row per cell of the stock
    machined = table.actual_mm < -1.0
    assert machined.sum() * stock.resolution_mm**2 == pytest.approx(area, rel=1e-3)


def test_part_files_need_a_stock():
    from typer.testing import CliRunner

    from twin.cli import app

    out = CliRunner().invoke(app, ["run", "choi1999_pid_air_cut", "--part", "somewhere"])
    assert out.exit_code == 2
    assert out.output.strip().splitlines() == [
        "error: --part = 'somewhere': the virtual part is cut from a stock: the scenario has no [stock]"
    ]


@pytest.fixture(scope="module")
def pocket():
    return api.run("gcode_pocket_ball_finish")


def test_pocket_roughed_and_ball_finished(pocket):
    # the program's floors: Z -2 and -4 (flat end mill), -4.2 (the ball's raster): walls are
    # read in the middle of each band under the top
    part = pocket.outcome.part
    assert part.levels_mm == [-1.0, -3.0, -4.1]
    # the pocket's length at Y 15, Z -0.5 from the actual motion alone: the furthest reach of the
    # tool's discs (the ball's radius at that height over its tip) along the line Y 15, each way
    xy = pocket.result.table_position_m() * 1e3
    sweep = part.actual
    radius = swept_radius_mm(sweep.tip_mm, sweep.radius_mm, sweep.corner_mm, -0.5)
    half = np.sqrt(np.maximum(radius**2 - (xy[:, 1] - 15.0) ** 2, 0.0))
    on = half > 0.0
    length = (xy[on, 0] + half[on]).max() - (xy[on, 0] - half[on]).min()
    row = next(r for r in pocket.outcome.inspection if r.name == "length")
    assert isinstance(row, WidthMeasured)
    assert row.width_mm == pytest.approx(length, abs=1e-4)  # 0.1 µm
    assert row.deviation_um == pytest.approx((length - 24.0) * 1e3, abs=0.1)
    measured = [r for r in pocket.outcome.inspection if not isinstance(r, FeatureNotFound)]
    assert len(measured) == 3
    assert {r.name: r.passed for r in measured} == {
        r.name: abs(r.deviation_um) <= 20.0 if r.type == FeatureType.WIDTH else abs(r.deviation_um) <= 10.0
        for r in measured
    }


def test_a_level_the_tool_ramps_through_is_skipped_not_swept_disc_by_disc(monkeypatch):
    # a bull-nose tool (0.5 mm corner) ramping from Z -1 to -3: at Z -2 its corner sweeps a new
    # radius at every sample of the ramp (50 of them); over the budget the level is not
    # sectioned (memory and time stay bounded) and says so; at Z -0.5 it is its full radius
    import twin.machining.part as part_module

    monkeypatch.setattr(part_module, "MAX_SECTION_RUNS", 20)
    n = 400
    x = np.linspace(5.0, 25.0, n)
    ramp = ToolSweep(
        np.column_stack([x, np.full(n, 10.0)]),
        np.concatenate([np.full(100, -1.0), np.linspace(-1.0, -3.0, 200), np.full(100, -3.0)]),
        np.full(n, 3.0),
        np.full(n, 0.5),
        np.full(n, 7),
    )
    part = machined_part(STOCK, ramp, ramp, top_mm=0.0, bottom_mm=-10.0)
    assert part.levels_mm == [-0.5]
    assert part.skipped_levels_mm == [-2.0]
    summary = part.summary()
    assert summary["skipped_levels_mm"] == [-2.0]
    assert "moves in Z" in summary["skipped_note"]
    with pytest.raises(part_module.SectionTooComplex, match="radii at Z -2 mm"):
        section(STOCK, ramp, -2.0)


@pytest.fixture(scope="module")
def slot_passes():
    return api.run("gcode_slot_passes").outcome


def test_four_passes_and_a_through_cut(slot_passes):
    # the floors -2, -4 and the block's bottom (the through-cut's tip 2 mm under it): walls read
    # between them; the slot's width through the block from the actual motion alone: the
    # furthest reach of the 5 mm discs along X 50 each way, over the samples cutting below Z -10
    part = slot_passes.part
    assert part.levels_mm == [-1.0, -3.0, -12.0]
    xy = slot_passes.run.table_position_m() * 1e3
    deep = part.actual.tip_mm < -10.0
    half = np.sqrt(np.maximum(25.0 - (xy[deep, 0] - 50.0) ** 2, 0.0))
    on = half > 0.0
    width = (xy[deep][on, 1] + half[on]).max() - (xy[deep][on, 1] - half[on]).min()
    row = next(r for r in slot_passes.inspection if r.name == "through slot")
    assert isinstance(row, WidthMeasured)
    assert row.width_mm == pytest.approx(width, abs=1e-4)
    # the pass stepped over widened the slot near the top only
    stepped = next(r for r in slot_passes.inspection if r.name == "stepped slot")
    assert isinstance(stepped, WidthMeasured)
    assert stepped.width_mm == pytest.approx(15.0, abs=0.05)
    # every wall point lies on a wall the nominal tool formed: the slot's sides, Y 20 and 30/35
    walls = part.walls
    inside = (walls[:, 0] > 5.0) & (walls[:, 0] < 95.0)
    assert set(np.round(walls[inside, 1], 3)) <= {20.0, 30.0, 35.0}


def test_bench_programs_read_as_written():
    from twin.bench import finish_program, slot_variants
    from twin.gcode.reader import Reader
    from twin.scenario.files import bundled_scenarios

    lines = list(finish_program(2_000))
    assert 1_990 <= len(lines) <= 2_100
    moves = list(Reader(lines).moves())
    assert len(moves) >= 1_900
    program = bundled_scenarios()["gcode_slot_passes"].parent / "programs" / "slot_passes.ngc"
    variants = slot_variants(program.read_text().splitlines())
    assert [text for text in variants["slot_through_cut"] if text.startswith("G1")] == ["G1 Z-22 F600", "G1 X120 F1200"]
    assert sum(text == "G1 X120 F1200" for text in variants["slot_two_passes"]) == 2


@pytest.mark.slow
def test_bench_times_the_part_beside_its_run():
    from twin.bench import part_figures

    figures = part_figures(1, 300)
    assert sorted(figures["cases"]) == sorted(
        [
            "slot_four_passes",
            "slot_two_passes",
            "slot_through_cut",
            "slot_100mm_cutter_0.05s",
            "pocket_ball_finish",
            "test_piece",
        ]
    )
    for case in figures["cases"].values():
        assert case["part_over_run"] == pytest.approx(case["part_s"] / case["run_s"])
        assert 0 < case["part_peak_mb"] < 1000
    # the two-pass slot: 2 levels of walls (Z -1 and -3) over both of the slot's sides
    assert figures["cases"]["slot_two_passes"]["wall_points"] == 2 * 2 * 1999
    assert figures["cases"]["slot_100mm_cutter_0.05s"]["ticks"] == 100
    finish = figures["finish"]
    assert finish["lines"] == 300
    assert finish["samples"] > 1000
    assert 0 < finish["part_peak_mb"] < 1000
