"""The engagement read from the material left inside the tool's envelope, against closed forms
(step-down depths, a re-cut in air, a step-over's arccos(1 - 2a/D), a ball's engaged height)
and against a brute-force reference written here: the exact geometry of every earlier tool
position along the same sampled path, with no height map (step-downs, step-overs, a ramp, a
ball end mill's parallel passes)."""

import math

import numpy as np
import pytest

from twin.gcode.planned import Limits
from twin.gcode.planner import PlannerSettings, plan
from twin.gcode.reader import Reader
from twin.machining.engagement import StockSpec, ToolSpec, engaged_degrees
from twin.machining.program_cut import program_milling

LIMITS = Limits((0.5, 0.5, 0.2), (5.0, 5.0, 2.0), (100.0, 100.0, 200.0))
FLAT = ToolSpec(diameter_mm=6.0, n_flutes=2)
BALL = ToolSpec(diameter_mm=6.0, n_flutes=2, corner_radius_mm=3.0)
BLOCK = StockSpec(corners_mm=((0, -10), (40, 10)), top_mm=0, bottom_mm=-20, resolution_mm=0.02)


def _run(lines, stock=BLOCK, tool=FLAT):
    planned = plan(Reader(["G21 G90 G0 X-10 Y0 Z5", "M3 S10000", *lines, "M5"]).moves(), LIMITS, PlannerSettings())
    table = program_milling(planned, stock, tool, tools=[], seed=0).table
    return planned, table


def _on_line(planned, table, line, x_from=10.0, x_to=25.0):
    """Rows of program line ``line`` (1-based, after the two header lines) with the tool
    between x_from and x_to (mm): the steady part of a pass."""
    x = planned.position[:, 0] * 1e3
    return table[(planned.line == line + 2) & (x > x_from) & (x < x_to)]


def _passes(depths):
    """One slot along y = 0 cut at each depth in turn, left to right, back over the top."""
    lines = []
    for z in depths:
        lines += [f"G1 Z{z} F300", "G1 X30 F600", "G0 Z5", "G0 X-10"]
    return lines


def test_step_downs_engage_the_material_each_pass_leaves_not_the_walls():
    """The issue's case: three passes down one slot at Z -2, -4 and -22 in a 20 mm block engage
    2, 2 and 16 mm (the block's bottom at -20), each over the whole leading half."""
    planned, table = _run(_passes([-2, -4, -22]))
    for k, depth in enumerate([2.0, 2.0, 16.0]):
        rows = _on_line(planned, table, 4 * k + 2)
        assert len(rows) > 100
        assert engaged_degrees(rows) == pytest.approx(180.0, abs=1.0)
        assert rows[:, 2] == pytest.approx(depth, abs=1e-9)
        assert rows[:, 6] == pytest.approx(depth, abs=1e-9)


def test_a_recut_in_air_and_a_pass_below_the_stock_engage_nothing():
    planned, table = _run(_passes([-3, -3, -25, -26]))
    for k in (1, 3):  # the same pass again; a pass below the one that cut through the bottom
        rows = _on_line(planned, table, 4 * k + 2)
        assert len(rows) > 100
        assert not rows[:, :7].any()


@pytest.mark.parametrize("step_mm", [1.0, 3.0, 4.5])
def test_a_step_over_engages_arccos_of_one_minus_2a_over_d_at_its_own_depth(step_mm):
    """A second pass beside the first at y = step: the material left is a_e = step (down
    milling on that side, the tool turning M3): the arc ends at 180 deg and spans
    arccos(1 - 2 a_e / D), at the pass's own 2 mm."""
    lines = [*_passes([-2]), f"G0 Y-{step_mm}", "G1 Z-2 F300", "G1 X30 F600", "G0 Z5"]
    planned, table = _run(lines)
    rows = _on_line(planned, table, 7)
    closed = math.degrees(math.acos(1 - 2 * step_mm / 6.0))
    assert engaged_degrees(rows).mean() == pytest.approx(closed, abs=1.0)
    assert np.degrees(rows[:, 1]) == pytest.approx(180.0, abs=1e-9)
    assert rows[:, 2] == pytest.approx(2.0, abs=1e-9)


def test_a_ball_end_mill_slotting_engages_its_depth_at_every_angle():
    """A ball of radius 3 mm at 1.5 mm deep: the edge meets material from its tip to the top at
    every angle of the leading half (the height it engages is the depth, a closed form of the
    ball: its radius there is sqrt(2 R d - d^2) = 2.60 mm, inside the cutter's 3 mm)."""
    planned, table = _run(["G1 Z-1.5 F300", "G1 X30 F600"], tool=BALL)
    rows = _on_line(planned, table, 2)
    assert engaged_degrees(rows) == pytest.approx(180.0, abs=1.0)
    assert rows[:, 6] == pytest.approx(1.5, rel=0.01)
    assert rows[:, 2] == pytest.approx(1.5, rel=0.01)


# --- the brute-force reference ---------------------------------------------------------------


