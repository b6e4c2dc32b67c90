"""Travel and drive checks of a planned program (:mod:`twin.gcode.checks`): every arc's and
helix's extent against brute-force sampling, the offsets in machine coordinates, refuse and
warn, the command line's exit codes, and the drive force against the machine's numbers computed
here on their own (Choi 1999's Table 1, a machine file's catalogue values)."""

from __future__ import annotations

import json
import math
import re
import tomllib
from pathlib import Path

import numpy as np
import pytest

from tests.cli_process import twin
from twin.gcode.checks import DriveCheck, TravelCheck, segment_extent
from twin.gcode.path import move_segment
from twin.gcode.planned import Limits, PlanningError
from twin.gcode.planner import PlannerSettings, plan
from twin.gcode.reader import PLANES, Move, Reader, Settings
from twin.machines import build
from twin.machines.rigid_drive import rigid_drives, table_travel_m
from twin.records import DriveWarning, TravelWarning
from twin.references.gcode import planned_for

ROOT = Path(__file__).resolve().parent.parent
LINEAR_FILE = str(ROOT / "examples" / "machines" / "linear_motor_xy.toml")
COMPACT_FILE = str(ROOT / "examples" / "machines" / "compact_xy.toml")
LIMITS = Limits((0.5, 0.5, 0.2), (5.0, 5.0, 2.0), (100.0, 100.0, 200.0))


def _moves(text: str, settings: Settings | None = None) -> list[Move]:
    return list(Reader(text.strip().splitlines(), settings).moves())


def _segments(moves: list[Move]):
    """The programmed segments as the planner strings them (from each move's predecessor's end)."""
    position = (np.asarray(moves[0].start_mm) + np.asarray(moves[0].offset_mm)) * 1e-3
    for move in moves:
        seg = move_segment(move, position, 0.0)
        if seg is not None:
            position = seg.end
            yield seg


def _random_arc(rng, spiral: bool) -> Move:
    """An arc in a random plane, 1-3 turns either way, a helix half the time, a spiral (its end
    radius 0.2-1.8 times its start's) if asked."""
    plane = str(rng.choice(list(PLANES)))
    first, second, normal = PLANES[plane]
    center = rng.uniform(-50.0, 50.0, 2)
    r0 = rng.uniform(1.0, 40.0)
    r1 = r0 * rng.uniform(0.2, 1.8) if spiral else r0
    a0, a1 = rng.uniform(-math.pi, math.pi, 2)
    start, end = np.zeros(3), np.zeros(3)
    start[[first, second]] = center + r0 * np.array([math.cos(a0), math.sin(a0)])
    end[[first, second]] = center + r1 * np.array([math.cos(a1), math.sin(a1)])
    start[normal] = rng.uniform(-20.0, 20.0)
    end[normal] = start[normal] + (rng.uniform(-30.0, 30.0) if rng.random() < 0.5 else 0.0)
    turns = int(rng.integers(1, 4)) * (1 if rng.random() < 0.5 else -1)
    offset = tuple(rng.uniform(-100.0, 100.0, 3))
    return Move(1, "arc", tuple(start), tuple(end), offset, 600.0, plane=plane, center_mm=tuple(center), turns=turns)


@pytest.mark.parametrize("spiral", [False, True])
def test_an_arcs_extent_is_exact_against_brute_force_sampling(spiral):
    """Circles, helices (G17, G18, G19, up to three turns either way) and spirals: the extent
    holds every one of 100 001 points along the arc and is within 1 nm of the sampled one."""
    rng = np.random.default_rng(46 + spiral)
    for _ in range(25):
        move = _random_arc(rng, spiral)
        start = (np.asarray(move.start_mm) + np.asarray(move.offset_mm)) * 1e-3
        seg = move_segment(move, start, 0.0)
        assert seg is not None and seg.kind == "arc"
        low, high = segment_extent(seg)
        points = seg.points(np.linspace(0.0, seg.length, 100_001))
        assert np.all(low <= points.min(axis=0) + 1e-12) and np.all(high >= points.max(axis=0) - 1e-12)
        assert low == pytest.approx(points.min(axis=0), abs=1e-9)
        assert high == pytest.approx(points.max(axis=0), abs=1e-9)


