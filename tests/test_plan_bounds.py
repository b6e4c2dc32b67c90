"""Bounded plans (issue 46): a program's motion time bounded from below from its moves alone,
before planning, so that one too long is refused at once, whatever its feed and the limits; a
stretch planned at rest never takes forever."""

import time

import pytest
from typer.testing import CliRunner

from twin.cli import app
from twin.gcode.planned import Limits, PlanningError
from twin.gcode.planner import PlannerSettings, plan
from twin.gcode.reader import Reader

LIMITS = Limits((0.5, 0.5, 0.2), (5.0, 5.0, 2.0), (100.0, 100.0, 200.0))
HELD = "the program runs longer than the 2000 s of motion a reference held whole may hold"


@pytest.mark.parametrize("as_list", [True, False])
def test_a_slow_move_is_refused_before_it_is_planned(as_list):
    """1 m at 0.01 mm/min (69 days): refused at its line, with its time, in a list of moves
    (counted first) and as a stream (counted as it is read)."""
    moves = Reader(["G21 G90 G0 X0 Y0", "G1 X1000 F0.01", "G1 X0"]).moves()
    t0 = time.perf_counter()
    with pytest.raises(PlanningError) as caught:
        plan(list(moves) if as_list else moves, LIMITS, PlannerSettings())
    assert time.perf_counter() - t0 < 5.0
    assert str(caught.value).startswith(f"line 2: {HELD} (split it, or run it in a scenario without a stock")
    assert "its moves to this line take at least 6000000 s (1666.7 h)" in str(caught.value)


def test_the_bound_counts_the_axis_limits_the_override_and_dwells():
    """A rapid at the axis limit, a feed over it, a dwell, the override: each counted as the
    planner bounds it, the line named where the sum passes 2000 s."""
    slow = Limits((0.001, 0.001, 0.001), (5.0, 5.0, 2.0), (100.0, 100.0, 200.0))
    program = ["G21 G90 G0 X0 Y0", "G0 X1000", "G1 X0 F60000", "G4 P1", "G1 X1 F1"]
    with pytest.raises(PlanningError, match=r"^line 4: .* at least 2001 s "):
        plan(list(Reader(program).moves()), slow, PlannerSettings())
    fast = ["G21 G90 G0 X0 Y0", "G1 X1000 F1"]  # 60 000 s at the feed, 6 000 s at 10 times it
    with pytest.raises(PlanningError, match=r"^line 2: .* at least 6000 s "):
        plan(list(Reader(fast).moves()), LIMITS, PlannerSettings(feed_override=10.0))


def test_a_program_just_within_its_limit_is_planned():
    """The bound is a lower one: a move of 1900 s (the filter's and the ends' rest added) plans."""
    p = plan(list(Reader(["G21 G90 G0 X0 Y0", "G1 X190 F6"]).moves()), LIMITS, PlannerSettings())
    assert 1900.0 < p.cycle_time_s < 1902.0


def test_the_cli_refuses_a_program_longer_than_it_plans_at_once(tmp_path):
    slow = tmp_path / "slow.ngc"
    slow.write_text("G21 G90\nG1 X1000 F0.01\nM2\n")
    t0 = time.perf_counter()
    out = CliRunner().invoke(app, ["gcode", str(slow), "--machine", "linear_motor_xy"])
    assert time.perf_counter() - t0 < 5.0
    assert out.exit_code == 2, out.output
    lines = out.output.strip().splitlines()
    assert lines == [
        f"error: file = {str(slow)!r}: line 2: {HELD} (split it, or run it in a scenario without a stock, whose "
        "reference streams it): its moves to this line take at least 6000000 s (1666.7 h) at their feeds and the "
        "axes' velocity limits"
    ]


