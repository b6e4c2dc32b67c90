"""Edge values of a machine file and of the commissioning commands' options: each is computed
with or refused by one line naming the field and the value (exit 2), never exit 70 (issue 48).

The fuzz draws, with a fixed seed, hostile and boundary values for every numeric key of the
example machine files and checks the schema's answer (validation only: fast); the values on
the physical ranges' bounds run through the commands themselves in the slow test."""

import json
import math
import random
import re
from pathlib import Path

import numpy as np
import pytest
from cli_process import twin

from twin.commissioning.calibration import calibrate, replay, write_table
from twin.errors import TwinInputError
from twin.fidelity import fidelity
from twin.machines import build, get_machine
from twin.machines.machine_file import BallScrewSpec, LimitsSpec, LinearMotorSpec, MachineSpec, physical_range

EXAMPLES = Path(__file__).resolve().parent.parent / "examples" / "machines"
MID = EXAMPLES / "mid_size_xy.toml"
FILES = [EXAMPLES / "mid_size_xy.toml", EXAMPLES / "heavy_xy.toml", EXAMPLES / "linear_motor_xy.toml"]
#: ``key = number`` lines of a machine file, with the table they are in.
NUMBER = re.compile(r"^([A-Za-z0-9_]+)\s*=\s*([-+0-9.e]+)", re.M)
TABLE = re.compile(r"^\[([A-Za-z0-9_.]+)\]", re.M)
#: What a hostile user types.
HOSTILE = [0.0, -1.0, 1e-15, 1e-300, 1e300, 1e12, math.nan, math.inf, -math.inf]


def _numeric_keys(text: str) -> list[tuple[str, str, re.Match]]:
    """(table, key, match of its value) for every numeric line of a machine file."""
    tables = [(m.start(), m.group(1)) for m in TABLE.finditer(text)]
    out = []
    for m in NUMBER.finditer(text):
        table = [name for start, name in tables if start < m.start()][-1]
        out.append((table, m.group(1), m))
    return out


def _model(table: str, key: str, text: str):
    """The schema model that holds ``key`` of ``table``."""
    if table == "machine":
        return MachineSpec
    if table.endswith(".limits"):
        return LimitsSpec
    axis_type = re.search(rf"\[{re.escape(table)}\]\s*\ntype\s*=\s*\"(\w+)\"", text).group(1)
    return BallScrewSpec if axis_type == "ball_screw" else LinearMotorSpec


def _with_value(text: str, match: re.Match, value: float) -> str:
    number = "nan" if math.isnan(value) else ("inf" if value > 0 else "-inf") if math.isinf(value) else repr(value)
    return text[: match.start(2)] + number + text[match.end(2) :]


def _one_error_line(result) -> str:
    assert result.returncode == 2, (result.returncode, result.stderr)
    assert result.stdout == ""
    lines = result.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), result.stderr
    return lines[0]


@pytest.mark.parametrize(
    ("edit", "field"),
    [
        (("screw_diameter_m = 0.032", "screw_diameter_m = 1e12"), "axes.x.screw_diameter_m = 1000000000000.0"),
        (("delay_s = 0.0002", "delay_s = 1.0"), "machine.delay_s = 1.0"),
    ],
)
def test_the_issues_machine_files_are_refused_naming_the_field(tmp_path, edit, field):
    """Issue 48's cases: BadCoefficients from a 1e12 m screw, a ZeroDivisionError from a 1 s
    delay; now refused by the schema's physical range, in fidelity, frf, tune and calibrate."""
    path = tmp_path / "edge.toml"
    path.write_text(MID.read_text().replace(*edit, 1))
    for args in (
        ["fidelity", "--machine", path],
        ["frf", path, "--duration", "3.3"],
        ["tune", path, "--no-verify"],
        ["calibrate", path, "--trace", tmp_path / "none.csv", "--fit", "x_table_mass_kg"],
    ):
        line = _one_error_line(twin(*args))
        assert f"{field}: must be within [" in line, line


