"""The interpolator against closed forms: a straight move's time-optimal time, a circle's
speed limits, every axis within its limits on the sampled reference, the path within the
tolerance; and the G-code reference in scenarios."""

import json
import math
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from twin import api
from twin.cli import app
from twin.gcode.planner import MAX_SAMPLES, Limits, PlannerSettings, PlanningError, plan
from twin.gcode.reader import Reader, Settings, read_program
from twin.gcode.report import max_path_deviation_m
from twin.machines import build

ROOT = Path(__file__).resolve().parent.parent
PROGRAMS = ROOT / "twin" / "scenarios" / "programs"
FIXTURES = ROOT / "tests" / "fixtures" / "gcode"
LIMITS = Limits((0.5, 0.5, 0.2), (5.0, 5.0, 2.0), (100.0, 100.0, 200.0))


def _plan(lines, limits=LIMITS, **settings):
    return plan(Reader(lines).moves(), limits, PlannerSettings(**settings))


def _jerk(p):
    return np.diff(p.acceleration, axis=0, prepend=0.0, append=0.0) / p.period_s


def test_a_long_straight_move_takes_the_time_optimal_time():
    """L/v + v/a + a/j when all three limits are reached (rest to rest)."""
    for length_mm, feed in ((300.0, 30000.0), (500.0, 24000.0)):
        p = _plan(["G21 G90 G0 X0 Y0", f"G1 X{length_mm} F{feed}"])
        v, a, j = feed / 60e3, 5.0, 100.0
        closed = length_mm * 1e-3 / v + v / a + a / j
        assert p.cycle_time_s == pytest.approx(closed, rel=0.01)
        top = p.max_abs()["x"]
        assert top["velocity_m_per_s"] == pytest.approx(v, rel=1e-3)
        assert top["acceleration_m_per_s2"] == pytest.approx(a, rel=1e-3)
        assert top["jerk_m_per_s3"] == pytest.approx(j, rel=1e-3)
        assert p.position[-1, 0] == pytest.approx(length_mm * 1e-3, abs=1e-12)


