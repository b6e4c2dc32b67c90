"""Rerun recordings, read back with Rerun's own reader."""

from controllers import make_controller
from twin.machines import build
from twin.recording import read_back, record
from twin.references import Circle, Step
from twin.sim.runner import simulate


def test_recording_entities_and_counts(tmp_path):
    bm = build("cncmt_xy")
    res = simulate(bm, make_controller("seed000_robust_pi", 1e-3, axes=("x", "y")),
                   Circle(5.0, 600.0), 0.5, 1e-3)
    path = record(res, tmp_path / "run.rrd")
    counts = read_back(path)
    for axis in ("x", "y"):
        for entity in (f"machine/{axis}/motor/angle", f"machine/{axis}/screw/velocity",
                       f"machine/{axis}/table/position", f"reference/{axis}", f"error/{axis}",
                       f"control/{axis}/u", f"cutting/force/{axis}", f"machine/{axis}/drive/force"):
            assert counts["/" + entity] == 500, entity
    assert counts["/contour/reference"] == 1 and counts["/contour/actual"] == 1
    assert any(k.startswith("/contour/error_x") for k in counts)


def test_recording_decimates_long_runs(tmp_path):
    bm = build("cncmt")
    res = simulate(bm, make_controller("seed000_imc", 1e-4), Step(0.01), 1.0, 1e-4)
    counts = read_back(record(res, tmp_path / "long.rrd", max_points=1000))
    assert counts["/machine/x/table/position"] == 1000
    assert "/contour/reference" not in counts
