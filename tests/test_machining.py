"""Virtual machining: the engagement along a program against closed forms (a slot is 180 deg, a
side cut of radial depth a engages arccos(1 - 2a/D), an inside arc more than a straight line at
the same depth, air moves nothing), the stock and tool tables' errors, and Choi 1999's circle
cutting a stock against the built-in cutting circle."""

import math
from pathlib import Path

import numpy as np
import pytest

from twin import api
from twin.errors import TwinInputError
from twin.gcode.planned import Limits
from twin.gcode.planner import PlannerSettings, plan
from twin.gcode.reader import Reader
from twin.machining.engagement import StockSpec, ToolSpec, engaged_degrees
from twin.machining.program_cut import program_milling
from twin.scenario import assemble, read_scenario_data, scenario_from_dict

LIMITS = Limits((0.5, 0.5, 0.2), (5.0, 5.0, 2.0), (100.0, 100.0, 200.0))
TOOL = ToolSpec(diameter_mm=6.0, n_flutes=2)
STRAIGHT = ["G21 G90 G0 X-10 Y0 Z5", "M3 S10000", "G1 Z-2 F300", "G1 X30 F600", "M5"]


def _engagement(lines, stock, tool=TOOL, tools=()):
    planned = plan(Reader(lines).moves(), LIMITS, PlannerSettings(tolerance_mm=0.01))
    table = program_milling(planned, stock, tool, tools=list(tools), seed=0).table
    return planned, table


def _steady(planned, table):
    """Rows well inside the stock on the straight cut (x from 10 to 25 mm)."""
    inside = (planned.position[:, 0] > 0.010) & (planned.position[:, 0] < 0.025)
    return table[inside]


def test_a_slot_engages_half_the_circle_at_the_full_depth():
    planned, table = _engagement(STRAIGHT, StockSpec(corners_mm=((0, -10), (40, 10)), top_mm=0, bottom_mm=-10))
    rows = _steady(planned, table)
    assert engaged_degrees(rows) == pytest.approx(180.0, abs=1.0)
    assert rows[:, 2] == pytest.approx(2.0, abs=1e-6)  # stock top 0, tool tip at Z-2
    assert rows[:, 6] == pytest.approx(2.0, abs=1e-6)


@pytest.mark.parametrize("radial_mm", [0.5, 1.5, 3.0, 4.5])
def test_a_side_cut_engages_arccos_of_one_minus_2a_over_d(radial_mm):
    """The material right of the feed (down milling with M3): exit at pi, entry at
    pi - arccos(1 - 2a/D); half immersion (a = D/2) is 90 deg."""
    stock = StockSpec(corners_mm=((0, -10), (40, -3 + radial_mm)), top_mm=0, bottom_mm=-10)
    rows = _steady(*_engagement(STRAIGHT, stock))
    closed = math.degrees(math.acos(1 - 2 * radial_mm / 6.0))
    assert engaged_degrees(rows).mean() == pytest.approx(closed, abs=1.5)
    assert np.degrees(rows[:, 1]).mean() == pytest.approx(180.0, abs=1e-9)


def test_an_inside_arc_engages_more_than_a_straight_cut_as_the_two_circles_say():
    """Tool centre on a circle of R_t = 20 mm inside a bore of R_0 = R_t + r - a: the engaged
    angle is arccos((R_0^2 - R_t^2 - r^2) / (2 R_t r)), over arccos(1 - 2a/D) of a straight cut."""
    a, r, r_t = 1.0, 3.0, 20.0
    r_0 = r_t + r - a
    block = [(50 * math.cos(q), 50 * math.sin(q)) for q in np.linspace(0, 2 * math.pi, 200, endpoint=False)]
    bore = [(r_0 * math.cos(q), r_0 * math.sin(q)) for q in np.linspace(0, 2 * math.pi, 1440, endpoint=False)]
    stock = StockSpec(outline_mm=block, islands_mm=[bore], top_mm=0, bottom_mm=-10)
    planned, table = _engagement(["G21 G90 G0 X20 Y0 Z5", "M3 S10000", "G1 Z-2 F300", "G3 X20 Y0 I-20 J0 F600"], stock)
    angle = np.arctan2(planned.position[:, 1], planned.position[:, 0])
    on_arc = (angle > 1.0) & (angle < 2.5) & (planned.position[:, 2] < -0.0019)
    closed = math.degrees(math.acos((r_0**2 - r_t**2 - r**2) / (2 * r_t * r)))
    straight = math.degrees(math.acos(1 - 2 * a / 6.0))
    assert engaged_degrees(table[on_arc]).mean() == pytest.approx(closed, abs=1.0)
    assert closed > straight + 3.0


