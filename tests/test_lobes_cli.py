"""``twin lobes`` and ``twin.lobes``: the Insperger-Stepan benchmark from a scenario, a program's
lines on the lobes, bad input."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from cli_process import twin

import twin as api
from twin.scenario.files import bundled_scenarios

#: The benchmark's mode (Insperger and Stepan 2004) on slot_linear_motor's end_milling (a
#: 10 mm two-flute slot), its coefficients K_t = 600 N/mm^2, K_n = 200 N/mm^2.
BENCHMARK = [
    "--set",
    "disturbances.0.dynamics={modes=[{direction='x',frequency_hz=922.0,damping_ratio=0.011,modal_mass_kg=0.03993}]}",
    "--set",
    "disturbances.0.coefficients={K_tc=600.0,K_rc=200.0}",
]


def test_benchmark_lobes_from_the_command_line(tmp_path):
    """Full slot: the zero-order lowest is the averaged closed form 2 k zeta (1 + zeta) / (N K_n
    / 4) = 0.298 mm; the semi-discretization's at 10 000 rpm 0.322 mm (test_stability's
    reference); the PNG is written."""
    out = twin("lobes", "slot_linear_motor", *BENCHMARK, "--rpm", "5000:25000:81", "--json", "--plots", tmp_path)
    assert out.returncode == 0, out.stderr
    summary = json.loads(out.stdout)
    k = 0.03993 * (2 * math.pi * 922.0) ** 2
    closed_mm = 2 * k * 0.011 * 1.011 / (2 * 200e6 / 4) * 1e3
    assert summary["lowest"]["zoa"]["critical_depth_mm"] == pytest.approx(closed_mm, rel=0.02)
    at_10000 = next(r for r in summary["lobes"]["sd"] if r["spindle_rpm"] == 10000.0)
    assert at_10000["critical_depth_mm"] == pytest.approx(0.3224, rel=0.01)
    assert set(summary["lobes"]) == {"zoa", "sd"} and len(summary["lobes"]["zoa"]) == 81
    assert (tmp_path / "lobes_slot_linear_motor.png").stat().st_size > 10_000


def test_a_programs_lines_on_the_lobes():
    """gcode_slot_passes (its tool's illustrative modes): the 16 mm pass (line 22) chatters, the
    2 mm passes do not; the API gives the same lines as the command line."""
    found = api.lobes("gcode_slot_passes", method="zoa", rpm=(5000.0, 20000.0, 60))
    lines = {r["line"]: r["stability"] for r in found.summary["lines"]}
    assert lines[22]["margin"] < 1 < lines[14]["margin"]
    assert lines[22]["text"].startswith("line 22: 16.00 mm at 10 000 rpm, critical ")
    assert found.to_pandas().shape == (60, 2)


@pytest.mark.parametrize(
    ("args", "field"),
    [
        (["slot_linear_motor"], "tool.dynamics"),
        (["slot_linear_motor", *BENCHMARK, "--rpm", "5000:25000"], "--rpm"),
        (["slot_linear_motor", *BENCHMARK, "--rpm", "9000:5000:10"], "--rpm"),
        (["slot_linear_motor", *BENCHMARK, "--immersion", "0"], "--immersion"),
        (["slot_linear_motor", *BENCHMARK, "--method", "fast"], "--method"),
        (["slot_linear_motor", *BENCHMARK, "--depth-max", "-1"], "--depth-max"),
    ],
)
def test_bad_input_is_one_line_and_exit_2(args, field):
    out = twin("lobes", *args, "--method", "zoa") if "--method" not in args else twin("lobes", *args)
    assert out.returncode == 2, out.stdout + out.stderr
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"error: {field}"), out.stderr


def test_a_runs_lines_carry_their_chatter_check():
    """twin run's per-line table: the first pass (line 14, a 2 mm slot) carries the same check
    as twin lobes gives it."""
    rows = {r["line"]: r for r in api.run("gcode_slot_passes", duration_s=1.0).summary["lines"]}
    checked = api.lobes("gcode_slot_passes", method="zoa", rpm=(2500.0, 20000.0, 20)).summary["lines"]
    assert rows[14]["stability"] == next(r["stability"] for r in checked if r["line"] == 14)
    assert 13 not in rows or "stability" not in rows[13]  # the plunge takes no side chip


def test_a_measured_frf_gives_the_modes_lobes(tmp_path):
    """The benchmark's mode written as a tap-test CSV (0.5 Hz lines, beside the scenario file):
    its zero-order lobes are the mode's within 0.5 %; semi-discretization of it is refused."""
    f = np.arange(300.0, 3000.0, 0.5)
    k, zeta, fn = 0.03993 * (2 * math.pi * 922.0) ** 2, 0.011, 922.0
    g = 1 / (k * (1 - (f / fn) ** 2 + 2j * zeta * f / fn))
    rows = "\n".join(f"{a},{b.real},{b.imag},0,0" for a, b in zip(f, g))
    (tmp_path / "tap.csv").write_text("frequency_hz,xx_real,xx_imag,yy_real,yy_imag\n" + rows + "\n")
    text = bundled_scenarios()["slot_linear_motor"].read_text()
    (tmp_path / "s.toml").write_text(text + '\n[disturbances.dynamics]\nfrf_file = "tap.csv"\n')
    coefficients = {"disturbances.0.coefficients": {"K_tc": 600.0, "K_rc": 200.0}}
    measured = api.lobes(tmp_path / "s.toml", method="zoa", rpm=(5000.0, 25000.0, 50), **coefficients)
    modes = twin("lobes", "slot_linear_motor", *BENCHMARK, "--rpm", "5000:25000:50", "--method", "zoa", "--json")
    expected = json.loads(modes.stdout)["lobes"]["zoa"]
    got = measured.summary["lobes"]["zoa"]
    assert [r["critical_depth_mm"] for r in got] == pytest.approx([r["critical_depth_mm"] for r in expected], rel=5e-3)
    refused = twin("lobes", tmp_path / "s.toml", "--method", "sd")
    assert refused.returncode == 2 and "frf_file" in refused.stderr and "sd needs modes" in refused.stderr


def test_the_lines_parquet_has_the_check_as_columns(tmp_path):
    import pandas as pd

    run = api.run("gcode_slot_passes", duration_s=1.0)
    frame = pd.read_parquet(run.lines_to_parquet(tmp_path / "lines.parquet")).set_index("line")
    row = next(r for r in run.summary["lines"] if r["line"] == 14)["stability"]
    assert frame.loc[14, "stability_critical_depth_mm"] == row["critical_depth_mm"]
    assert frame.loc[14, "stability_stable_rpm_high"] == row["stable_rpm"][1]
    assert pd.isna(frame.loc[11, "stability_margin"])  # a rapid


def test_a_programs_lines_in_the_text_report():
    """With a stock and a program the text report ends with the chatter check of the cutting
    lines (a crash with an internal error before: the lobes' lines were read as per-line rows)."""
    out = twin("lobes", "gcode_slot_passes", "--method", "zoa", "--rpm", "5000:25000:20")
    assert out.returncode == 0, out.stderr
    lines = out.stdout.splitlines()
    assert lines[-2] == "  chatter check (zero-order lobes): 4 cutting line(s), 1 over their critical depth"
    assert lines[-1].startswith("    line 22: 16.00 mm at 10 000 rpm, critical 3.08 mm")
