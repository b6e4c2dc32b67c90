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
from twin.gcode.planned import Limits, PlanningError
from twin.gcode.planner import MAX_SAMPLES, PlannerSettings, plan
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
    """v = min(F, sqrt(a R), 0.97 (j R^2)^(1/3)) (and the axis velocity; the planner keeps 3 %
    of the jerk for the speed's changes), with a tolerance wide enough that the filter's shrink
    is not compensated; the filter (length T = a/j) turns the circle into one of radius
    R sinc(w T/2), w = v/R, so the sampled speed is v sinc."""
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
        "jerk": 0.97 * (100.0 * r * r) ** (1 / 3),
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
    return [(PROGRAMS / f"{n}.ngc", Settings()) for n in ("choi1999_circle", "test_piece")] + [
        (FIXTURES / f"{n}.ngc", Settings(tool_lengths_mm={1: 5.08})) for n in ("basic", "planes", "offsets")
    ]


@pytest.mark.parametrize("machine", ["linear_motor_xy", "googol_xy", "coupled_servo_xy"])
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
    """Choi 1999's cutting circle as G-code, with limits far above what the circle needs (the
    filter a/j then one sample: none): over the same second of the circle, the same tracking
    errors and cutting forces as the built-in circle reference (which starts at full feed)."""
    fast = {
        "planner.acceleration_m_per_s2": {"x": 1e3, "y": 1e3, "z": 1e3},
        "planner.jerk_m_per_s3": {"x": 1e6, "y": 1e6, "z": 1e6},
        "planner.velocity_m_per_s": {"x": 10.0, "y": 10.0, "z": 10.0},
    }
    program = api.run("gcode_choi1999_circle", **fast).result
    builtin = api.run("choi1999_cutting_circle").result
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
    whole = api.run("gcode_choi1999_circle")
    planned = api.program(
        PROGRAMS / "choi1999_circle.ngc", machine="linear_motor_xy", **{"planner.tolerance_mm": 0.005}
    )
    assert whole.summary["completed_ticks"] == pytest.approx(planned.planned.cycle_time_s / 5e-4, abs=2)
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
        (["{bad}"], "bad.ngc:3 = 'G41 D7 X1 Y1': Requested tool 7 not found in the tool table"),
        (
            ["{bad}", "--set", "reference.tool_diameters_mm={{ 7 = 4.0 }}"],
            "bad.ngc:3 = 'G41 D7 X1 Y1': Length of cutter compensation entry move is not greater than the tool radius",
        ),
        (["{bad_g33}"], "bad_g33.ngc:3 = 'G33 X1 K1': spindle-synchronized motion (G33) is not supported"),
        (["{good}", "--machine", "mill"], "machine = 'mill': unknown machine"),
        (["{good}", "--machine", "googol_xy", "--set", "planner.tolerance_mm=-1"], "planner.tolerance_mm = -1"),
        (["{good}", "--set", "spindle=3"], "--set spindle = 3: give planner.KEY, reference.KEY or drive.KEY"),
        (["{good}", "--set", "planner.jerk_m_per_s3={{ w = 3.0 }}"], "'w' is not an axis"),
        (["{missing}"], "file = "),
    ],
)
def test_twin_gcode_bad_input_is_one_line_and_exit_2(tmp_path, args, words):
    bad = tmp_path / "bad.ngc"
    bad.write_text("G21\nG0 X0 Y0\nG41 D7 X1 Y1\nG1 X2 F100\n")
    bad_g33 = tmp_path / "bad_g33.ngc"
    bad_g33.write_text("G21\nG0 X0 Y0\nG33 X1 K1\nG1 X2 F100\n")
    good = tmp_path / "good.ngc"
    good.write_text("G21 G0 X0 Y0\nG1 X1 F100\n")
    argv = [a.format(bad=bad, bad_g33=bad_g33, good=good, missing=tmp_path / "none.ngc") for a in args]
    out = CliRunner().invoke(app, ["gcode", *argv])
    assert out.exit_code == 2, out.output
    lines = out.output.strip().splitlines()
    assert words in lines[-1], out.output
    assert lines[-1].startswith("error: "), out.output
    assert sum(line.startswith("error") for line in lines) == 1


def test_a_dwell_too_long_to_hold_is_refused():
    with pytest.raises(PlanningError, match="runs longer than the 2000 s of motion a reference held whole may hold"):
        _plan(["G21 G90 G0 X0 Y0", "G1 X1 F100", "G4 P900000"])