def _bottom(rho, r, rc):
    """Height of a tool's bottom surface above its tip at radius rho (flat inside r - rc, the
    corner's arc outside it); inf beyond r (the tool is not there)."""
    out = np.clip(rho - (r - rc), 0.0, None)
    with np.errstate(invalid="ignore"):
        return np.where(rho <= r, rc - np.sqrt(np.clip(rc * rc - out * out, 0.0, None)), np.inf)


def reference_row(path, velocity, k, r, rc, stock, n_corner=200):
    """Extents (m) of the edge at 1-degree angles of the leading half at sample k, from every
    earlier sample's tool solid: material at a point of the tool's surface is there if it is
    inside the stock's box and below every earlier tool's bottom surface over it."""
    (x0, y0), (x1, y1) = stock.corners_mm
    x0, y0, x1, y1 = (v * 1e-3 for v in (x0, y0, x1, y1))
    top, bottom = stock.top_mm * 1e-3, stock.bottom_mm * 1e-3
    c, earlier = path[k], path[:k]
    # a tool over 2r away covers no point of this tool's surface: those are left out, and every
    # fourth sample kept (0.04 mm apart at F600: their discs' scallops are 1e-4 mm deep)
    earlier = earlier[np.hypot(earlier[:, 0] - c[0], earlier[:, 1] - c[1]) < 2.0 * r + 1e-9][::4]
    u = velocity[k, :2] / np.hypot(*velocity[k, :2])
    phi = np.radians(np.arange(181.0))
    normal = np.stack([np.sin(phi) * u[0] - np.cos(phi) * u[1], np.sin(phi) * u[1] + np.cos(phi) * u[0]], axis=1)

    def ceiling(rho):
        """Height (m) of the material over the surface point at radius rho at each angle."""
        p = c[:2] + rho * normal
        d = np.hypot(p[:, None, 0] - earlier[None, :, 0], p[:, None, 1] - earlier[None, :, 1])
        cut = np.min(earlier[None, :, 2] + _bottom(d, r, rc), axis=1, initial=np.inf)
        inside = (p[:, 0] > x0) & (p[:, 0] < x1) & (p[:, 1] > y0) & (p[:, 1] < y1)
        return np.where(inside, np.minimum(cut, top), -np.inf)

    extent = np.clip(ceiling(r) - max(c[2] + rc, bottom), 0.0, None)
    if rc > 0:
        dz = rc / n_corner
        for q in range(n_corner):
            z = (q + 0.5) * dz
            rho = r - rc + math.sqrt(rc * rc - (rc - z) ** 2)
            if c[2] + z > bottom:
                extent += np.where(ceiling(rho) > c[2] + z, dz, 0.0)
    return extent


def _arcs(extent):
    """(entry deg, exit deg, mean extent mm) of each engaged run of angles."""
    on = extent > 1e-9
    edges = np.flatnonzero(np.diff(np.concatenate([[0], on.astype(int), [0]])))
    return [(a, b - 1, extent[a:b].mean() * 1e3) for a, b in zip(edges[::2], edges[1::2])]


@pytest.mark.parametrize(
    "name, lines, tool, check_lines",
    [
        (
            "flat: a slot, a step-over, a deeper pass across both",
            [*_passes([-2]), "G0 Y2.5", "G1 Z-2 F300", "G1 X30 F600", "G0 Z5", "G0 X-10 Y1", "G1 Z-3.5", "G1 X30"],
            FLAT,
            (2, 7, 11),
        ),
        (
            "flat: a ramp down into a slot cut before it",
            [*_passes([-1]), "G1 Z-1 F300", "G1 X30 Z-4 F600"],
            FLAT,
            (2, 6),
        ),
        (
            "ball: two parallel passes and one across a flat step",
            [*_passes([-2]), "G0 Y2", "G1 Z-2 F300", "G1 X30 F600", "G0 Z5", "G0 X-10 Y1", "G1 Z-2.5", "G1 X30"],
            BALL,
            (7, 11),
        ),
    ],
)
def test_engagement_matches_a_brute_force_reference_to_1_degree_and_1_percent(name, lines, tool, check_lines):
    planned, table = _run(lines, tool=tool)
    r, rc = tool.diameter_mm / 2e3, tool.corner_radius_mm * 1e-3
    x = planned.position[:, 0] * 1e3
    checked = 0
    for line in check_lines:
        on = np.flatnonzero((planned.line == line + 2) & (x > 8.0) & (x < 28.0))
        for k in on[:: max(len(on) // 3, 1)]:
            arcs = _arcs(reference_row(planned.position, planned.velocity, k, r, rc, BLOCK))
            row = table[k]
            assert len(arcs) <= 2, (name, k, arcs)
            largest = max((a[2] for a in arcs), default=0.0)
            for n_arc, (entry, exit_, mean) in enumerate(arcs):
                st, ex, depth = row[3 * n_arc : 3 * n_arc + 3]
                assert math.degrees(st) == pytest.approx(entry, abs=1.0), (name, k, arcs, row)
                assert math.degrees(ex) == pytest.approx(exit_, abs=1.0), (name, k, arcs, row)
                assert depth == pytest.approx(mean, abs=0.01 * largest), (name, k, arcs, row)
            checked += 1
    assert checked >= 3 * len(check_lines)


# --- a helix's depth and a slot's end (issue 45) ---------------------------------------------


def _previous_turn_depth(path, velocity, k, r, radius, top, tol=2e-7):
    """The material (m) over the tip at sample k on a counter-clockwise helix of ``radius`` (m)
    where the flat tool's edge faces out of the helix (180 degrees, right of the feed): the
    stock's top or the lowest tip among the samples over a quarter turn back (the previous
    turns: the tool's own sweep now only grazes that place) whose disc covers the place within
    ``tol`` (the samples' spacing on the circle), from geometry alone."""
    c = path[k]
    travelled = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(path[: k + 1, :2], axis=0).T))])
    earlier = path[: k + 1][travelled[k] - travelled > 0.5 * math.pi * radius]
    u = velocity[k, :2] / np.hypot(*velocity[k, :2])
    p = c[:2] + r * np.array([u[1], -u[0]])
    d = np.hypot(p[0] - earlier[:, 0], p[1] - earlier[:, 1])
    return float(min(np.min(earlier[:, 2][d <= r + tol], initial=np.inf), top) - c[2])


