"""The contour error of a part program's moves in their own axes: a plunge, a ramp and a helix
(the machine moves X and Y, the program's Z is planned), per tick against the distance to each
move's programmed geometry computed here, and per line never over the tracking error."""

import math
from pathlib import Path

import numpy as np
import pytest

from twin import api
from twin.metrics import contour_error, tick_contour_error

PROGRAM = """G21 G90 G17 G94
T1 M6
S10000 M3
G0 X6 Y6 Z1
G1 Z-4 F600
G1 X8 F100
G0 Z1
G0 X30 Y20
G1 Z-4 F600
G1 X28 F100
G1 X30
G0 Z1
G0 X10 Y24
G1 Z-4 F600
G0 Z1
G0 X18 Y10
G1 X30 Y10 Z-1 F400
G0 Z1
G0 X12 Y15
G3 X12 Y15 I-1.5 J0 Z-1 F400
G0 Z5
M2
"""
PLUNGES = {9: (30.0, 20.0, 1.0, -4.0), 14: (10.0, 24.0, 1.0, -4.0)}  # line: x, y, z from, z to (mm)
RAMP = (17, (18.0, 10.0, 1.0), (30.0, 10.0, -1.0))
HELIX = (20, (10.5, 15.0), 1.5, 1.0, -1.0)  # line, centre, radius, z from, z to: a full turn from 0 deg


BUNDLED = Path(__file__).resolve().parent.parent / "twin" / "scenarios" / "gcode_pocket_ball_finish.toml"


@pytest.fixture(scope="module")
def cut(tmp_path_factory):
    """The moves cut through the bundled pocket's block (its force pushes the tool off the slow
    ones), on its machine and controllers."""
    folder = tmp_path_factory.mktemp("moves")
    (folder / "moves.ngc").write_text(PROGRAM)
    text = BUNDLED.read_text()
    text = text[: text.index("[[inspect]]")].replace("programs/pocket_ball_finish.ngc", "moves.ngc")
    (folder / "moves.toml").write_text(text)
    return api.run(folder / "moves.toml")


def _point_segment(p, a, b):
    """Distance (mm) from points p (n, 3) to the segment a-b."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    s = np.clip((p - a) @ (b - a) / ((b - a) @ (b - a)), 0.0, 1.0)
    return np.linalg.norm(p - (a + s[:, None] * (b - a)), axis=1)


def _point_helix(p, centre, radius, z0, z1, n=20001):
    """Distance (mm) from points p (n, 3) to a counter-clockwise turn of a helix from angle 0,
    sampled at n points (0.5 µm apart on this one)."""
    t = np.linspace(0.0, 1.0, n)
    helix = np.column_stack(
        [centre[0] + radius * np.cos(2 * math.pi * t), centre[1] + radius * np.sin(2 * math.pi * t), z0 + (z1 - z0) * t]
    )
    return np.array([np.linalg.norm(helix - q, axis=1).min() for q in p])


def _independent(line, p):
    """The distance (mm) of tool points p (n, 3) to program line ``line``'s own geometry."""
    if line in PLUNGES:
        x, y, z0, z1 = PLUNGES[line]
        return _point_segment(p, (x, y, z0), (x, y, z1))
    if line == RAMP[0]:
        return _point_segment(p, RAMP[1], RAMP[2])
    return _point_helix(p, *HELIX[1:])


def test_the_contour_error_of_a_plunge_a_ramp_and_a_helix_is_the_distance_to_each(cut):
    """Per tick, the contour error is the distance of the tool point (measured X, Y; planned Z)
    to the move's own programmed geometry, within the planner's deviation from it (0.5 µm); per
    line, never over the tracking error.  The windowed walk of :func:`contour_error` (XY only)
    loses the tool here: after the rapid that approaches the second plunge at an angle, it
    stays on the rapid's leg and reports millimetres."""
    result, rows = cut.result, {row["line"]: row for row in cut.summary["lines"]}
    for row in rows.values():
        tracking = row["max_tracking_error_um"]
        assert row["max_contour_error_um"] <= math.hypot(tracking["x"], tracking["y"]) + 1e-3, row
    z = result.program.extra_axes["z"]
    tool = np.column_stack([result.table_position_m(), z]) * 1e3
    ours = tick_contour_error(tool * 1e-3, np.column_stack([result.ref[:, :, 0], z])) * 1e3
    for line in (*PLUNGES, RAMP[0], HELIX[0]):
        on = np.flatnonzero(result.program.lines == line)
        on = on[len(on) // 20 : -len(on) // 20]  # the move's own part, its junctions left out
        assert len(on) > 100
        expected = _independent(line, tool[on])
        # the planned helix is within 0.23 µm of the programmed one; the lines, to rounding
        assert ours[on] == pytest.approx(expected, abs=5e-4), line
        assert expected.max() > 0.0005  # the tool is off the path: the check is not of zeros
    assert contour_error(result.table_position_m(), result.ref[:, :, 0]).max() > 1e-3  # the walk: mm


def test_the_tick_search_equals_the_full_search_on_a_path_that_never_comes_back():
    """An open 3-D spiral going down with a square corner, tracked 12 samples behind with
    noise: the distance to every segment of the path, and never over the tracking error."""
    t = np.linspace(0.0, 6.0, 3000)
    r = 0.01 + 0.004 * t
    path = np.stack([r * np.cos(t), r * np.sin(t), -0.001 * t], 1)
    path = np.vstack([path, path[-1] + np.outer(np.linspace(0, 0.02, 300)[1:], [0.0, 1.0, 0.0])])
    rng = np.random.default_rng(4)
    actual = np.vstack([np.repeat(path[:1], 12, axis=0), path[:-12]]) + rng.normal(scale=2e-5, size=path.shape)
    a, b = path[:-1], path[1:]
    s = np.clip(((actual[:, None] - a) * (b - a)).sum(-1) / np.maximum(((b - a) ** 2).sum(1), 1e-300), 0.0, 1.0)
    brute = np.linalg.norm(actual[:, None] - (a + s[..., None] * (b - a)), axis=-1).min(axis=1)
    ours = tick_contour_error(actual, path)
    np.testing.assert_allclose(ours, brute, rtol=0, atol=1e-15)
    assert (ours <= np.linalg.norm(actual - path, axis=1)).all()