def test_zpetc_reads_the_programs_preview_and_the_progress_is_in_lines():
    """Choi 1999's MIMO controller with ZPETC (which reads the reference ahead) on the circle
    program; the progress bar of a program counts its lines."""
    from twin.scenario import assemble, read_scenario_data, scenario_from_dict
    from twin.sim.runner import _progress_bar

    data = read_scenario_data("choi1999_mimo_cutting")
    data["reference"] = {"type": "gcode", "file": str(PROGRAMS / "choi1999_circle.ngc")}
    data["duration_s"] = 1.0
    run = api.run(scenario_from_dict(data))
    assert run.summary["status"] == "ok"
    assert run.summary["max_tracking_error_um"]["y"] < 500
    reference = assemble(scenario_from_dict(data)).reference
    with _progress_bar(reference, 100, "linear_motor_xy", show=True) as bar:
        assert (bar.total, bar.format_dict["unit"]) == (reference.n_lines, "line")
        assert reference.n_lines == 15
    # the first move is line 10 (line 9 goes where the table is), the last line 13
    assert reference.line_at(0.0) == 10
    assert reference.line_at(reference.duration_s) == 13


def _speed(p):
    return np.linalg.norm(p.velocity, axis=1)


def _deviation_over_tolerance(p):
    from twin.gcode.report import path_deviation_m

    return path_deviation_m(p) / p.sample_tolerance_m


def test_the_tolerance_is_modal_per_block():
    """A square's corners under G64 P1 then under G64 P0.005 (the issue's case: all at 1 mm
    before): each corner within the tolerance in force there, the tight ones cut 0.005 mm."""
    p = _plan(
        ["G21 G90 G0 X0 Y0", "G64 P1.0", "G1 X40 F3000", "G1 Y40", "G64 P0.005", "G1 X0", "G1 Y0", "G1 X40"],
        LIMITS,
    )
    ratio = _deviation_over_tolerance(p)
    assert ratio.max() <= 1.0
    loose = (p.sample_tolerance_m == 1e-3) & (ratio > 0.3)
    tight = p.sample_tolerance_m == 5e-6
    assert loose.any()  # the P1 corner is rounded by more than 0.3 mm
    assert (ratio[tight] * 5e-6).max() <= 5e-6  # the P0.005 corners within 5 um


def test_g61_stops_at_corners_not_tangent_junctions_and_g61_1_stops_at_every_junction():
    def stops(lines):
        """Times the speed falls below 1 % of the feed between the program's start and end."""
        p = _plan(lines, LIMITS)
        slow = _speed(p) < 0.01 * 0.05
        inner = slow[np.argmin(slow) : len(slow) - np.argmin(slow[::-1])]
        return int(np.count_nonzero(inner[1:] & ~inner[:-1])), p

    corner = ["G21 G90 G0 X0 Y0", "G61", "G1 X20 F3000", "G1 Y20", "G1 X0"]
    tangent = ["G21 G90 G0 X0 Y0", "G61", "G1 X20 F3000", "G3 X20 Y20 I0 J10", "G1 X0"]
    collinear = ["G21 G90 G0 X0 Y0", "G61.1", "G1 X10 F3000", "G1 X20", "G1 X30"]
    assert stops(corner)[0] == 2  # the two corners
    assert stops(tangent)[0] == 0  # line-arc-line, tangent: no stop under exact path
    assert stops(collinear)[0] == 2  # exact stop: at both junctions of collinear lines
    assert stops([line.replace("G61.1", "G64 P0.01") for line in collinear])[0] == 0


