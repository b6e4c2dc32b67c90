"""Rerun recordings of runs: the machine in 3-D, the contour from above, named series.

One timeline, ``sim_time`` (s).  Entity paths (under ``<name>/`` for each of several runs):

- ``machine/<body>/<geom>``: every geom of the compiled MJCF (boxes, cylinders, capsules,
  ellipsoids, meshes; m), logged once; ``machine/<body>`` carries the body's pose over time
  (MuJoCo's forward kinematics at the recorded ticks), so tables, carriages, screws and rotors
  move with the time cursor; the orange tabs on screws and rotors show their rotation;
  ``machine/spindle`` holds the tool;
- ``machine/cutting_force``: the force on the workpiece as an arrow from just above the tool
  tip, scaled by a round number of N per mm that the 3-D view's name states (runs with a
  cutting-force model);
- ``contour/reference``, ``contour/actual``, ``contour/error_x<gain>`` (mm, z = 0; the last is
  reference + gain x (actual - reference), gain a round number from 10 to 1000) and
  ``contour/tool`` (the actual position, a point over time), for two-axis runs;
- ``reference/<axis>``, ``actual/<axis>`` (mm), ``error/<axis>`` (µm), ``control/<axis>`` (V);
- ``torque/drive/<axis>`` (N m, motor shafts) or ``force/drive/<axis>`` (N, linear motors and
  tendons); ``force/cutting/<axis>`` (N, on the workpiece, when a force model acted);
- ``joints/<axis>/motor/angle``, ``.../screw/angle`` (rad), ``.../velocity`` (rad/s),
  ``joints/<axis>/table/velocity`` (mm/s).

Every series has a legend name with its unit.  Series and poses are decimated to at most
``max_points`` recorded ticks.  The blueprint puts the series left and the machine and contour
right (:mod:`twin.recording.layout`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import rerun as rr

from twin.outcome import RunOutcome
from twin.recording.contour import log_contour
from twin.recording.layout import blueprint
from twin.recording.machine3d import arrow_scale_N_per_mm, log_cutting_force, log_geometry, log_poses
from twin.recording.series import log_series
from twin.scales import contour_gain
from twin.sim.runner import RunResult

__all__ = ["read_back", "record", "record_runs"]


def record(
    result: RunOutcome | RunResult,
    path: str | Path,
    max_points: int = 20_000,
    application_id: str = "cnc_feed_drive_twin",
) -> Path:
    """Write a run to a ``.rrd`` file.

    Parameters
    ----------
    result : twin.outcome.RunOutcome or twin.sim.runner.RunResult
        The run, with what was computed from its motion (a program's part) where it has any.
    path : str or Path
        Output file.
    max_points : int
        Decimate every series and the body poses to at most this many recorded ticks.

    Returns
    -------
    Path
        The file written.
    """
    return record_runs({"": result}, path, max_points, application_id)


def record_runs(
    runs: dict[str, RunOutcome | RunResult],
    path: str | Path,
    max_points: int = 20_000,
    application_id: str = "cnc_feed_drive_twin",
) -> Path:
    """Write several runs (:class:`~twin.outcome.RunOutcome` or bare
    :class:`~twin.sim.runner.RunResult`) to one ``.rrd`` file, each under its name
    (``<name>/machine/...``).

    A single run under the name ``""`` keeps the plain entity paths of the module docstring.

    Raises
    ------
    ValueError
        A run that recorded no series (``record_every = 0``, metrics only).
    """
    outcomes = {name: r if isinstance(r, RunOutcome) else RunOutcome(r) for name, r in runs.items()}
    results = {name: outcome.run for name, outcome in outcomes.items()}
    empty = [name for name, r in results.items() if len(r.t_s) == 0]
    if empty:
        raise ValueError(f"run {empty[0]!r} kept metrics only (record_every = 0): nothing to record")
    path = Path(path)
    rec = rr.RecordingStream(application_id)
    rec.save(str(path))
    gains = {name: contour_gain(r) if len(r.axis_names) == 2 else None for name, r in results.items()}
    scales = {
        name: arrow_scale_N_per_mm(r.workpiece_force_N) if r.has_workpiece_force else None
        for name, r in results.items()
    }
    rec.send_blueprint(blueprint(outcomes, gains, scales))
    for name, outcome in outcomes.items():
        _log_run(
            rec,
            outcome,
            prefix=f"{name}/" if name else "",
            max_points=max_points,
            gain=gains[name],
            n_per_mm=scales[name],
        )
    rec.flush()
    rec.disconnect()
    return path


def _log_run(
    rec, outcome: RunOutcome, *, prefix: str, max_points: int, gain: int | None, n_per_mm: float | None
) -> None:
    """Send one run under ``prefix``: series, machine, the force arrow when ``n_per_mm`` is
    given and the contour when ``gain`` is."""
    result = outcome.run
    rows = slice(None, None, max(1, int(np.ceil(len(result.t_s) / max_points))))
    model = result.machine.model
    log_series(rec, result, prefix, rows)
    log_geometry(rec, model, prefix)
    log_poses(rec, model, t=result.t_s[rows], qpos=result.qpos[rows], prefix=prefix)
    if n_per_mm is not None:
        log_cutting_force(
            rec, model, t=result.t_s[rows], force_N=result.workpiece_force_N[rows], n_per_mm=n_per_mm, prefix=prefix
        )
    if gain is not None:
        log_contour(rec, outcome, prefix=prefix, rows=rows, gain=gain)


def read_back(path: str | Path) -> dict[str, int]:
    """Rows per entity path in a recording, read with Rerun's own reader (for checks)."""
    from rerun.chunk import RrdReader

    counts: dict[str, int] = {}
    for chunk in RrdReader(str(path)).store().stream():
        counts[chunk.entity_path] = counts.get(chunk.entity_path, 0) + chunk.num_rows
    return counts
