"""Bounded plans (issue 46): a program's motion time bounded from below from its moves alone,
before planning, so that one too long is refused at once, whatever its feed and the limits; a
stretch planned at rest never takes forever."""

import time

import pytest
from typer.testing import CliRunner

from twin.cli import app
from twin.gcode.planner import Limits, PlannerSettings, PlanningError, plan
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
    assert str(caught.value).startswith(f"line 2: {HELD} (run it without a stock")
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
        f"error: file = {str(slow)!r}: line 2: {HELD} (run it without a stock, which streams it, or split it): its "
        "moves to this line take at least 6000000 s (1666.7 h) at their feeds and the axes' velocity limits"
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
    with pytest.raises(PlanningError, match=r"^line [234]: the planned speed falls to 0 m/s here .* more than 3600 s"):
        plan(Reader(program).moves(), fuzzed, PlannerSettings())
    assert time.perf_counter() - t0 < 5.0