def test_a_run_refuses_a_program_over_ten_hours_at_the_line_that_passes_them(tmp_path):
    """600 s a line (100 mm at 10 mm/min): the 61st move passes 10 hours; nothing is planned."""
    zigzag = tmp_path / "zigzag.ngc"
    zigzag.write_text("G21 G90 G61\nG1 F10\n" + "".join(f"G1 X{100 * (i % 2 == 0)}\n" for i in range(20_000)))
    t0 = time.perf_counter()
    out = CliRunner().invoke(app, ["run", "gcode_choi1999_circle", "--set", f"reference.file={zigzag}"])
    assert time.perf_counter() - t0 < 5.0
    assert out.exit_code == 2, out.output
    assert out.output.strip().splitlines()[-1] == (
        f"error: reference.file = {str(zigzag)!r}: line 63: the program runs longer than the 10 hours of motion a "
        "run may plan: its moves to this line take at least 36600 s (10.2 h) at their feeds and the axes' velocity "
        "limits"
    )


def test_a_stretch_slowed_to_rest_is_refused_before_it_is_sampled(monkeypatch):
    """Repairs that multiply a place's speed limit down to nothing (0 m/s over a grid interval:
    1e300 s of motion, once a MemoryError) end in one planning error naming the line."""
    import twin.gcode.planner as planner

    def to_rest(grid, s_lo, s_hi, speed, acceleration):
        near = (grid.s >= s_lo) & (grid.s <= s_hi)
        grid.vmax[near] *= 0.0

    monkeypatch.setattr(planner._Grid, "lower", to_rest)
    fuzzed = Limits((0.1, 0.1, 0.05), (1.5, 1.5, 1.0), (1500.0, 1500.0, 1000.0))  # the issue's: no filter
    program = ["G21 G90 G17 G0 X0 Y0 Z0", "G1 X1 F400", "G1 X1.001 Z-0.001", "G1 X2 Z-0.001"]
    t0 = time.perf_counter()
    with pytest.raises(
        PlanningError,
        match=r"^line [234]: the planned speed falls to 0 m/s here .* more than 36000 s of motion between two cruises, "
        "longer than a program may run$",
    ):
        plan(Reader(program).moves(), fuzzed, PlannerSettings())
    assert time.perf_counter() - t0 < 5.0


def _arcs():
    """Circles, helices and spirals of many turns, whole and split."""
    from twin.gcode.planner import _programmed

    out = []
    for code, z, end_x, turns in (("G2", 0, 0, 7), ("G3", -10, 0, 20), ("G2", 0.01, 0, 20), ("G3", 0, 0.001, 7)):
        lines = ["G21 G90 G17 G0 X0 Y0 Z0", f"{code} X{end_x} Y0 Z{z} I-5 J0 P{turns} F600"]
        seg = list(_programmed(Reader(lines).moves(), PlannerSettings(), None))[-1]
        out += [seg, *seg.split(0.37 * seg.length)]
    return out


@pytest.mark.parametrize("seg", _arcs())
def test_an_arcs_distance_looks_at_the_turns_near_a_point_only_and_finds_the_nearest(seg):
    """The distance to a many-turn arc is the smallest over every turn (the brute force: each
    turn's Newton refinement from the point's angle), points near it and 1 mm off."""
    import math

    import numpy as np

    from twin.gcode.path import SPIRAL_NEWTON_STEPS

    rng = np.random.default_rng(1)
    s = rng.uniform(0.0, seg.length, 400)
    p = seg.points(s) + rng.normal(size=(400, 3)) * np.repeat([1e-7, 1e-5, 1e-4, 1e-3], 100)[:, None]
    rel = p - seg.center
    angle = np.mod(np.arctan2(rel @ seg.v, rel @ seg.u), 2 * math.pi)
    k, h = (seg.radius_end - seg.radius) / seg.sweep, seg.rise / seg.sweep
    brute = np.minimum(np.linalg.norm(p - seg.start, axis=1), np.linalg.norm(p - seg.end, axis=1))
    for turn in range(math.ceil(seg.sweep / (2 * math.pi)) + 1):
        phi = angle + 2 * math.pi * turn
        for _ in range(SPIRAL_NEWTON_STEPS + 1):
            c, si = np.cos(phi)[:, None], np.sin(phi)[:, None]
            r = (seg.radius + k * phi)[:, None]
            point = seg.center + r * (c * seg.u + si * seg.v) + (h * phi)[:, None] * seg.normal
            d1 = k * (c * seg.u + si * seg.v) + r * (-si * seg.u + c * seg.v) + h * seg.normal
            d2 = 2 * k * (-si * seg.u + c * seg.v) - r * (c * seg.u + si * seg.v)
            grad = np.einsum("ij,ij->i", point - p, d1)
            curv = np.einsum("ij,ij->i", d1, d1) + np.einsum("ij,ij->i", point - p, d2)
            phi = np.clip(phi - grad / np.where(curv > 0, curv, 1.0), 0.0, seg.sweep)
        inside = angle + 2 * math.pi * turn <= seg.sweep
        brute[inside] = np.minimum(brute[inside], np.linalg.norm(point - p, axis=1)[inside])
    assert np.allclose(seg.distance(p), brute, rtol=0.0, atol=1e-12)


