"""The public Python API (``import twin``) and the runnable examples that use it."""

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from cli_process import twin as _twin

import twin
from twin.errors import SimulationDiverged, TwinInputError

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"


def test_run_summary_equals_the_cli_json_and_settings_take_both_spellings():
    settings = {"duration_s": 0.2, "disturbances.0.axial_depth_mm": 1.0}
    run = twin.run("slot_linear_motor", **settings)
    cli = _twin(
        "run", "slot_linear_motor", "--json", "--set", "duration_s=0.2", "--set", "disturbances.0.axial_depth_mm=1.0"
    )
    assert cli.returncode == 0, cli.stderr
    assert run.summary == json.loads(cli.stdout)
    same = twin.run("slot_linear_motor", duration_s=0.2, disturbances__0__axial_depth_mm=1.0)
    assert same.summary == run.summary
    assert twin.load("slot_linear_motor", **settings).disturbances[0].axial_depth_mm == 1.0


def test_to_pandas_is_time_indexed_with_units_in_the_names():
    run = twin.run("choi1999_mimo_air_cut", duration_s=0.1)
    frame = run.to_pandas()
    result = run.result
    assert isinstance(frame, pd.DataFrame)
    assert frame.index.name == "time (s)"
    np.testing.assert_array_equal(frame.index.to_numpy(), result.t_s)
    pos = result.table_position_m()
    np.testing.assert_allclose(frame["actual/y (mm)"], pos[:, 1] * 1e3)
    np.testing.assert_allclose(frame["error/x (µm)"], (result.ref[:, 0, 0] - pos[:, 0]) * 1e6)
    np.testing.assert_allclose(frame["control/x (V)"], result.u_V[:, 0])
    assert {"reference/x (mm)", "force/drive/x (N)", "joints/y/table/velocity (mm/s)"} <= set(frame.columns)
    # the largest error in the frame is the summary's (every tick is recorded here)
    assert frame["error/x (µm)"].abs().max() == pytest.approx(run.summary["max_tracking_error_um"]["x"], abs=1e-3)


def test_bad_settings_and_divergence_are_the_twins_errors():
    with pytest.raises(TwinInputError, match="nope"):
        twin.run("slot_linear_motor", nope=1)
    with pytest.raises(TwinInputError, match=r"disturbances\.9\.spindle_rpm"):
        twin.load("slot_linear_motor", **{"disturbances.9.spindle_rpm": 1.0})
    with pytest.raises(TwinInputError, match="source = 'smith2000'"):
        twin.reproduce("smith2000")
    with pytest.raises(SimulationDiverged) as err:
        twin.run("step_cncmt_hinf", controller={"type": "pid", "params": {"kp": 1e9}}, duration_s=0.5)
    partial = twin.run(
        "step_cncmt_hinf", controller={"type": "pid", "params": {"kp": 1e9}}, duration_s=0.5, keep_partial=True
    )
    assert partial.status == "diverged"
    assert partial.summary["sim_time_s"] == err.value.sim_time_s


@pytest.mark.parametrize(
    "script, args, check",
    [
        ("run_and_plot.py", ["--duration", "0.3"], "run_and_plot.png"),
        ("compare_controllers.py", ["--duration", "0.3"], "MIMO H-infinity"),
        ("sweep_box.py", ["--samples", "4", "--workers", "1"], "4 samples in"),
        ("tune_vs_papers.py", ["--duration", "0.3"], "tuned servo_cascade (ours)"),
        (
            "frf_accuracy.py",
            [
                "--machine",
                "sgm7j_axis",
                "--excitation",
                "prbs",
                "--friction",
                "off",
                "--no-calibration",
                "--duration",
                "3.3",
            ],
            "sgm7j_axis  x motor prbs      off max|err|  0.0",  # each mode within 0.1 % of the lumped model
        ),
        pytest.param(
            "verify_margins.py",
            ["--machines", "googol_xy", "--gains", "kp_vel"],
            "| googol_xy | dual | x | kp_vel |",
            marks=pytest.mark.slow,  # three designs and 56 runs of 0.5 s: about 30 s
        ),
        pytest.param(
            "feed_override.py",
            ["--overrides", "0.8", "1.2", "--workers", "1", "--duration", "1.0"],
            "largest feed override with rms_contour_error_feed_um < 10 µm:",
            marks=pytest.mark.slow,  # eight 1 s runs on a Dask cluster
        ),
    ],
)
def test_examples_run(tmp_path, script, args, check):
    extra = (
        ["--out", str(tmp_path)]
        if script not in ("compare_controllers.py", "tune_vs_papers.py", "verify_margins.py", "frf_accuracy.py")
        else []
    )
    r = subprocess.run(
        [sys.executable, str(EXAMPLES / script), *args, *extra],
        capture_output=True,
        text=True,
        timeout=300,
        cwd=tmp_path,
    )
    assert r.returncode == 0, r.stderr
    assert check in r.stdout
    if script == "run_and_plot.py":
        assert (tmp_path / "run_and_plot.png").stat().st_size > 10_000
    if script == "sweep_box.py":
        assert (tmp_path / "square_sabau_pid_sweep.parquet").is_dir()
    if script == "feed_override.py":  # two overrides at the four vertices of the m_x, m_y box
        assert "(8 runs)" in r.stdout
        assert "0.8" in r.stdout
        assert "1.2" in r.stdout