@pytest.mark.parametrize("name", ["mid_size_xy", "linear_motor_xy"])
def test_no_viscous_friction_is_measured_by_fidelity_and_frf(tmp_path, name):
    """``friction_viscous_N_s_per_m = 0`` (the issue's divide by zero): a frictionless double
    integrator's proportional loop has a decay of exactly 0 (linear_motor_xy: 12 / 0, exit 70),
    or a rounding's -7e-7 1/s (mid_size_xy: taken as settled, then refused as never settling);
    the fidelity check's lead loop holds it, and the twin meets its transfer function; the
    open-loop FRF measures the model's modes."""
    path = tmp_path / f"frictionless_{name}.toml"
    text = (EXAMPLES / f"{name}.toml").read_text()
    path.write_text(re.sub(r"^friction_viscous_N_s_per_m = .*$", "friction_viscous_N_s_per_m = 0.0", text, flags=re.M))
    case = fidelity(str(path), frf_period_s=2.0, frf_tones=12)
    assert case["pass"], case
    result = twin("frf", path, "--duration", "3.3", "--loop", "open", "--json")
    assert result.returncode == 0, result.stderr
    assert json.loads(result.stdout)["parameters"]["x_friction_viscous_N_s_per_m"] == 0.0


@pytest.mark.parametrize("amplitude", ["1e-300", "0", "-1", "nan", "11"])
def test_an_frf_amplitude_out_of_its_range_is_refused(amplitude):
    line = _one_error_line(twin("frf", MID, "--amplitude", amplitude, "--duration", "3.3"))
    assert line.startswith("error: --amplitude = ") and "must be in [0.001, 10] V" in line


def test_fuzzed_machine_file_values_are_accepted_within_their_range_or_refused_naming_the_key(tmp_path):
    """Every numeric key of the example machine files at hostile values and just inside and
    outside its physical range (seeded): the schema accepts exactly the values within the
    range (and the machine's MJCF is generated, or its physical step refused as too coarse for
    a mode), and refuses the others naming the table, the key and the value; a sample of the
    refusals through ``twin mjcf`` is one error line, exit 2."""
    rng = random.Random(48)
    checked, refusals = 0, []
    for path in FILES:
        text = path.read_text()
        for table, key, match in _numeric_keys(text):
            model = _model(table, key, text)
            bounds = physical_range(model, key)
            values = rng.sample(HOSTILE, 3)
            if bounds is not None:
                values += [bounds.low, bounds.high, bounds.low / 10 or -1e-3, bounds.high * 10]
            for value in values:
                checked += 1
                edited = tmp_path / f"{checked}_{path.name}"
                edited.write_text(_with_value(text, match, value))
                inside = bounds.contains(value) if bounds is not None else None
                try:
                    machine = get_machine(str(edited))
                    machine.make_spec(machine.resolve())
                except TwinInputError as exc:
                    line = str(exc)
                else:
                    assert inside in (True, None), (table, key, value)
                    continue
                refusals.append(edited)
                if "too coarse for the drive train's" in line:  # a mode the physics step cannot follow
                    assert line.startswith("timestep_s = ") and inside, (key, value, line)
                    continue
                if f"{table} = " in line:  # a cross-check of the table (a root diameter over the screw's)
                    assert key in line, (key, value, line)
                    continue
                assert f"{table}.{key} = " in line, (key, value, line)
                if "out of any physical range" not in line:  # StrictSpec: a magnitude under 1e-15 or over 1e12
                    assert inside in (False, None), (key, value, line)
    assert checked > 400
    for edited in rng.sample(refusals, 10):
        _one_error_line(twin("mjcf", edited, "--out", tmp_path / "model.xml"))


@pytest.mark.parametrize(
    ("setting", "message"),
    [
        ("x_screw_diameter_m=1.0", "overrides.x_screw_diameter_m = 1.0: must be within [0.001, 0.5]"),
        ("delay_s=0.1", "overrides.delay_s = 0.1: must be within [0, 0.01]"),
        ("x_screw_root_diameter_m=0.05", "overrides.x_screw_root_diameter_m = 0.05: screw_root_diameter_m = 0.05"),
        ("x_motor_encoder_counts_per_rev=0.5", "overrides.x_motor_encoder_counts_per_rev = 0.5: must be within"),
    ],
)
def test_an_override_out_of_the_physical_range_is_refused(setting, message):
    """``--set`` goes through the same ranges and cross-checks as the file (the heavy machine's
    root diameter 25.6 mm may not exceed its 32 mm screw)."""
    line = _one_error_line(twin("fidelity", "--machine", EXAMPLES / "heavy_xy.toml", "--set", setting))
    assert message in line, line