def test_the_planned_reference_stays_within_the_programmed_extent():
    """Blended corners, arcs and the smoothing filter: no sample of the plan leaves the box of
    the programmed moves' exact extents (what lets the travel be checked before planning)."""
    moves = _moves(
        "G21 G90 G64 P0.05\nG0 X0 Y0\nG1 X30 F3000\nG3 X30 Y20 I0 J10\nG1 X0 Y20\nG3 X0 Y0 I0 J-10\n"
        "G0 X40 Y-5\nG1 X40 Y25 F6000\nG0 X0 Y0\nM2"
    )
    extents = [segment_extent(seg) for seg in _segments(moves)]
    low, high = np.min([e[0] for e in extents], axis=0), np.max([e[1] for e in extents], axis=0)
    planned = plan(moves, LIMITS)
    assert np.all(planned.position >= low - 1e-12) and np.all(planned.position <= high + 1e-12)
    assert high[0] == pytest.approx(0.040) and low[0] == pytest.approx(-0.010)  # the G3's leftmost point


def test_the_travel_is_the_machine_files_centred_on_machine_zero():
    """``travel_m`` (0.6 m for X, 0.4 m for Y of the file), the simulated slide's range; the papers'
    machines have none."""
    data = tomllib.loads(Path(LINEAR_FILE).read_text())
    travel = table_travel_m(build(LINEAR_FILE))
    for axis in ("x", "y"):
        half = data["axes"][axis]["travel_m"] / 2
        assert travel[axis] == pytest.approx((-half, half), abs=1e-15)
    assert table_travel_m(build("linear_motor_xy")) == {}


LINEAR_TRAVEL = {0: (-0.3, 0.3), 1: (-0.2, 0.2)}


@pytest.mark.parametrize(
    "program, settings, line, value",
    [
        # G54 at X -250: X-60 is machine X -310
        ("G21 G90 G54\nG0 X0 Y0\nG0 X-60\nM2", Settings(work_offsets_mm={1: (-250.0, 0.0, 0.0)}), 3, "X -310.000"),
        # G92 X100 where the tool is at machine X0: X-220 is machine X -320
        ("G21 G90\nG0 X0 Y0\nG92 X100\nG0 X-220\nM2", None, 4, "X -320.000"),
        # G52 Y150: Y60 is machine Y 210
        ("G21 G90\nG0 X0 Y0\nG52 Y150\nG1 Y60 F1000\nM2", None, 4, "Y 210.000"),
        # a circle whose ends are inside: its rightmost point (X 250 + 2 x 40) is not
        ("G21 G90\nG0 X250 Y0\nG3 X250 Y0 I40 J0 F1000\nM2", None, 3, "X 330.000"),
        # an arc about X0 Y-160 (R 50) from one end of the travel to the other: its lowest point,
        # between its ends, is 10 mm beyond
        ("G21 G90\nG0 X-30 Y-200\nG3 X30 Y-200 I30 J40 F1000\nM2", None, 3, "Y -210.000"),
    ],
)
def test_a_move_outside_the_travel_is_refused_with_its_line_in_machine_coordinates(program, settings, line, value):
    with pytest.raises(PlanningError) as refused:
        TravelCheck(LINEAR_TRAVEL, refuse=True).check(_moves(program, settings))
    assert str(refused.value).startswith(f"line {line}: {value} mm (machine coordinates) is outside the travel")


TRAVEL_FIXTURES = ROOT / "tests" / "fixtures" / "gcode" / "travel"


def _linuxcnc_travel() -> dict:
    """LinuxCNC 2.9's task and motion controller on the programs of ``fixtures/gcode/travel``
    with X soft limits of -300..300 mm (``regenerate.py`` there)."""
    return json.loads((TRAVEL_FIXTURES / "linuxcnc.json").read_text())


@pytest.mark.parametrize("program", ["line.ngc", "g92.ngc", "g52.ngc"])
def test_a_line_outside_the_travel_is_refused_where_linuxcnc_refuses_it(program):
    """LinuxCNC refuses a straight move whose end is beyond a soft limit ("Linear move on line 4
    would exceed X's negative limit", the G92 and G52 offsets in machine coordinates); the twin
    refuses the same line."""
    messages = _linuxcnc_travel()["programs"][program]["messages"]
    line = int(re.match(r"Linear move on line (\d+) would exceed X's negative limit", messages[0]).group(1))
    with pytest.raises(PlanningError, match=rf"^line {line}: X -3[0-9.]+ mm \(machine coordinates\) is outside"):
        TravelCheck(LINEAR_TRAVEL, refuse=True).check(_moves((TRAVEL_FIXTURES / program).read_text()))