def test_air_moves_engage_nothing_and_a_stopped_spindle_no_force():
    """Above the top nothing is engaged; a tool that does not turn (no M3) still meets the
    material it is moved through (a crash: :mod:`twin.machining.misuse` warns of it), but the
    force model's table carries no spindle speed there, so no cutting force."""
    stock = StockSpec(corners_mm=((0, -10), (40, 10)), top_mm=0, bottom_mm=-10)
    _, air = _engagement(["G21 G90 G0 X-10 Y0 Z5", "M3 S10000", "G1 X30 F600"], stock)  # above the top
    assert not air[:, :7].any()
    lines = ["G21 G90 G0 X-10 Y0 Z5", "G1 Z-2 F300", "G1 X30 F600"]  # no M3
    planned = plan(Reader(lines).moves(), LIMITS, PlannerSettings(tolerance_mm=0.01))
    cut = program_milling(planned, stock, TOOL, tools=[], seed=0)
    assert cut.table[:, 6].max() == pytest.approx(2.0)
    assert not cut.milling.spindle_rpm.any()


@pytest.mark.parametrize(
    "change, field, words",
    [
        (
            {"stock": {"outline_mm": [[0, 0], [10, 10], [10, 0], [0, 10]], "top_mm": 0, "bottom_mm": -5}},
            "stock.outline_mm",
            "Self-intersection",
        ),
        (
            {"stock": {"corners_mm": [[0, 0], [10, 10]], "top_mm": -6, "bottom_mm": -5}},
            "stock",
            "is not above bottom_mm",
        ),
        ({"stock": {"top_mm": 0, "bottom_mm": -5}}, "stock", "give outline_mm or corners_mm"),
        (
            {"stock": {"corners_mm": [[0, 0], [9, 9]], "islands_mm": [[[0, 0], [1, 1]]], "top_mm": 0, "bottom_mm": -5}},
            "stock.islands_mm.0",
            "at least 3 items",
        ),
        (
            {"tools": [{"number": 1, "diameter_mm": 0, "n_flutes": 2}]},
            "tools.0.diameter_mm",
            "greater than or equal to 0.01",
        ),
        ({"tools": [{"number": 1, "diameter_mm": 6, "n_flutes": 0}]}, "tools.0.n_flutes", "greater than or equal to 1"),
        (
            {"tools": [{"number": 1, "diameter_mm": 6, "n_flutes": 2, "corner_radius_mm": 3.5}]},
            "tools.0",
            "corner_radius_mm = 3.5 is over half the diameter",
        ),
        (
            {"tools": [{"number": 2, "diameter_mm": 6, "n_flutes": 2}]},
            str(Path(__file__).resolve().parent.parent / "twin" / "scenarios" / "programs" / "test_piece.ngc:8"),
            "T1: no such tool (tools: [2])",
        ),
    ],
)
def test_bad_stock_and_tools_are_one_error_line_naming_the_field(change, field, words):
    data = read_scenario_data("gcode_test_piece")
    data.update(change)
    with pytest.raises(TwinInputError) as err:
        assemble(scenario_from_dict(data))
    assert err.value.field.startswith(field), str(err.value)
    assert words in str(err.value), str(err.value)


