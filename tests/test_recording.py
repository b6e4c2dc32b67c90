"""Rerun recordings, read back with Rerun's own reader: entity paths, archetypes, sample counts,
body poses against the simulated joints, the contour seen from above with +y up."""

import mujoco
import numpy as np
import pytest
from rerun.chunk import RrdReader

from controllers import make_controller
from twin.machines import build
from twin.machining.cutting import AverageForce
from twin.recording import read_back, record, record_runs
from twin.references import Circle, Step
from twin.scales import contour_gain, round_down, round_up
from twin.sim.runner import simulate


def _columns(path, entity: str) -> dict:
    """Every component of an entity, static and over time, as Python lists by column name."""
    out = {}
    for chunk in RrdReader(str(path)).store().stream():
        if chunk.entity_path == entity:
            batch = chunk.to_record_batch()
            for name in batch.schema.names:
                out.setdefault(name, []).extend(batch.column(name).to_pylist())
    return out


def _views(path) -> dict:
    """Blueprint components per view entity."""
    reader = RrdReader(str(path))
    views = {}
    for chunk in reader.store(store=reader.blueprints()[0]).stream():
        if chunk.entity_path.startswith("/view/"):
            view = "/".join(chunk.entity_path.split("/")[:3])
            batch = chunk.to_record_batch()
            for name in batch.schema.names:
                if ":" in name:  # components, not the row ids and times
                    views.setdefault(view, {})[name] = batch.column(name).to_pylist()[-1]
    return views


@pytest.fixture(scope="module")
def circle_run():
    bm = build("cncmt_xy")
    return simulate(
        bm,
        make_controller("yadav2020_robust_pi", 1e-3, axes=("x", "y")),
        Circle(5.0, 600.0),
        duration_s=0.5,
        control_period_s=1e-3,
    )


def test_series_are_named_and_counted(circle_run, tmp_path):
    counts = read_back(record(circle_run, tmp_path / "run.rrd"))
    for axis in ("x", "y"):
        for entity in (
            f"reference/{axis}",
            f"actual/{axis}",
            f"error/{axis}",
            f"control/{axis}",
            f"torque/drive/{axis}",
            f"joints/{axis}/motor/angle",
            f"joints/{axis}/screw/velocity",
            f"joints/{axis}/table/velocity",
        ):
            assert counts["/" + entity] == 500 + 1, entity  # 500 ticks + the static legend name and colour
        assert f"/force/cutting/{axis}" not in counts  # no force model in this run
    names = {
        tuple(_columns(tmp_path / "run.rrd", f"/{e}/x")["SeriesLines:names"][0])
        for e in ("reference", "actual", "error", "control")
    }
    assert names == {("x reference (mm)",), ("x actual (mm)",), ("x error (µm)",), ("x control input (V)",)}


def test_machine_geometry_and_poses_follow_the_joints(circle_run, tmp_path):
    path = record(circle_run, tmp_path / "run.rrd")
    counts = read_back(path)
    model = circle_run.machine.model
    geoms = [k for k in counts if k.count("/") == 3 and k.startswith("/machine/") and "cutting" not in k]
    assert len(geoms) == model.ngeom  # boxes and cylinders: every geom is drawn
    assert "Cylinders3D:radii" in _columns(path, "/machine/x_screw/x_screw_marker") or "Boxes3D:half_sizes" in _columns(
        path, "/machine/x_screw/x_screw_marker"
    )
    pos = circle_run.table_position_m()
    for axis, body in ((0, "x_table"), (1, "y_table")):
        translation = np.array([row[0] for row in _columns(path, f"/machine/{body}")["Transform3D:translation"]])
        assert len(translation) == 500
        moved = translation[:, axis] - translation[0, axis]  # the body's world position follows its slide
        np.testing.assert_allclose(moved, pos[:, axis] - pos[0, axis], atol=1e-7)  # float32 in the file
        assert np.ptp(moved) > 1e-3  # 5 mm along a 5 mm-radius circle: the table really moves
    screw = np.array([row[0] for row in _columns(path, "/machine/x_screw")["Transform3D:quaternion"]])
    assert np.ptp(screw, axis=0).max() > 0.01  # the screw (and its marker) turns
    assert _columns(path, "/machine/spindle")["Transform3D:translation"]  # static body, logged once
    assert "/machine/cutting_force" not in counts