def test_an_arc_through_a_soft_limit_linuxcnc_runs_the_twin_refuses():
    """A circle whose ends are inside: LinuxCNC checks a move's end only and runs it, its
    commanded X reaching 330 mm past the 300 mm limit; the twin's exact extent is where LinuxCNC's
    commanded positions went (within 1 um), and it refuses the line. A program inside (a G54
    offset, a full circle to 10 mm of the limit) both run, to the same extent."""
    programs = _linuxcnc_travel()["programs"]
    arc = _moves((TRAVEL_FIXTURES / "arc.ngc").read_text())
    assert programs["arc.ngc"]["messages"] == []
    assert max(segment_extent(seg)[1][0] for seg in _segments(arc)) * 1e3 == pytest.approx(
        programs["arc.ngc"]["max_x_mm"], abs=1e-3
    )
    with pytest.raises(PlanningError, match=r"^line 3: X 330\.000 mm"):
        TravelCheck(LINEAR_TRAVEL, refuse=True).check(arc)
    inside = _moves((TRAVEL_FIXTURES / "inside.ngc").read_text())
    assert programs["inside.ngc"]["messages"] == []
    TravelCheck(LINEAR_TRAVEL, refuse=True).check(inside)
    extents = [segment_extent(seg) for seg in _segments(inside)]
    assert min(e[0][0] for e in extents) * 1e3 == pytest.approx(programs["inside.ngc"]["min_x_mm"], abs=1e-3)
    assert max(e[1][0] for e in extents) * 1e3 == pytest.approx(programs["inside.ngc"]["max_x_mm"], abs=1e-3)


def test_the_tool_length_offset_counts_on_z():
    """G43 H1 with a 30 mm tool: Z-120 is machine Z -90 (inside -100..0), Z-140 machine Z -110."""
    settings = Settings(tool_lengths_mm={1: 30.0})
    check = TravelCheck({2: (-0.1, 0.0)}, refuse=True)
    check.check(_moves("G21 G90\nT1 M6\nG43 H1\nG0 Z-120\nM2", settings))
    with pytest.raises(PlanningError, match=r"^line 4: Z -110\.000 mm .* -100\.000\.\.0\.000 mm of axis z"):
        check.check(_moves("G21 G90\nT1 M6\nG43 H1\nG0 Z-140\nM2", settings))
    with pytest.raises(PlanningError, match=r"^line 3: Z -120\.000 mm"):
        check.check(_moves("G21 G90\nT1 M6\nG0 Z-120\nM2", settings))  # without G43


def test_warn_lists_each_lines_worst_excess_per_axis():
    """Every move the machine makes outside its travel is warned of, one that comes back in (from
    where the move before ended) too."""
    moves = _moves("G21 G90\nG0 X0 Y0\nG0 X-310 Y-250\nG1 X0 Y0 F1000\nG0 X305\nG0 X320\nM2")
    check = TravelCheck(LINEAR_TRAVEL, refuse=False)
    assert [m.line for m in check.passing(moves)] == [m.line for m in moves]  # every move passes on
    rows = check.warnings.listed()
    assert all(isinstance(r, TravelWarning) for r in rows)
    assert [(r.line, r.axis, r.value_mm) for r in rows] == [
        (3, "x", -310.0),
        (3, "y", -250.0),
        (4, "x", -310.0),
        (4, "y", -250.0),
        (5, "x", 305.0),
        (6, "x", 320.0),
    ]
    assert rows[0].message == "X -310.000 mm (machine coordinates) is outside the travel -300.000..300.000 mm of axis x"
    assert rows[0].text == "G0 X-310 Y-250" and check.warnings.total == 6
    first = {"line": 3, "check": "travel", "axis": "x", "value_mm": -310.0}
    assert json.dumps(rows[0].to_json()) == json.dumps({**first, "message": rows[0].message, "text": rows[0].text})


def _rigid_force(mass_kg, viscous, coulomb, velocity, acceleration):
    return mass_kg * acceleration + viscous * velocity + coulomb * np.sign(velocity)