def test_calibration_keeps_its_trials_within_the_physical_ranges(tmp_path):
    """A 100 t workpiece on mid_size_xy's X: its table's mass is not seen in a 0.1 s trace, and
    the solver's trials once ran below the 1 g bound (exit 2 during the fit); the fit now
    stays within the range and ends, the mass named as not identifiable."""
    path = tmp_path / "heavy_workpiece.toml"
    path.write_text(MID.read_text().replace("workpiece_mass_kg = 20.0", "workpiece_mass_kg = 1e5", 1))
    trace = tmp_path / "trace.csv"
    assert twin("excite", path, "--out", trace, "--simulate", "--duration", "0.1").returncode == 0
    result = calibrate(str(path), trace, ["x_table_mass_kg"])
    bounds = get_machine(str(path)).parameters["x_table_mass_kg"].bounds
    assert bounds.low <= result.parameters["x_table_mass_kg"] <= bounds.high


def test_calibrate_takes_the_physics_step_from_set(tmp_path):
    """``twin calibrate --set timestep_s=...``: the fit's twin runs at that step. A trace the
    twin made at 25 us gives back its hidden mass within 1e-6 at 25 us, and off by the
    integrator's own error at the machine's 50 us (100.145 kg)."""
    hidden = {"x_table_mass_kg": 100.0}
    dt, n = 1e-4, 1000
    u = 2.0 * np.sign(np.sin(2 * np.pi * 37 * np.arange(n) * dt))
    y = replay(build(str(MID), hidden, 2.5e-5), dt, np.c_[u, np.zeros(n)], np.zeros(2))[:, 0]
    trace = tmp_path / "trace.csv"
    write_table({"time_s": np.arange(n) * dt, "u_x_V": u, "pos_x_m": y}, trace)
    args = ["calibrate", MID, "--trace", trace, "--fit", "x_table_mass_kg", "--json"]
    fine = twin(*args, "--set", "timestep_s=2.5e-5")
    assert fine.returncode == 0, fine.stderr
    fitted = json.loads(fine.stdout)["fitted"]["x_table_mass_kg"]
    assert fitted == pytest.approx(100.0, rel=1e-6)
    coarse = json.loads(twin(*args).stdout)["fitted"]["x_table_mass_kg"]
    assert abs(coarse / 100.0 - 1) > 1e-3  # the machine's own step: the integrator's error (0.15 %)
    line = _one_error_line(twin(*args, "--set", "timestep_s=3e-5"))
    assert "must be a multiple of the timestep 3e-05 s" in line
    line = _one_error_line(twin(*args, "--set", "timestep_s=-1"))
    assert line.startswith("error: --set timestep_s = -1.0: must be in [")


@pytest.mark.slow
def test_values_on_the_physical_bounds_compute_or_refuse_in_every_command(tmp_path):
    """Seeded keys of mid_size_xy's X axis at a bound of their range, through fidelity, frf, tune
    and calibrate: each computes (0), diverges (3: the loop on the motor encoder unstable), or
    refuses with one line (2), never exit 70."""
    text = MID.read_text()
    trace = tmp_path / "trace.csv"
    assert twin("excite", MID, "--out", trace, "--simulate", "--duration", "0.1").returncode == 0
    keys = [(t, k, m) for t, k, m in _numeric_keys(text) if t in ("machine", "axes.x")]
    rng = random.Random(48)
    for table, key, match in rng.sample(keys, 6):
        bounds = physical_range(_model(table, key, text), key)
        if bounds is None:
            continue
        path = tmp_path / "edge.toml"
        path.write_text(_with_value(text, match, rng.choice([bounds.low, bounds.high])))
        for args in (
            ["fidelity", "--machine", path],
            ["frf", path, "--duration", "3.3"],
            ["tune", path, "--no-verify"],
            ["calibrate", path, "--trace", trace, "--fit", "x_table_mass_kg"],
        ):
            result = twin(*args)
            assert result.returncode in (0, 2, 3), (key, args[0], result.stderr[-300:])
            if result.returncode:
                errors = [line for line in result.stderr.splitlines() if line.startswith("error: ")]
                assert len(errors) == 1, result.stderr