def test_contour_is_seen_from_above_with_y_up(circle_run, tmp_path):
    path = record(circle_run, tmp_path / "run.rrd")
    gain = contour_gain(circle_run)
    counts = read_back(path)
    assert counts["/contour/tool"] == 500 + 1
    assert counts[f"/contour/error_x{gain}"] == 1
    assert 10 <= gain <= 1000
    assert gain == round_down(gain)
    strip = np.array(_columns(path, "/contour/actual")["LineStrips3D:strips"][0][0])
    pos_mm = circle_run.table_position_m() * 1e3
    np.testing.assert_allclose(strip[:, :2], pos_mm, atol=1e-4)  # the machine's y, not mirrored
    assert (strip[:, 2] == 0).all()
    coordinates = _columns(path, "/contour")["ViewCoordinates:xyz"][0]
    assert coordinates == [[3, 5, 1]]  # x Right, y Forward, z Up (Rerun codes 3, 5, 1): RIGHT_HAND_Z_UP
    (view,) = [v for v in _views(path).values() if v["ViewBlueprint:space_origin"] == ["contour"]]
    assert view["ViewBlueprint:class_identifier"] == ["3D"]
    assert f"error x{gain}" in view["ViewBlueprint:display_name"][0]
    eye, target = view["EyeControls3D:position"][0], view["EyeControls3D:look_target"][0]
    assert view["EyeControls3D:eye_up"] == [[0.0, 1.0, 0.0]]  # +y up on the screen
    assert eye[:2] == pytest.approx(target[:2])
    assert eye[2] > target[2]  # straight down from above: +x right


def test_cutting_force_arrow_and_series(tmp_path):
    bm = build("linear_motor_xy")
    force = AverageForce(k_il_N_s_per_m=-1800.0, k_c_N_s_per_m=1800.0)
    res = simulate(
        bm,
        make_controller("pid", 1e-3, {"kp": 2e4}, axes=("x", "y")),
        Circle(20.0, 2400.0),
        duration_s=0.3,
        control_period_s=1e-3,
        disturbances=(force,),
    )
    path = record(res, tmp_path / "cut.rrd")
    counts = read_back(path)
    assert counts["/force/cutting/x"] == counts["/force/cutting/y"] == 300 + 1
    assert counts["/force/drive/x"] == 300 + 1  # a linear motor: force in N, not a torque
    arrow = _columns(path, "/machine/cutting_force")
    vectors = np.array([row[0] for row in arrow["Arrows3D:vectors"] if row])
    scale = round_up(np.abs(res.workpiece_force_N).max() / 100.0)  # N per mm: the longest arrow <= 0.1 m
    np.testing.assert_allclose(vectors, res.workpiece_force_N * 1e-3 / scale, rtol=1e-5, atol=1e-9)
    names = [v["ViewBlueprint:display_name"][0] for v in _views(path).values()]
    assert any(f"{scale:g} N per mm" in n for n in names)


def test_recording_decimates_long_runs(tmp_path):
    bm = build("cncmt")
    res = simulate(bm, make_controller("yadav2020_imc", 1e-4), Step(0.01), duration_s=1.0, control_period_s=1e-4)
    path = record(res, tmp_path / "long.rrd", max_points=1000)
    counts = read_back(path)
    assert counts["/actual/x"] == 1000 + 1
    assert counts["/machine/x_table"] == 1000
    assert "/contour/reference" not in counts


def test_several_runs_get_a_prefix_each(tmp_path):
    bm = build("cncmt")
    runs = {
        name: simulate(bm, make_controller(name, 1e-3), Step(0.01), duration_s=0.2, control_period_s=1e-3)
        for name in ("yadav2020_imc", "yadav2020_robust_pi")
    }
    counts = read_back(record_runs(runs, tmp_path / "two.rrd"))
    assert counts["/yadav2020_imc/actual/x"] == counts["/yadav2020_robust_pi/machine/x_table"] + 1 == 201


def test_round_numbers():
    assert [round_up(x) for x in (0.3, 1.0, 1.2, 3.0, 7.0, 42.0)] == [0.5, 1.0, 2.0, 5.0, 10.0, 50.0]
    assert [round_down(x) for x in (0.3, 1.0, 1.2, 3.0, 7.0, 42.0)] == [0.2, 1.0, 1.0, 2.0, 5.0, 20.0]


def test_every_bundled_machine_draws_every_geom():
    from twin.machines import MACHINES
    from twin.recording.machine3d import geom_shape

    for name in MACHINES:
        model = build(name).model
        assert all(geom_shape(model, g) is not None for g in range(model.ngeom)), name
        assert mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, "tool_tip") >= 0, name


def test_short_ranges_are_widened_to_labelled_grid_lines():
    """Data spanning under three power-of-ten steps gets whole steps plus a 6 % margin; wider
    data keeps Rerun's own range."""
    from twin.recording.layout import readable_y_axis

    assert readable_y_axis([-70.0, 70.0]).range.as_arrow_array().to_pylist() == [[-112.0, 112.0]]
    assert readable_y_axis([0.02, 0.166]).range.as_arrow_array().to_pylist() == [pytest.approx([-0.012, 0.212])]
    assert readable_y_axis([-400.0, 9000.0]) is None
    assert readable_y_axis([5.0, 5.0]) is None