def test_a_cam_arc_chain_with_tiny_kinks_runs_at_its_feed():
    """Arcs of a circle written with four decimals (kinks of 0.003-0.11 deg between them, as CAM
    posts write them): the speed stays at F along the chain, away from its ends."""
    lines, r, n = ["G21 G90 G0 X25 Y0", "G64 P0.01", "F2540"], 25.0, 24
    for k in range(1, n + 1):
        a = 2 * math.pi * k / n
        lines.append(f"G3 X{r * math.cos(a):.4f} Y{r * math.sin(a):.4f} R{r}")
    p = _plan(lines, Limits((0.5, 0.5, 0.2), (5.0, 5.0, 2.0), (200.0, 200.0, 200.0)))
    speed = _speed(p) * 60e3
    middle = speed[len(speed) // 5 : 4 * len(speed) // 5]
    assert middle.min() >= 0.99 * 2540
    assert _deviation_over_tolerance(p).max() <= 1.0


def test_an_arc_whose_end_is_off_its_circle_moves_on_a_spiral_within_the_limits():
    """The issue's case on linear_motor_xy: the end 5 um off the circle. The path is continuous,
    every axis within its limits (it jerked 9 061 m/s^3 against 1 878), and the path stays
    within the tolerance of the programmed spiral."""
    limits = PlannerSettings().limits(build("linear_motor_xy").motion_limits)
    p = _plan(["G21 G90 G0 X0 Y0", "G1 X10 F3000", "G3 X-10.005 Y0 I-10 J0", "G1 X-30"], limits)
    jerk = np.abs(_jerk(p)).max(axis=0)
    for i in range(2):
        assert jerk[i] <= limits.jerk_m_per_s3[i] * 1.000001
        assert np.abs(p.acceleration[:, i]).max() <= limits.acceleration_m_per_s2[i] * 1.000001
    assert np.abs(np.diff(p.position, axis=0)).max() <= 0.05 * 1e-3 * 1.01  # no jump at the end (50 mm/s)
    assert _deviation_over_tolerance(p).max() <= 1.0
    assert p.position[-1] == pytest.approx([-0.030, 0.0, 0.0], abs=1e-12)


def test_the_deviation_is_the_exact_distance_to_the_arc():
    """A circle at constant speed through the moving-average filter of length T is a circle of
    radius R sinc(v T / 2R) (closed form): the reported deviation is R (1 - sinc), not the
    distance to a polyline of the arc."""
    limits = Limits((0.3, 0.3, 0.2), (5.0, 5.0, 2.0), (100.0, 100.0, 200.0))
    r_mm, feed = 10.0, 6000.0
    p = _plan(["G21 G90 G0 X0 Y0", f"G3 X0 Y0 I{-r_mm} J0 F{feed}", f"G3 X0 Y0 I{-r_mm} J0"], limits, tolerance_mm=5.0)
    from twin.gcode.report import path_deviation_m

    d = path_deviation_m(p)
    r, v, t_filter = r_mm * 1e-3, feed / 60e3, p.filter_s
    x = v * t_filter / (2 * r)
    middle = d[len(d) // 3 : 2 * len(d) // 3]
    assert middle.max() == pytest.approx(r * (1 - math.sin(x) / x), rel=1e-3)


def _hostile_program(seed: int) -> list[str]:
    """60 random blocks: short moves, reversals, tiny and large arcs, changes of tolerance and
    path mode."""
    rng = np.random.default_rng(seed)
    lines, x, y = ["G21 G90 G0 X0 Y0", "F6000"], 0.0, 0.0
    for _ in range(60):
        kind = rng.integers(4)
        if kind == 0:
            lines.append(rng.choice(["G64 P0.002", "G64 P0.05", "G61", "G64"]))
        step = float(rng.choice([0.01, 0.3, 5.0])) * float(rng.choice([-1, 1]))
        if kind == 3:
            r = abs(step)
            lines.append(f"G{rng.choice([2, 3])} X{x:.4f} Y{y + 2 * r:.4f} I0 J{r:.4f}")
            y += 2 * r
        else:
            x += step
            y += float(rng.normal()) * abs(step)
            lines.append(f"G1 X{x:.4f} Y{y:.4f}")
    return lines


@pytest.mark.parametrize("seed", range(4))
def test_no_axis_exceeds_its_limits_on_hostile_paths_or_the_plan_says_where(seed):
    """Random short moves, reversals, tiny and large arcs, changes of tolerance and path mode:
    every sampled velocity, acceleration and jerk within the limits, or the plan names the line
    and axis that is over (never a number over the limit said nothing about)."""
    lines = _hostile_program(seed)
    limits = PlannerSettings().limits(build("googol_xy").motion_limits)
    p = _plan(lines, limits)
    over = [
        np.abs(p.velocity).max(axis=0) / limits.velocity_m_per_s,
        np.abs(p.acceleration).max(axis=0) / limits.acceleration_m_per_s2,
        np.abs(_jerk(p)).max(axis=0) / limits.jerk_m_per_s3,
    ]
    worst = max(float(r.max()) for r in over)
    assert worst <= 1.000001 or p.violations, worst
    for violation in p.violations:
        assert violation.line >= 1
        assert violation.axis in "xyz"
        assert violation.ratio > 1
    assert _deviation_over_tolerance(p).max() <= 1.0


def test_a_streamed_reference_is_the_held_one_in_bounded_memory(monkeypatch):
    """The same program held whole and streamed (planned again as a run asks for it, windows
    and pieces made small here): the same samples, and the stream keeps a window, not the whole."""
    import twin.gcode.planner as planner
    from twin.references.gcode import GcodeReference, StreamedGcodeReference

    lines = ["G21 G90 G0 X0 Y0", "G64 P0.01", "F4000"]
    for k in range(120):
        lines += [
            f"G1 X{20 + 5 * math.sin(k):.4f} Y{k * 0.5:.4f}",
            f"G2 X{20 + 5 * math.sin(k):.4f} Y{k * 0.5 + 1:.4f} I0 J0.5",
        ]
    limits = PlannerSettings().limits(build("linear_motor_xy").motion_limits)
    monkeypatch.setattr(planner, "WINDOW_POINTS", 3000)
    monkeypatch.setattr(planner, "PIECE_POINTS", 500)
    held = _plan(lines, limits)
    held_reference = GcodeReference(held, (0, 1), len(lines))
    streamed = StreamedGcodeReference(
        lambda: Reader(lines).moves(), limits, PlannerSettings(), None, len(held.position), (0, 1), len(lines)
    )
    assert streamed.duration_s == held_reference.duration_s
    window = 0
    for k0 in range(0, len(held.position) * 2, 700):  # the runner's chunks at a 0.5 ms period
        t = np.arange(k0, k0 + 710) * 5e-4
        assert streamed.sample(t) == pytest.approx(held_reference.sample(t), abs=1e-12)
        assert (streamed.lines_at(t[:700]) == held_reference.lines_at(t[:700])).all()
        window = max(window, len(streamed.held[0]))
    assert window < len(held.position) / 3


def test_twin_gcode_says_which_line_and_axis_is_over_a_limit(tmp_path, monkeypatch):
    """With the repairs turned off, a hostile path's reference is over the jerk limit in places:
    the text and the JSON of ``twin gcode --machine`` name each line and axis, as the plan does."""
    import twin.gcode.planner as planner

    monkeypatch.setattr(planner, "MAX_REPAIRS", 0)
    lines = _hostile_program(1)
    program = tmp_path / "hostile.ngc"
    program.write_text("\n".join(lines) + "\n")
    limits = PlannerSettings().limits(build("googol_xy").motion_limits)
    violations = _plan(lines, limits).violations
    assert violations
    assert all(v.ratio > 1 for v in violations)
    out = CliRunner().invoke(app, ["gcode", str(program), "--machine", "googol_xy"])
    assert out.exit_code == 0, out.output
    said = [line.strip() for line in out.output.splitlines() if "over a limit" in line]
    assert said == [f"over a limit: line {v.line}, {v.axis} {v.quantity} x{v.ratio:.4f}" for v in violations]
    out = CliRunner().invoke(app, ["gcode", str(program), "--machine", "googol_xy", "--json"])
    assert [(v["line"], v["axis"]) for v in json.loads(out.output)["planned"]["violations"]] == [
        (v.line, v.axis) for v in violations
    ]


def test_the_look_ahead_plans_each_window_a_bounded_number_of_times(monkeypatch):
    """googol_xy's pocket raster (5 mm lines at 50 mm/s between 0.5 mm arcs at 9.8 mm/s): the
    window is handed on at the arcs' cruise, about every 20 s of motion, and a window with no
    cruise is planned again only once it is half as long again (before: at every new segment,
    two look-aheads per move, 140 times slower on 2000 moves)."""
    import twin.gcode.planner as planner
    from twin.bench import raster_program

    grids = []
    grid_init = planner._Grid.__init__

    def counted(self, *args, **kwargs):
        grids.append(1)
        grid_init(self, *args, **kwargs)

    monkeypatch.setattr(planner._Grid, "__init__", counted)
    limits = PlannerSettings().limits(build("googol_xy").motion_limits)
    p = _plan(raster_program(400), limits)
    assert p.cycle_time_s >= p.feed_only_time_s
    assert not p.violations
    assert len(grids) <= 0.2 * p.cycle_time_s + 2, len(grids)
