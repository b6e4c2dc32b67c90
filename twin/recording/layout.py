"""The blueprint: named time-series panels on the left (two columns); the machine in 3-D and,
for two axes, the contour seen from above on the right."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import rerun.blueprint as rrb

from twin.outcome import RunOutcome


def _machine_view(model, prefix: str, n_per_mm: float | None) -> rrb.Spatial3DView:
    """3-D view aimed at the workpiece from the front right, above the table; the name states
    the cutting-force arrow's scale when there is one."""
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    target = data.xpos[model.body("workpiece").id]
    extent = float((np.linalg.norm(data.geom_xpos[:, :2] - target[:2], axis=1) + model.geom_rbound).max())
    reach = 1.5 * extent
    name = "machine (3-D, m): bodies move with the time cursor"
    if n_per_mm is not None:
        name += f"; red arrow: cutting force on the workpiece, {n_per_mm:g} N per mm"
    return rrb.Spatial3DView(
        name=name,
        origin=f"{prefix}machine",
        eye_controls=rrb.EyeControls3D(
            position=target + reach * np.array([0.55, -0.8, 0.6]), look_target=target, eye_up=[0.0, 0.0, 1.0]
        ),
    )


def _contour_view(outcome: RunOutcome, prefix: str, gain: int) -> rrb.Spatial3DView:
    """The contour from straight above: +x right, +y up, the whole path in view."""
    result = outcome.run
    ref = result.ref[:, :, 0] * 1e3
    centre = (ref.min(axis=0) + ref.max(axis=0)) / 2
    height = 1.35 * max(float(np.ptp(ref, axis=0).max()), 1e-3)
    name = f"contour (mm, seen from above): reference grey, actual blue, error x{gain} red, tool yellow"
    if result.program is not None and result.program.lines.size:
        name = (
            f"part (mm, seen from above): path coloured by contour error (scale right), error x{gain} red, "
            "stock grey, machined outline white, tool yellow"
        )
        if outcome.part is not None:
            name += "; the virtual part's walls red where material is left, blue where overcut"
    return rrb.Spatial3DView(
        name=name,
        origin=f"{prefix}contour",
        eye_controls=rrb.EyeControls3D(
            position=[centre[0], centre[1], height], look_target=[centre[0], centre[1], 0.0], eye_up=[0.0, 1.0, 0.0]
        ),
    )


def readable_y_axis(values) -> rrb.ScalarAxis | None:
    """A y range for a panel whose data spans less than three of its power-of-ten grid steps.

    Rerun's plots label grid lines at powers of ten only, so data spanning, say, -70 to 70 in
    a short panel shows a single label (0): its size cannot be read.  The range is then widened
    to whole steps (here -100 to 100), which puts at least two labelled lines in view.  None
    (Rerun's own range) otherwise.
    """
    values = np.asarray(values, float)
    lo, hi = float(values.min()), float(values.max())
    if not hi > lo:
        return None
    step = 10.0 ** math.floor(math.log10(hi - lo))
    if (hi - lo) / step >= 3:
        return None
    lo, hi = math.floor(lo / step) * step, math.ceil(hi / step) * step
    margin = 0.06 * (hi - lo)  # so that the labels of the outer lines are not cut at the edges
    return rrb.ScalarAxis(range=(lo - margin, hi + margin))


def series_views(result, prefix: str = "") -> list:
    """The time-series panels of one run, for a two-column grid: the joint states get their own
    cell where it would stay empty, else they sit in tabs behind the positions."""
    machine = result.machine
    quantity, unit = machine.drive_quantity(machine.axes[0])
    drive = result.actuator_force[:, [machine.model.actuator(a.actuator).id for a in machine.axes]]
    parts = [
        (a.name, part)
        for a in machine.axes
        for part, joint in (("motor", a.motor_joint), ("screw", a.screw_joint))
        if joint
    ]
    tables = [f"{prefix}joints/{a.name}/table/velocity" for a in machine.axes]
    joints = [
        rrb.TimeSeriesView(
            name="joint angles (rad)", contents=[f"{prefix}joints/{a}/{part}/angle" for a, part in parts]
        ),
        rrb.TimeSeriesView(
            name="joint speeds (rad/s), table velocity (mm/s)",
            contents=[f"{prefix}joints/{a}/{part}/velocity" for a, part in parts] + tables,
        ),
    ]
    if not parts:  # linear motors: no rotating joints
        joints = [rrb.TimeSeriesView(name="table velocity (mm/s)", contents=tables)]
    position_mm = np.concatenate([result.ref[:, :, 0], result.table_position_m()]) * 1e3
    views = [
        rrb.TimeSeriesView(
            name="position (mm): reference and actual",
            contents=[f"{prefix}reference/**", f"{prefix}actual/**"],
            axis_y=readable_y_axis(position_mm),
        ),
        rrb.TimeSeriesView(
            name="tracking error = reference - actual (µm)",
            origin=f"{prefix}error",
            axis_y=readable_y_axis(result.error_m() * 1e6),
        ),
        rrb.TimeSeriesView(name="control input (V)", origin=f"{prefix}control", axis_y=readable_y_axis(result.u_V)),
        rrb.TimeSeriesView(
            name=f"drive {quantity} ({unit})", origin=f"{prefix}{quantity}/drive", axis_y=readable_y_axis(drive)
        ),
    ]
    if result.has_workpiece_force:
        views.append(
            rrb.TimeSeriesView(
                name="cutting force on the workpiece (N)",
                origin=f"{prefix}force/cutting",
                axis_y=readable_y_axis(result.workpiece_force_N[:, : len(machine.axes)]),
            )
        )
    if result.vibration_probe.any():
        views.append(
            rrb.TimeSeriesView(
                name="chatter indicator: once-per-tooth vibration / feed per tooth (1)", origin=f"{prefix}chatter"
            )
        )
    if len(views) % 2:
        return [*views, rrb.Tabs(*joints)]
    return [rrb.Tabs(views[0], *joints, active_tab=0), *views[1:]]


def run_layout(
    outcome: RunOutcome, *, prefix: str, gain: int | None, n_per_mm: float | None, name: str | None = None
) -> rrb.Horizontal:
    """One run: series left; machine (and the contour when ``gain`` is given) right."""
    result = outcome.run
    right = [_machine_view(result.machine.model, prefix, n_per_mm)]
    if gain is not None:
        right.append(_contour_view(outcome, prefix, gain))
    # two columns of series: panels tall enough for Rerun to label their grid lines
    return rrb.Horizontal(
        rrb.Grid(*series_views(result, prefix), grid_columns=2),
        rrb.Vertical(*right),
        column_shares=[0.45, 0.55],
        name=name,
    )


def blueprint(results: dict[str, RunOutcome], gains: dict, arrow_scales: dict) -> rrb.Blueprint:
    """One run fills the window; several get a tab each (named as the runs).  ``gains`` and
    ``arrow_scales`` per run name: contour error magnification and N per mm of force arrow
    (None where there is no contour or no cutting force)."""
    if list(results) == [""]:
        return rrb.Blueprint(
            run_layout(results[""], prefix="", gain=gains[""], n_per_mm=arrow_scales[""]), collapse_panels=True
        )
    return rrb.Blueprint(
        rrb.Tabs(
            *[
                run_layout(r, prefix=f"{name}/", gain=gains[name], n_per_mm=arrow_scales[name], name=name)
                for name, r in results.items()
            ]
        ),
        collapse_panels=True,
    )