def test_choi1999_circle_cutting_a_stock_gives_the_builtin_cutting_circles_force_level():
    """3 mm radial depth left by a 30 mm bore (the built-in circle's depth): the engaged angle
    is the inside arc's 71.0 deg (the built-in's straight-line 66.4 deg), the mean cutting force
    within 20 % of the built-in's over the same second of the circle."""
    stock_run = api.run("gcode_choi1999_circle_stock").result
    builtin = api.run("choi1999_cutting_circle").result
    start = stock_run.t_s[np.argmax(np.abs(stock_run.ref[:, :, 0]).sum(axis=1) > 0)]

    def mean_force(res, t0):
        window = (res.t_s >= t0 + 0.5) & (res.t_s < t0 + 1.5)
        return np.hypot(*res.workpiece_force_N[window, :2].T).mean(), window

    ours, window = mean_force(stock_run, start)
    theirs, _ = mean_force(builtin, 0.0)
    closed = math.degrees(math.acos((30.0**2 - 28.0**2 - 5.0**2) / (2 * 28.0 * 5.0)))
    assert stock_run.program.engagement[window, 0].mean() == pytest.approx(closed, abs=1.0)
    assert stock_run.program.engagement[window, 1] == pytest.approx(3.0)
    assert ours == pytest.approx(theirs, rel=0.2)


def test_the_part_is_recorded_and_plotted(tmp_path):
    """The recording holds the stock and machined outlines, the path coloured by its contour
    error and the colour scale; --plots writes the part from above and the feed profile."""
    from twin.recording import read_back

    run = api.run("gcode_test_piece", duration_s=2.0)
    counts = read_back(run.record(tmp_path / "part.rrd"))
    for entity in ("stock", "machined", "path_by_contour_error", "scale", "scale/labels", "tool"):
        assert counts.get(f"/contour/{entity}", 0) > 0, entity
    assert counts.get("/engagement/angle", 0) > 0
    assert "/contour/actual" not in counts
    written = {p.name for p in run.plots(tmp_path / "plots")}
    assert {"gcode_test_piece_part.png", "gcode_test_piece_feed.png"} <= written
    outlines = run.outcome.outlines
    stock = outlines["stock"][0]
    assert stock[:, 0].min() == pytest.approx(-5.0)
    assert stock[:, 1].max() == pytest.approx(43.0)
    # the program leaves the part's top standing and cuts the pocket (1.5 mm), the slot (1 mm)
    # and the band around the contour (2 mm): the height map as the engagement left it
    program = assemble(scenario_from_dict(read_scenario_data("gcode_test_piece"))).program
    assert program is not None and program.cut is not None
    heights = program.cut.height_map

    def height_mm(x_mm, y_mm):
        i = int((x_mm * 1e-3 - heights.x0_m) / heights.res_m)
        j = int((y_mm * 1e-3 - heights.y0_m) / heights.res_m)
        return heights.heights[i, j] * 1e3

    assert height_mm(35.0, 10.0) == pytest.approx(0.0)  # the part's top
    assert height_mm(25.0, 19.0) == pytest.approx(-1.5)  # the pocket
    assert height_mm(8.0, 20.0) == pytest.approx(-1.0)  # the slot
    assert height_mm(-3.0, 20.0) == pytest.approx(-2.0)  # the contour's band
    assert height_mm(-4.5, -4.5) == pytest.approx(0.0)  # the block's corner, out of the tool's reach


def test_cutter_compensation_takes_the_diameters_of_tools(tmp_path):
    """G41 D1 with ``[[tools]]`` number 1 of 6 mm: an entry move of 2 mm is shorter than the
    3 mm radius, which LinuxCNC refuses (with no diameter the move would be read as written)."""
    program = tmp_path / "entry.ngc"
    program.write_text("G21 F600\nT1 M6\nG0 X0 Y0 Z5\nG41 D1 G1 X2 Y0\nG40 G0 X0\nM2\n")
    data = read_scenario_data("gcode_test_piece")
    data["tools"] = [{"number": 1, "diameter_mm": 6.0, "n_flutes": 2}]
    data["reference"]["file"] = str(program)
    with pytest.raises(TwinInputError) as err:
        assemble(scenario_from_dict(data))
    assert err.value.field.endswith("entry.ngc:4"), str(err.value)
    assert "entry move is not greater than the tool radius" in str(err.value)
