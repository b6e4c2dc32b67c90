"""Rerun recordings of runs: joint states, reference, error, control, forces and the contour.

One timeline, ``sim_time`` (s).  Entity paths and units:

- ``machine/<axis>/motor/angle`` (rad), ``.../motor/velocity`` (rad/s), same for ``screw``
  (lead-screw axes only);
- ``machine/<axis>/table/position`` (mm), ``.../table/velocity`` (mm/s);
- ``machine/<axis>/drive/force`` (N m on a motor shaft, N on a linear-motor slide);
- ``reference/<axis>`` (mm), ``error/<axis>`` (um), ``control/<axis>/u`` (V);
- ``cutting/force/<axis>`` (N, force on the workpiece);
- ``contour/reference``, ``contour/actual`` and ``contour/error_x<gain>`` (mm, 2-D line strips;
  the last is reference + gain x (actual - reference)) for two-axis runs.

Series are buffered during the run and sent as columns (``send_columns``), decimated to at most
``max_points`` samples.  A blueprint lays the recording out: time series left, contour right.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import rerun as rr
import rerun.blueprint as rrb

from twin.metrics import contour_error


def _series(rec, path, t, values):
    rec.send_columns(path, indexes=[rr.TimeColumn("sim_time", duration=t)],
                     columns=rr.Scalars.columns(scalars=np.ascontiguousarray(values, float)))


def contour_gain(result) -> int:
    """Error magnification so the largest contour error shows as about 10 % of the path size."""
    pos = result.table_position_m()
    ref = result.ref[:, :, 0]
    size = np.ptp(ref, axis=0).max()
    worst = contour_error(pos[:: max(1, len(pos) // 2000)], ref).max()
    if worst <= 0 or size <= 0:
        return 1
    return int(10 ** np.floor(np.log10(max(1.0, 0.1 * size / worst))))


def blueprint(axes: list[str], two_d: bool, gain: int) -> rrb.Blueprint:
    """Layout: per-quantity time series, and the 2-D contour when there are two axes."""
    series = rrb.Vertical(
        rrb.TimeSeriesView(name="table position (mm)", contents=[f"machine/{a}/table/position" for a in axes]
                           + [f"reference/{a}" for a in axes]),
        rrb.TimeSeriesView(name="tracking error (um)", origin="error"),
        rrb.TimeSeriesView(name="control input (V)", origin="control"),
        rrb.TimeSeriesView(name="forces (N, N m)", contents=["cutting/**"] + [f"machine/{a}/drive/**" for a in axes]),
    )
    if not two_d:
        return rrb.Blueprint(series, collapse_panels=True)
    return rrb.Blueprint(rrb.Horizontal(series, rrb.Spatial2DView(name=f"contour (mm), error x{gain}",
                                                                  origin="contour")),
                         collapse_panels=True)


def record(result, path: str | Path, max_points: int = 20_000, application_id: str = "cnc_feed_drive_twin") -> Path:
    """Write a run to a ``.rrd`` file.

    Parameters
    ----------
    result : twin.sim.runner.RunResult
    path : str or Path
        Output file.
    max_points : int
        Decimate every series to at most this many samples.

    Returns
    -------
    Path
        The file written.
    """
    return record_runs({"": result}, path, max_points, application_id)


def record_runs(results: dict, path: str | Path, max_points: int = 20_000,
                application_id: str = "cnc_feed_drive_twin") -> Path:
    """Write several runs to one ``.rrd`` file, each under its name (``<name>/machine/...``).

    A single run under the name ``""`` keeps the plain entity paths of the module docstring.

    Raises
    ------
    ValueError
        A run that recorded no series (``record_every = 0``, metrics only).
    """
    empty = [name for name, r in results.items() if len(r.t_s) == 0]
    if empty:
        raise ValueError(f"run {empty[0]!r} kept metrics only (record_every = 0): nothing to record")
    path = Path(path)
    rec = rr.RecordingStream(application_id)
    rec.save(str(path))
    if list(results) == [""]:
        result = results[""]
        axes = result.axis_names
        two_d = len(axes) == 2
        gain = contour_gain(result) if two_d else 1
        rec.send_blueprint(blueprint(axes, two_d, gain))
        _log_run(rec, result, "", max_points, gain)
    else:
        rec.send_blueprint(rrb.Blueprint(rrb.Vertical(*[
            rrb.TimeSeriesView(name=f"{name}: table position (mm)", origin=f"{name}/machine")
            for name in results]), collapse_panels=True))
        for name, result in results.items():
            two_d = len(result.axis_names) == 2
            _log_run(rec, result, f"{name}/", max_points, contour_gain(result) if two_d else 1)
    rec.flush()
    rec.disconnect()
    return path


def _log_run(rec, result, prefix: str, max_points: int, gain: int) -> None:
    """Send one run's series (and its contour for two axes) under ``prefix``."""
    machine = result.machine
    step = max(1, int(np.ceil(len(result.t_s) / max_points)))
    sl = slice(None, None, step)
    t = result.t_s[sl]
    pos = result.table_position_m()
    for i, axis in enumerate(machine.axes):
        a = f"{prefix}machine/{axis.name}"
        for part, joint in (("motor", axis.motor_joint), ("screw", axis.screw_joint)):
            if joint:
                _series(rec, f"{a}/{part}/angle", t, result.qpos[sl, machine.joint_qpos_index(joint)])
                _series(rec, f"{a}/{part}/velocity", t, result.qvel[sl, machine.joint_dof_index(joint)])
        _series(rec, f"{a}/table/position", t, pos[sl, i] * 1e3)
        _series(rec, f"{a}/table/velocity", t, result.qvel[sl, machine.joint_dof_index(axis.table_joint)] * 1e3)
        _series(rec, f"{a}/drive/force", t, result.actuator_force[sl, machine.model.actuator(axis.actuator).id])
        _series(rec, f"{prefix}reference/{axis.name}", t, result.ref[sl, i, 0] * 1e3)
        _series(rec, f"{prefix}error/{axis.name}", t, (result.ref[sl, i, 0] - pos[sl, i]) * 1e6)
        _series(rec, f"{prefix}control/{axis.name}/u", t, result.u_V[sl, i])
        _series(rec, f"{prefix}cutting/force/{axis.name}", t, result.workpiece_force_N[sl, i])
    if len(machine.axes) == 2:
        ref_xy = result.ref[sl, :, 0] * 1e3
        act_xy = pos[sl] * 1e3
        rec.log(f"{prefix}contour/reference", rr.LineStrips2D([ref_xy], colors=[(120, 120, 120)]), static=True)
        rec.log(f"{prefix}contour/actual", rr.LineStrips2D([act_xy], colors=[(30, 140, 255)]), static=True)
        rec.log(f"{prefix}contour/error_x{gain}", rr.LineStrips2D([ref_xy + gain * (act_xy - ref_xy)],
                                                                   colors=[(230, 60, 60)]), static=True)


def read_back(path: str | Path) -> dict[str, int]:
    """Rows per entity path in a recording, read with Rerun's own reader (for checks)."""
    from rerun.chunk import RrdReader

    counts: dict[str, int] = {}
    for chunk in RrdReader(str(path)).store().stream():
        counts[chunk.entity_path] = counts.get(chunk.entity_path, 0) + chunk.num_rows
    return counts
