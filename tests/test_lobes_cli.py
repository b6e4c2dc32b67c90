"""``twin lobes`` and ``twin.lobes``: the Insperger-Stepan benchmark from a scenario, a program's
lines on the lobes, bad input."""

from __future__ import annotations

import json
import math

import pytest
from cli_process import twin

import twin as api

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