def test_a_thousand_turn_arcs_distance_takes_time_linear_in_its_points():
    """A pass over every point for each turn made 300 turns 25 s; a few per point now."""
    import numpy as np

    from twin.gcode.planner import _programmed

    lines = ["G21 G90 G17 G0 X1 Y0 Z0", "G2 X1 Y0 Z-20 I-1 J0 P1000 F600"]
    seg = list(_programmed(Reader(lines).moves(), PlannerSettings(), None))[-1]
    p = seg.points(np.linspace(0.0, seg.length, 50_000)) + 1e-6
    t0 = time.perf_counter()
    assert seg.distance(p).max() < 2e-6
    assert time.perf_counter() - t0 < 5.0


def test_a_thousand_turn_arc_plans_in_seconds_and_planning_outruns_the_motion():
    """Issue 46: a 1 000-turn arc (628 s of motion) planned (counted, in bounded memory) in
    seconds; planning at least 100 times faster than the motion at the issue's slow limits on
    a CAM-like program (CPU time: the machine is shared)."""
    from twin.bench import SLOW_LIMITS, cam_program
    from twin.gcode.planner import hold_or_count
    from twin.machines import build

    machine = PlannerSettings().limits(build("linear_motor_xy").motion_limits)
    hold_or_count(Reader(["G21 G0 X0", "G1 X1 F100", "G2 X1 Y0 I1 J0"]).moves(), machine, None, most=0)  # compiled
    arc = ["G21 G90 G17 G0 X1 Y0 Z0", "G2 X1 Y0 Z-20 I-1 J0 P1000 F600"]
    t0 = time.process_time()
    _held, facts, samples = hold_or_count(Reader(arc).moves(), machine, None, most=0)
    assert time.process_time() - t0 < 10.0
    assert samples * 1e-3 == pytest.approx(1000 * 2 * 3.141592653589793 * 1e-3 / 0.01, rel=0.01)
    t0 = time.process_time()
    _held, facts, samples = hold_or_count(Reader(list(cam_program(300))).moves(), Limits(*SLOW_LIMITS), None, most=0)
    assert samples * 1e-3 / (time.process_time() - t0) >= 100.0
    assert not facts.violations


def test_a_copy_of_a_segment_works_its_limits_out_again():
    """What the planner keeps of a segment (``planned``) is not carried to its pieces."""
    from twin.gcode.planner import _programmed, _segment_speed_limit

    seg = list(_programmed(Reader(["G21 G90 G0 X0 Y0", "G1 X10 Y10 F600"]).moves(), PlannerSettings(), None))[-1]
    assert _segment_speed_limit(seg, LIMITS, 1.0, 0.05) == pytest.approx(0.01)
    first, second = seg.split(0.004)
    assert first.planned == {} and second.planned == {}
    assert first.tangent(True) == pytest.approx(seg.tangent(True))
