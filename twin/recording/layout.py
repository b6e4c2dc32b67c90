"""The blueprint: named time-series panels on the left; the machine in 3-D and, for two axes,
the contour seen from above on the right."""

from __future__ import annotations

import mujoco
import numpy as np
import rerun.blueprint as rrb


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
    return rrb.Spatial3DView(name=name, origin=f"{prefix}machine",
                             eye_controls=rrb.EyeControls3D(position=target + reach * np.array([0.55, -0.8, 0.6]),
                                                            look_target=target, eye_up=[0.0, 0.0, 1.0]))


def _contour_view(result, prefix: str, gain: int) -> rrb.Spatial3DView:
    """The contour from straight above: +x right, +y up, the whole path in view."""
    ref = result.ref[:, :, 0] * 1e3
    centre = (ref.min(axis=0) + ref.max(axis=0)) / 2
    height = 1.35 * max(float(np.ptp(ref, axis=0).max()), 1e-3)
    return rrb.Spatial3DView(
        name=f"contour (mm, seen from above): reference grey, actual blue, error x{gain} red, tool yellow",
        origin=f"{prefix}contour",
        eye_controls=rrb.EyeControls3D(position=[centre[0], centre[1], height], look_target=[centre[0], centre[1], 0.0],
                                       eye_up=[0.0, 1.0, 0.0]))


def series_views(result, prefix: str = "") -> list:
    """The time-series panels of one run (positions with the joint states behind tabs)."""
    machine = result.machine
    quantity, unit = machine.drive_quantity(machine.axes[0])
    joints = [rrb.TimeSeriesView(name="joint angles (rad)", origin=f"{prefix}joints",
                                 contents=[f"{prefix}joints/*/motor/angle", f"{prefix}joints/*/screw/angle"]),
              rrb.TimeSeriesView(name="joint speeds (rad/s), table velocity (mm/s)", origin=f"{prefix}joints")]
    views = [rrb.Tabs(rrb.TimeSeriesView(name="position (mm): reference and actual",
                                         contents=[f"{prefix}reference/**", f"{prefix}actual/**"]),
                      *joints, active_tab=0),
             rrb.TimeSeriesView(name="tracking error = reference - actual (µm)", origin=f"{prefix}error"),
             rrb.TimeSeriesView(name="control input (V)", origin=f"{prefix}control"),
             rrb.TimeSeriesView(name=f"drive {quantity} ({unit})", origin=f"{prefix}{quantity}/drive")]
    if result.has_workpiece_force:
        views.append(rrb.TimeSeriesView(name="cutting force on the workpiece (N)", origin=f"{prefix}force/cutting"))
    return views


def run_layout(result, prefix: str, gain: int | None, n_per_mm: float | None,
               name: str | None = None) -> rrb.Horizontal:
    """One run: series left; machine (and the contour when ``gain`` is given) right."""
    right = [_machine_view(result.machine.model, prefix, n_per_mm)]
    if gain is not None:
        right.append(_contour_view(result, prefix, gain))
    views = series_views(result, prefix)
    shares = [1.2, 1.6] + [1.0] * (len(views) - 2)  # the error panel tall enough for its tick labels
    return rrb.Horizontal(rrb.Vertical(*views, row_shares=shares), rrb.Vertical(*right),
                          column_shares=[0.45, 0.55], name=name)


def blueprint(results: dict, gains: dict, arrow_scales: dict) -> rrb.Blueprint:
    """One run fills the window; several get a tab each (named as the runs).  ``gains`` and
    ``arrow_scales`` per run name: contour error magnification and N per mm of force arrow
    (None where there is no contour or no cutting force)."""
    if list(results) == [""]:
        return rrb.Blueprint(run_layout(results[""], "", gains[""], arrow_scales[""]), collapse_panels=True)
    return rrb.Blueprint(rrb.Tabs(*[run_layout(r, f"{name}/", gains[name], arrow_scales[name], name)
                                    for name, r in results.items()]), collapse_panels=True)