def test_the_drive_force_of_a_rapid_on_choi_1999s_table():
    """A 52 mm rapid on X of ``linear_motor_xy`` at its limits (18.8 m/s^2 = 982 N / 52.3 kg, 1 m/s):
    the force m a + b v with Table 1's m_x = 52.3 kg, b_x = 193.5 N s/m passes the Anorad's 982 N
    (98.2 N/V at 10 V) while the axis still accelerates at speed."""
    machine = build("linear_motor_xy")
    moves = _moves("G21 G90\nG0 X0 Y0\nG0 X52\nM2")
    planned = plan(moves, PlannerSettings().limits(machine.motion_limits))
    force = _rigid_force(52.3, 193.5, 0.0, planned.velocity[:, 0], planned.acceleration[:, 0])
    check = DriveCheck({0: rigid_drives(machine)["x"], 1: rigid_drives(machine)["y"]}, 10.0)
    check.add(planned.position, planned.velocity, planned.acceleration, planned.line, planned.texts)
    (row,) = check.warnings.listed()
    worst = float(np.abs(force).max())
    assert isinstance(row, DriveWarning) and (row.line, row.axis) == (3, "x")
    assert row.force_N == pytest.approx(worst, abs=1e-3)
    assert row.ratio == pytest.approx(worst / 982.0, abs=1e-6)
    assert row.message == f"axis x needs {worst:.1f} N, the drive saturates at 982.0 N (x{worst / 982.0:.3f})"
    assert list(row.to_json()) == ["line", "check", "axis", "ratio", "force_N", "message", "text"]
    assert row.to_json()["check"] == "drive"
    assert worst / 982.0 > 1.1


def _reflected_mass_kg(data: dict, axis: str) -> float:
    """A ball-screw axis's moving mass in table travel from a machine file's values: rotor,
    coupling and screw inertia over (lead / 2 pi)^2, nut and table, and what rides on it (the
    upper axis's table, motor, nut and steel screw, the workpiece)."""
    ax = data["axes"][axis]
    lead = ax["screw_lead_m"] / (2 * math.pi)
    screw_j = math.pi * 7850.0 * ax["screw_diameter_m"] ** 4 * ax["screw_length_m"] / 32
    rotary = (ax["motor_inertia_kg_m2"] + ax["coupling_inertia_kg_m2"]) * ax.get("gear_ratio", 1.0) ** 2 + screw_j
    mass = rotary / lead**2 + ax["nut_mass_kg"] + ax["table_mass_kg"] + data["machine"]["workpiece_mass_kg"]
    stacking = data["machine"]["stacking"]
    for upper in stacking[stacking.index(axis) + 1 :]:
        up = data["axes"][upper]
        screw_mass = 7850.0 * math.pi * up["screw_diameter_m"] ** 2 / 4 * up["screw_length_m"]
        mass += up["table_mass_kg"] + up["motor_mass_kg"] + up["nut_mass_kg"] + screw_mass
    return mass


def test_the_drive_force_on_a_compliant_ball_screw_machine_file():
    """``compact_xy``: the warned force of each line and axis equals M a + B v + F_c sign(v) at
    its worst sample, M the reflected mass computed here from the file's catalogue values (its
    springs and dampers leave the low-frequency force unchanged), K = k_t k_a 2 pi / lead."""
    data = tomllib.loads(Path(COMPACT_FILE).read_text())
    saturation_V = 1.1
    moves = _moves("G21 G90\nG0 X0 Y0\nG0 X100 Y-80\nG1 X-50 F20000\nG0 Y60\nM2")
    summary = planned_for("p.ngc", moves, COMPACT_FILE, PlannerSettings(), saturation_V)
    planned = plan(moves, PlannerSettings().limits(build(COMPACT_FILE).motion_limits))
    expected = {}
    for i, axis in enumerate("xy"):
        ax = data["axes"][axis]
        gain = ax["torque_constant_N_m_per_A"] * ax["amplifier_gain_A_per_V"] * 2 * math.pi / ax["screw_lead_m"]
        force = np.abs(
            _rigid_force(
                _reflected_mass_kg(data, axis),
                ax["friction_viscous_N_s_per_m"],
                ax["friction_coulomb_N"],
                planned.velocity[:, i],
                planned.acceleration[:, i],
            )
        )
        for line in np.unique(planned.line):
            worst = float(force[planned.line == line].max())
            if worst > gain * saturation_V:
                expected[(int(line), axis)] = (worst, gain * saturation_V)
    rows = summary.warnings
    assert {axis for _line, axis in expected} == {"x", "y"}
    assert {(r.line, r.axis) for r in rows} == set(expected)
    for row in rows:
        assert isinstance(row, DriveWarning)
        worst, limit = expected[(row.line, row.axis)]
        assert row.force_N == pytest.approx(worst, rel=1e-9, abs=1e-3)
        assert row.ratio == pytest.approx(worst / limit, rel=1e-6)


@pytest.fixture
def outside(tmp_path):
    program = tmp_path / "outside.ngc"
    program.write_text("G21 G90\nG0 X0 Y0\nG0 X-380 Y10\nG0 X0\nM2\n")
    return program


