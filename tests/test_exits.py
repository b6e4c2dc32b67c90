"""The command line's contract (twin/exits.py): what each exit code means, one error line,
no warning, strict JSON; and the rows of issue 33's table, each one error line."""

import json
import math
import warnings
from pathlib import Path

import numpy as np
import pytest

import twin.api
import twin.fidelity
from twin import exits
from twin.cli import run_cli


def _run(capsys, argv: list[str]) -> tuple[int, str, list[str]]:
    """Exit code, stdout and stderr's lines of the command line ``argv`` in process."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        code = run_cli(argv)
    out, err = capsys.readouterr()
    assert not caught, [str(w.message) for w in caught]
    return code, out, err.splitlines()


def test_strict_json_writes_null_and_names_what_was_not_finite():
    text = exits.strict_json({"a": 1.5, "b": [math.inf, -math.inf], "c": {"d": math.nan}})
    assert json.loads(text) == {
        "a": 1.5,
        "b": [None, None],
        "c": {"d": None},
        "non_finite": {"b.0": "inf", "b.1": "-inf", "c.d": "nan"},
    }


@pytest.mark.parametrize(
    ("argv", "words"),
    [
        (["run", "x", "--max-steps", "abc"], "twin run: Invalid value for '--max-steps'"),
        (["bogus"], "No such command 'bogus'"),
        (["frf"], "twin frf: Missing argument 'machine'"),
        (["run", "demo_circle_cncmt_xy", "--bogus"], "No such option: --bogus"),
    ],
)
def test_a_usage_error_is_one_line_and_exit_code_2(capsys, argv, words):
    code, out, err = _run(capsys, argv)
    assert code == 2, err
    assert out == "", err
    assert len(err) == 1, err
    assert err[0].startswith("error: "), err
    assert words in err[0], err


def test_a_warning_inside_a_command_is_an_internal_error_not_a_warning_line(capsys, monkeypatch):
    def overflowing(*args, **kwargs):
        return np.float64(1e308) * 10.0  # numpy's RuntimeWarning: overflow

    monkeypatch.setattr(twin.api, "run", overflowing)
    code, out, err = _run(capsys, ["run", "demo_circle_cncmt_xy", "--json"])
    assert code == exits.INTERNAL_ERROR, err
    assert out == "", err
    assert len(err) == 1, err
    assert err[0].startswith("error: internal error, a bug of the twin: RuntimeWarning: overflow"), err
    assert "tests/test_exits.py:" in err[0]


def test_a_failed_fidelity_target_is_exit_code_4_after_the_report(capsys, monkeypatch):
    monkeypatch.setattr(twin.fidelity, "TARGETS", {**twin.fidelity.TARGETS, "time_nrmse": 0.0})
    code, out, err = _run(capsys, ["fidelity", "--machine", "cncmt", "--json"])
    report = json.loads(out)
    assert code == exits.CHECK_FAILED
    assert report[0]["pass"] is False
    assert report[0]["time_nrmse"] > 0
    assert err == ["error: 1 case(s) miss their fidelity targets: cncmt"]


def test_an_output_the_system_cannot_write_is_one_line(capsys, tmp_path):
    long_name = tmp_path / ("a" * 300 + ".rrd")
    code, out, err = _run(capsys, ["run", "demo_circle_cncmt_xy", "--rrd", str(long_name)])
    assert code == 2, err
    assert out == "", err
    assert len(err) == 1, err
    assert "over the system's 255 bytes" in err[0], err


@pytest.mark.parametrize(
    ("argv", "words"),
    [
        (
            ["run", "gcode_choi1999_circle_stock", "--set", "stock.corners_mm=[[-1e308,-1e308],[1e308,1e308]]"],
            "stock.corners_mm.0.0 = -1e+308: Input should be greater than or equal to -10000",
        ),
        (
            [
                "run",
                "gcode_choi1999_circle_stock",
                "--set",
                "stock.islands_mm=[[[-100.0,-100.0],[100.0,-100.0],[100.0,100.0],[-100.0,100.0]]]",
            ],
            "stock.islands_mm = '1 island(s)': leave no material",
        ),
        (
            ["run", "gcode_choi1999_circle", "--set", "reference.work_offsets_mm={G54=[1e300,0.0,0.0]}"],
            "work_offsets_mm.G54.0 = 1e+300: Input should be less than or equal to 10000",
        ),
        (["run", "step_cncmt_hinf", "--set", "reference.amplitude_m=1e308"], "1e+308 is beyond +-1e+12"),
        (["gcode", "a" * 300 + ".ngc"], "File name too long"),
        (["run", "gcode_choi1999_circle", "--set", f'reference.file="{"a" * 300}.ngc"'], "File name too long"),
        (["run", "demo_circle_cncmt_xy", "--set", "sensors.noise_std_m=1e308"], "less than or equal to 0.001"),
        (["gcode", "/dev/zero"], "is not a regular file"),
    ],
)
def test_the_hostile_rows_of_issue_33_are_one_line(capsys, argv, words):
    code, out, err = _run(capsys, [*argv, "--json"] if argv[0] == "run" else argv)
    assert code == 2, err
    assert out == "", err
    assert len(err) == 1, err
    assert words in err[0], err


@pytest.mark.parametrize(
    ("key", "value", "words"),
    [
        ("gear_ratio = 1.0", "gear_ratio = 1e308", "axes.x.gear_ratio = 1e+308: must be within [0.01, 1000]"),
        (
            "c_torsion_N_m_s_per_rad = 0.05",
            "c_torsion_N_m_s_per_rad = 1e308",
            "c_torsion_N_m_s_per_rad = 1e+308: must be within",
        ),
        (
            "friction_viscous_N_s_per_m = 150.0",
            "friction_viscous_N_s_per_m = 1e30",
            "friction_viscous_N_s_per_m = 1e+30: must be within [0, 1e+08]",
        ),
    ],
)
def test_machine_file_values_beyond_any_physical_range_are_one_line(capsys, tmp_path, key, value, words):
    text = (Path(__file__).parent.parent / "examples" / "machines" / "mid_size_xy.toml").read_text()
    path = tmp_path / "hostile_xy.toml"
    path.write_text(text.replace(key, value, 1))
    for argv in (["tune", str(path), "--json", "--no-verify"], ["frf", str(path), "--json"]):
        code, out, err = _run(capsys, argv)
        assert code == 2, err
        assert out == "", err
        assert len(err) == 1, err
        assert words in err[0], err