@pytest.mark.parametrize(
    "radius_mm, feed, binding",
    [(10.0, 6000.0, "feed"), (2.0, 30000.0, "jerk"), (200.0, 30000.0, "velocity")],
)
def test_a_circle_runs_at_min_of_feed_centripetal_and_jerk_speeds(radius_mm, feed, binding):
    """v = min(F, sqrt(a R), (j R^2)^(1/3)) (and the axis velocity), with a tolerance wide
    enough that the filter's contour limit does not bind; the filter (length T = a/j) turns
    the circle into one of radius R sinc(w T/2), w = v/R, so the sampled speed is v sinc."""
    r = radius_mm * 1e-3
    limits = Limits((0.3, 0.3, 0.2), (5.0, 5.0, 2.0), (100.0, 100.0, 200.0))
    p = _plan(
        ["G21 G90 G0 X0 Y0", f"G3 X0 Y0 I{-radius_mm} J0 F{feed}", f"G3 X0 Y0 I{-radius_mm} J0"],
        limits,
        tolerance_mm=5.0,
    )
    candidates = {
        "feed": feed / 60e3,
        "centripetal": math.sqrt(5.0 * r),
        "jerk": (100.0 * r * r) ** (1 / 3),
        "velocity": 0.3,
    }
    planned = min(candidates.values())
    assert min(candidates, key=candidates.get) == binding
    half_turn = planned / r * 0.05 / 2
    expected = planned * math.sin(half_turn) / half_turn
    speed = np.hypot(p.velocity[:, 0], p.velocity[:, 1])
    middle = speed[len(speed) // 3 : 2 * len(speed) // 3]  # the second turn, away from start and stop
    assert middle.max() == pytest.approx(expected, rel=2e-3)
    assert middle.min() == pytest.approx(expected, rel=2e-3)


def _programs():
    return [(PROGRAMS / f"{n}.ngc", Settings()) for n in ("seed004_circle", "test_piece")] + [
        (FIXTURES / f"{n}.ngc", Settings(tool_lengths_mm={1: 5.08})) for n in ("basic", "planes", "offsets")
    ]


@pytest.mark.parametrize("machine", ["linear_motor_xy", "googol_xy", "sabau_xy"])
def test_no_axis_exceeds_its_limits_and_the_path_stays_within_the_tolerance(machine):
    settings = PlannerSettings()
    limits = settings.limits(build(machine).motion_limits)
    for program, reader_settings in _programs():
        p = plan(read_program(program, reader_settings), limits, settings)
        jerk = np.abs(_jerk(p)).max(axis=0)
        for i in range(3):
            assert np.abs(p.velocity[:, i]).max() <= limits.velocity_m_per_s[i] * 1.001, (program.name, i)
            assert np.abs(p.acceleration[:, i]).max() <= limits.acceleration_m_per_s2[i] * 1.001, (program.name, i)
            assert jerk[i] <= limits.jerk_m_per_s3[i] * 1.001, (program.name, i)
        assert max_path_deviation_m(p) <= p.tolerance_m * 1.001, program.name
        assert p.cycle_time_s >= p.feed_only_time_s  # the limits can only add time


def test_feed_only_time_dwell_and_rapids():
    p = _plan(["G21 G90 G0 X0 Y0", "G1 X60 F600", "G4 P0.5", "G0 X160 Y0"], tolerance_mm=0.01)
    # 60 mm at 10 mm/s, a 0.5 s dwell, 100 mm of rapid at the x axis's 0.5 m/s
    assert p.feed_only_time_s == pytest.approx(6.0 + 0.5 + 0.2)
    held = np.abs(p.position[:, 0] - 0.06) < 1e-12
    assert held.sum() * p.period_s >= 0.5  # the dwell holds the position
    assert p.max_abs()["x"]["velocity_m_per_s"] == pytest.approx(0.5, rel=1e-3)  # the rapid at the axis limit
    diagonal = _plan(["G21 G90 G0 X0 Y0 Z0", "G0 X100 Y100 Z100"])
    top = diagonal.max_abs()
    assert top["z"]["velocity_m_per_s"] == pytest.approx(0.2, rel=1e-3)  # z limits the diagonal rapid
    assert top["x"]["velocity_m_per_s"] == pytest.approx(0.2, rel=1e-3)


def test_feed_override_and_tolerance_from_the_program():
    slow = _plan(["G21 G90 G0 X0 Y0", "G1 X100 F6000"], feed_override=0.5)
    assert slow.max_abs()["x"]["velocity_m_per_s"] == pytest.approx(0.05, rel=1e-3)
    assert _plan(["G21 G64 P0.02", "G0 X0 Y0", "G1 X1 F100"]).tolerance_m == pytest.approx(2e-5)
    assert _plan(["G21 G64 P0.02", "G0 X0 Y0", "G1 X1 F100"], tolerance_mm=0.05).tolerance_m == pytest.approx(5e-5)


def test_a_program_too_long_to_hold_is_refused_with_its_time():
    with pytest.raises(PlanningError, match="longer than"):
        _plan(["G21 G90 G0 X0 Y0", "G1 X5000 F1"])  # 5 m at 1 mm/min: 5000 min
    assert MAX_SAMPLES * 1e-3 < 5000 * 60


def test_the_gcode_circle_gives_the_builtin_circles_results_when_the_limits_are_not_active():
    """Seed 004's cutting circle as G-code, with limits far above what the circle needs (the
    filter a/j then one sample: none): over the same second of the circle, the same tracking
    errors and cutting forces as the built-in circle reference (which starts at full feed)."""
    fast = {
        "planner.acceleration_m_per_s2": {"x": 1e3, "y": 1e3, "z": 1e3},
        "planner.jerk_m_per_s3": {"x": 1e6, "y": 1e6, "z": 1e6},
        "planner.velocity_m_per_s": {"x": 10.0, "y": 10.0, "z": 10.0},
    }
    program = api.run("gcode_seed004_circle", **fast).result
    builtin = api.run("seed004_cutting_circle").result
    start = program.t_s[np.argmax(np.abs(program.ref[:, :, 0]).sum(axis=1) > 0)]  # after the plunge

    def second_of_circle(res, t0):
        """RMS tracking error (m) and RMS cutting force (N) per axis, 0.5 s to 1.5 s into the circle."""
        window = (res.t_s >= t0 + 0.5) & (res.t_s < t0 + 1.5)
        rms = np.sqrt((res.error_m()[window] ** 2).mean(axis=0))
        return rms, np.sqrt((res.workpiece_force_N[window, :2] ** 2).mean(axis=0))

    program_error, program_force = second_of_circle(program, start)
    builtin_error, builtin_force = second_of_circle(builtin, 0.0)
    assert program_error == pytest.approx(builtin_error, rel=0.05)
    assert program_force == pytest.approx(builtin_force, rel=0.05)
    assert builtin_error.min() > 5e-6  # the cutting force's errors, not noise


def test_bundled_programs_run_to_their_end_with_z_recorded():
    run = api.run("gcode_test_piece", duration_s=0.3)
    frame = run.to_pandas()
    assert "reference/z (mm)" in frame.columns
    assert frame["reference/z (mm)"].max() == pytest.approx(2.0, abs=0.05)  # the rapid up to Z2
    whole = api.run("gcode_seed004_circle")
    planned = api.program(PROGRAMS / "seed004_circle.ngc", machine="linear_motor_xy", **{"planner.tolerance_mm": 0.005})
    assert whole.summary["completed_ticks"] == pytest.approx(planned["planned"]["cycle_time_s"] / 5e-4, abs=2)
    import twin

    assert twin.program is api.program  # the public name (twin.gcode is the package)


def test_twin_gcode_prints_moves_and_the_plan(tmp_path):
    runner = CliRunner()
    out = runner.invoke(app, ["gcode", str(FIXTURES / "planes.ngc"), "--json"])
    assert out.exit_code == 0, out.output
    moves = json.loads(out.output)["moves"]
    assert moves[1] == {
        "line": 5,
        "kind": "arc",
        "end_mm": [10.0, 0.0, 0.0],
        "feed_mm_per_min": 600.0,
        "spindle": "off",
        "spindle_rpm": 0.0,
        "coolant": "off",
        "plane": "zx",
        "center_mm": [0.0, 5.0],
        "turns": -1,
    }
    piece = str(PROGRAMS / "test_piece.ngc")
    out = runner.invoke(app, ["gcode", piece, "--machine", "googol_xy", "--json", "--set", "planner.feed_override=0.5"])
    planned = json.loads(out.output)["planned"]
    assert planned["limits"]["x"]["velocity_m_per_s"] == 0.25
    assert planned["cycle_time_s"] > planned["feed_only_time_s"] > 0
    assert planned["max_path_deviation_mm"] <= 0.01 * 1.001


@pytest.mark.parametrize(
    "args, words",
    [
        (["{bad}"], "bad.ngc:3 = 'G41 X1 Y1': cutter radius compensation (G41) is not supported"),
        (["{good}", "--machine", "mill"], "machine = 'mill': unknown machine"),
        (["{good}", "--machine", "googol_xy", "--set", "planner.tolerance_mm=-1"], "planner.tolerance_mm = -1"),
        (["{good}", "--set", "spindle=3"], "--set spindle = 3: give planner.KEY or reference.KEY"),
        (["{good}", "--set", "planner.jerk_m_per_s3={{ w = 3.0 }}"], "'w' is not an axis"),
        (["{missing}"], "file = "),
    ],
)
def test_twin_gcode_bad_input_is_one_line_and_exit_2(tmp_path, args, words):
    bad = tmp_path / "bad.ngc"
    bad.write_text("G21\nG0 X0 Y0\nG41 X1 Y1\nG1 X2 F100\n")
    good = tmp_path / "good.ngc"
    good.write_text("G21 G0 X0 Y0\nG1 X1 F100\n")
    argv = [a.format(bad=bad, good=good, missing=tmp_path / "none.ngc") for a in args]
    out = CliRunner().invoke(app, ["gcode", *argv])
    assert out.exit_code == 2, out.output
    lines = out.output.strip().splitlines()
    assert words in lines[-1] and lines[-1].startswith("error: "), out.output
    assert sum(line.startswith("error") for line in lines) == 1


def test_a_dwell_too_long_to_hold_is_refused():
    with pytest.raises(PlanningError, match="runs longer than the 2000 s of motion a reference held whole may hold"):
        _plan(["G21 G90 G0 X0 Y0", "G1 X1 F100", "G4 P900000"])


def test_zpetc_reads_the_programs_preview_and_the_progress_is_in_lines():
    """Seed 004's MIMO controller with ZPETC (which reads the reference ahead) on the circle
    program; the progress bar of a program counts its lines."""
    from twin.scenario import prepare, read_scenario_data, scenario_from_dict
    from twin.sim.runner import _progress_bar

    data = read_scenario_data("seed004_mimo_cutting")
    data["reference"] = {"type": "gcode", "file": str(PROGRAMS / "seed004_circle.ngc")}
    data["duration_s"] = 1.0
    run = api.run(scenario_from_dict(data))
    assert run.summary["status"] == "ok" and run.summary["max_tracking_error_um"]["y"] < 500
    reference = prepare(scenario_from_dict(data))["reference"]
    with _progress_bar(reference, 100, "linear_motor_xy", show=True) as bar:
        assert (bar.total, bar.format_dict["unit"]) == (reference.n_lines, "line") and reference.n_lines == 15
    # the first move is line 10 (line 9 goes where the table is), the last line 13
    assert reference.line_at(0.0) == 10 and reference.line_at(reference.duration_s) == 13