def test_twin_gcode_refuses_a_move_outside_the_travel_in_one_line(outside):
    done = twin("gcode", outside, "--machine", LINEAR_FILE)
    assert done.returncode == 2 and done.stdout == ""
    (line,) = done.stderr.strip().splitlines()
    assert line == (
        f"error: file = '{outside}': line 3: X -380.000 mm (machine coordinates) is outside the travel "
        '-300.000..300.000 mm of axis x (travel = "warn" in [planner] to warn only)'
    )


def test_twin_gcode_warns_and_strict_exits_4(outside):
    done = twin("gcode", outside, "--machine", LINEAR_FILE, "--set", "planner.travel=warn", "--json")
    assert done.returncode == 0, done.stderr
    rows = json.loads(done.stdout)["planned"]["warnings"]
    assert [(r["line"], r["check"], r["axis"], r["value_mm"]) for r in rows] == [
        (3, "travel", "x", -380.0),
        (4, "travel", "x", -380.0),  # back from there
    ]
    done = twin("gcode", outside, "--machine", LINEAR_FILE, "--set", "planner.travel=warn", "--strict")
    assert done.returncode == 4
    assert "line      3  X -380.000 mm (machine coordinates) is outside" in done.stdout
    (line,) = done.stderr.strip().splitlines()
    assert line.startswith("error: 2 warning(s) against the machine under --strict; the first: line 3: X -380.000 mm")


def test_twin_gcode_drive_warning_and_strict(tmp_path):
    program = tmp_path / "rapid.ngc"
    program.write_text("G21 G90\nG0 X0 Y0\nG0 X52\nM2\n")
    done = twin("gcode", program, "--machine", "linear_motor_xy")
    assert done.returncode == 0 and "warnings against the machine" not in done.stdout  # no saturation given
    done = twin("gcode", program, "--machine", "linear_motor_xy", "--set", "drive.saturation_V=10", "--strict")
    assert done.returncode == 4
    assert "line      3  axis x needs 11" in done.stdout
    assert done.stderr.strip().splitlines()[-1].startswith("error: 1 warning(s) against the machine under --strict")
    done = twin("gcode", program, "--machine", "linear_motor_xy", "--set", "drive.saturation_V=-1")
    assert done.returncode == 2 and "drive.saturation_V = -1" in done.stderr


def test_twin_run_reports_travel_and_drive_warnings(tmp_path):
    """A run of a program that passes the travel by 1 mm (warned) with a rapid the drive cannot
    make: both in the JSON, and ``--strict`` exits 4 after the report."""
    (tmp_path / "p.ngc").write_text("G21 G90\nG0 X0 Y0\nG0 X52\nG1 X301 F60000\nG1 X300\nM2\n")
    scenario = tmp_path / "run.toml"
    scenario.write_text(
        f'name = "checks"\nmachine = "{LINEAR_FILE}"\ntimestep_s = 1e-4\ncontrol_period_s = 5e-4\n'
        '[controllers.x]\ntype = "pid"\nparams = { kp = 2.0e4, ki = 2.0e5, kd = 150.0, tf_s = 5e-4 }\n'
        '[controllers.y]\ntype = "pid"\nparams = { kp = 7.0e3, ki = 7.0e4, kd = 50.0, tf_s = 5e-4 }\n'
        '[reference]\ntype = "gcode"\nfile = "p.ngc"\n[planner]\ntravel = "warn"\n[drive]\nsaturation_V = 10.0\n'
    )
    done = twin("run", scenario, "--json")
    assert done.returncode == 0, done.stderr
    rows = json.loads(done.stdout)["plan_warnings"]
    assert (rows[0]["line"], rows[0]["check"], rows[0]["axis"]) == (3, "drive", "x")
    travel = [(r["line"], r["axis"], r["value_mm"]) for r in rows if r["check"] == "travel"]
    assert travel == [(4, "x", 301.0), (5, "x", 301.0)]
    done = twin("run", scenario, "--strict")
    assert done.returncode == 4
    assert f"warnings against the machine ({len(rows)}):" in done.stdout
    last = done.stderr.strip().splitlines()[-1]
    assert last.startswith(
        f"error: {len(rows)} warning(s) against the machine under --strict; the first: line 3: axis x"
    )
    scenario.write_text(scenario.read_text().replace('travel = "warn"', 'travel = "refuse"'))
    done = twin("run", scenario)
    assert done.returncode == 2 and done.stdout == ""
    assert "line 4: X 301.000 mm (machine coordinates) is outside the travel -300.000..300.000 mm" in done.stderr