def test_a_helical_entry_engages_one_pitch_within_1_percent():
    """A flat 6 mm tool down a helix of radius 2.5 mm and 1 mm pitch into the block's top: on
    the steady turns (the second on) the edge facing out of the helix meets the material the
    previous turn left, one pitch above the tip, measured from the tip where the read is (a
    little further down the helix), not from the tip now (2.3 % low on average before, 2.6 %
    at worst).  What is left is the cells': the previous turn's wall there is the envelope of
    its discs, and a cell's centre up to half a cell inside it was cut a little later (0.7 %
    on average at 0.01 mm, 1.0 % at worst)."""
    stock = StockSpec(corners_mm=((13.5, -6.5), (26.5, 6.5)), top_mm=0, bottom_mm=-20, resolution_mm=0.01)
    turns = [f"G3 X22.5 Y0 I-2.5 J0 Z{-z} F300" for z in range(1, 4)]
    planned, table = _run(["G0 X22.5 Y0", "G1 Z0 F300", *turns, "G0 Z5"], stock=stock)
    r, top = FLAT.diameter_mm / 2e3, stock.top_mm * 1e-3
    ratios = []
    for line in (4, 5):  # the second and third turns, clear of their ends
        on = np.flatnonzero(planned.line == line + 2)
        for k in on[len(on) // 10 : -len(on) // 10 : 100]:
            expected = _previous_turn_depth(planned.position, planned.velocity, k, r, 2.5e-3, top) * 1e3
            assert expected == pytest.approx(1.0, abs=0.005)  # the reference is the pitch
            ratios.append(table[k, 6] / expected)
    assert len(ratios) >= 40
    assert np.mean(ratios) == pytest.approx(1.0, abs=0.01)
    assert np.array(ratios) == pytest.approx(1.0, abs=0.015)


def test_a_helix_into_the_top_engages_as_deep_as_its_tip_is_now():
    """The first turn of the same helix goes down into the block's flat top: the material ahead
    does not slope, so the deepest edge (facing out of the helix, into material no turn cut yet)
    engages from the top to the tip now, within 1 % (reading the depth from the tip ahead, as a
    steady turn's read does, gave the depth the tool will have there: 7 % deep at the end of the
    pocket's first turn).  The two reads ahead tell the two apart."""
    stock = StockSpec(corners_mm=((13.5, -6.5), (26.5, 6.5)), top_mm=0, bottom_mm=-20, resolution_mm=0.01)
    turns = [f"G3 X22.5 Y0 I-2.5 J0 Z{-z} F300" for z in range(1, 4)]
    planned, table = _run(["G0 X22.5 Y0", "G1 Z0 F300", *turns, "G0 Z5"], stock=stock)
    on = np.flatnonzero(planned.line == 3 + 2)  # the first turn, clear of its end (where the
    on = on[: -len(on) // 20]  # read ahead meets the turn's own start, cut shallower)
    deep = on[planned.position[on, 2] < -0.2e-3]  # in the material by over 0.2 mm
    assert len(deep) > 50
    np.testing.assert_allclose(table[deep, 6], -planned.position[deep, 2] * 1e3, rtol=0.01)


def test_a_slot_engages_its_half_circle_up_to_the_stop():
    """A full slot's engaged arc stays within 1 degree of 180 up to the last sample before the
    tool stops in the material: the read ahead goes straight on past the stop (the material is
    still there), not back inside the tool's own cut (178.3 deg at the end before)."""
    planned, table = _run(["G1 Z-2 F300", "G1 X30 F600", "G0 Z5"])
    on = np.flatnonzero((planned.line == 2 + 2) & (planned.position[:, 0] * 1e3 > 10.0))
    moving = planned.position[on, 0] * 1e3 < 30.0 - 1e-6  # at the stop the tool cuts nothing new
    assert np.hypot(*planned.velocity[on[moving][-1], :2]) > 0.0
    rows = table[on[moving]]
    assert len(rows) > 100
    assert engaged_degrees(rows) == pytest.approx(180.0, abs=1.0)