def _rapid_scenario(tmp_path: Path) -> Path:
    """The test piece's loops (Choi 1999's PID with feedforward, 10 V drives, its Coulomb
    friction) on a 52 mm rapid along X."""
    (tmp_path / "rapid.ngc").write_text("G21 G90\nG0 X0 Y0\nG0 X52\nG4 P0.1\nM2\n")
    scenario = tmp_path / "rapid.toml"
    scenario.write_text(
        'name = "rapid52"\nmachine = "linear_motor_xy"\noverrides = { F_coul_x = 2.94, F_coul_y = 1.90 }\n'
        'timestep_s = 1e-4\ncontrol_period_s = 5e-4\n[controllers.x]\ntype = "pid"\n'
        "params = { kp = 2.0e4, ki = 2.0e5, kd = 150.0, tf_s = 5e-4 }\nvelocity_ff = 1.97\nacceleration_ff = 0.533\n"
        '[controllers.y]\ntype = "pid"\nparams = { kp = 7.0e3, ki = 7.0e4, kd = 50.0, tf_s = 5e-4 }\n'
        'velocity_ff = 0.367\nacceleration_ff = 0.173\n[reference]\ntype = "gcode"\nfile = "rapid.ngc"\n'
        "[drive]\nsaturation_V = 10.0\n"
    )
    return scenario


def test_the_drive_check_agrees_with_the_closed_loop(tmp_path):
    """At the machine's limits the check warns (1138 N of 982 N) and the closed loop saturates
    its drive and overshoots by millimetres; within the accelerations the machine's README
    gives ((982 N - b v_max - F_c) / m: 15.0 and 55.5 m/s^2) it is silent and the loop stays
    within its drive and tracks within 20 um."""
    import twin as api

    scenario = _rapid_scenario(tmp_path)
    at_limits = api.run(scenario)
    (row,) = at_limits.summary["plan_warnings"]
    assert row["force_N"] == pytest.approx(1138.3, abs=0.05)  # 52.3 a + 193.5 v + 2.94 at the worst sample
    assert np.abs(at_limits.result.u_V[:, 0]).max() > 10.0
    assert at_limits.result.table_position_m()[:, 0].max() > 0.052 + 1e-3
    lowered = api.run(scenario, **{"planner.acceleration_m_per_s2": {"x": 15.0, "y": 55.5}})
    assert "plan_warnings" not in lowered.summary
    assert np.abs(lowered.result.u_V[:, 0]).max() < 10.0
    assert lowered.summary["max_tracking_error_um"]["x"] < 20.0


def test_a_streamed_program_gets_the_held_ones_drive_warnings(monkeypatch):
    """A program too long to hold is checked as the run draws its samples: once drawn to the end
    its warnings are those of the same program held whole."""
    import twin.gcode.planner as planner
    from twin.gcode.checks import plan_warnings
    from twin.references.gcode import StreamedGcodeReference

    monkeypatch.setattr(planner, "WINDOW_POINTS", 3000)
    monkeypatch.setattr(planner, "PIECE_POINTS", 500)
    lines = ["G21 G90 G0 X0 Y0"] + [f"G0 X{40 * (k % 2) + k} Y{30 * (k % 3)}" for k in range(1, 12)]
    machine = build("linear_motor_xy")
    drives = {0: rigid_drives(machine)["x"], 1: rigid_drives(machine)["y"]}
    limits = PlannerSettings().limits(machine.motion_limits)
    held = plan(Reader(lines).moves(), limits)
    whole = DriveCheck(drives, 10.0)
    whole.add(held.position, held.velocity, held.acceleration, held.line, held.texts)
    _none, facts, samples = planner.hold_or_count(Reader(lines).moves(), limits, PlannerSettings(), most=0)
    streamed_check = DriveCheck(drives, 10.0)
    streamed = StreamedGcodeReference(
        lambda: Reader(lines).moves(), limits, PlannerSettings(), facts, samples, (0, 1), len(lines), (streamed_check,)
    )
    for k0 in range(0, samples * 2, 700):  # the runner's chunks at a 0.5 ms period
        streamed.sample(np.arange(k0, k0 + 710) * 5e-4)
    assert len(whole.warnings.listed()) >= 5
    assert plan_warnings(streamed_check) == (whole.warnings.listed(), whole.warnings.total)
