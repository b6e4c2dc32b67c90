"""Performance metrics of responses and tracking runs.

Step metrics follow the usual definitions, stated per function: overshoot relative to the
final value, 2 % settling time, 10-90 % rise time and the 0-100 % rise time (first time the
response reaches its final value), which some papers call rise time.
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Any

import numpy as np
from numba import njit

from twin.machining.chatter import CHATTER_THRESHOLD, ChatterReading, chatter_reading
from twin.numba_cache import configure as configure_numba_cache
from twin.outcome import RunOutcome
from twin.records import ChatterCheck, ChatterWarning, LineRow, RunRecords
from twin.sim.runner import RunResult

configure_numba_cache()  # before the first @njit(cache=True): see twin.numba_cache


def step_metrics(
    t_s: np.ndarray, y: np.ndarray, final: float | None = None, settling_band: float = 0.02
) -> dict[str, float]:
    """Overshoot, settling and rise times of a step response.

    Parameters
    ----------
    t_s : ndarray, shape (n,)
        Time (s), step applied at ``t_s[0]``.
    y : ndarray, shape (n,)
        Response, starting from 0.
    final : float, optional
        Final value; default the last sample.
    settling_band : float
        Settling band as a fraction of ``final`` (0.02 for 2 %).

    Returns
    -------
    dict
        ``overshoot_pct`` (%, 0 if none), ``settling_time_s`` (last exit from the band),
        ``rise_time_10_90_s``, ``rise_time_0_100_s`` (nan if never reached), ``peak``,
        ``final``.
    """
    t = np.asarray(t_s, float) - t_s[0]
    y = np.asarray(y, float)
    yf = float(y[-1] if final is None else final)
    peak = float(y.max() if yf >= 0 else y.min())
    overshoot = max(0.0, (peak - yf) / abs(yf) * 100.0) if yf else float("nan")
    outside = np.flatnonzero(np.abs(y - yf) > settling_band * abs(yf))
    if outside.size == 0:
        settling = 0.0
    elif outside[-1] + 1 < len(t):
        settling = float(t[outside[-1] + 1])
    else:
        settling = float("nan")

    def first_cross(level):
        idx = np.flatnonzero(y >= level) if yf >= 0 else np.flatnonzero(y <= level)
        if idx.size == 0:
            return float("nan")
        i = idx[0]
        if i == 0:
            return float(t[0])
        # linear interpolation between samples
        return float(t[i - 1] + (level - y[i - 1]) / (y[i] - y[i - 1]) * (t[i] - t[i - 1]))

    return {
        "overshoot_pct": overshoot,
        "settling_time_s": settling,
        "rise_time_10_90_s": first_cross(0.9 * yf) - first_cross(0.1 * yf),
        "rise_time_0_100_s": first_cross(yf),
        "peak": peak,
        "final": yf,
    }


def fit_index(y: np.ndarray, r: np.ndarray) -> np.ndarray:
    """Fitting index (%) per column: ``100 (1 - ||y - r|| / ||r - mean(r)||)``, the NRMSE fit of
    MATLAB's ``compare`` (100 is a perfect fit, 0 no better than the mean of the reference).

    Parameters
    ----------
    y, r : ndarray, shape (n,) or (n, m)
        Response and reference, same unit.
    """
    y, r = np.asarray(y, float), np.asarray(r, float)
    return 100.0 * (1.0 - np.linalg.norm(y - r, axis=0) / np.linalg.norm(r - r.mean(axis=0), axis=0))


#: Path samples closer than this (m) to the one before are the path standing still.
STILL_M = 1e-9


def contour_error(actual_xy: np.ndarray, path_xy: np.ndarray) -> np.ndarray:
    """Distance (same unit) from each actual point to the reference path near it, in O(n).

    Parameters
    ----------
    actual_xy : ndarray, shape (n, 2)
        Points in time order.
    path_xy : ndarray, shape (m, 2)
        Reference path in time order, treated as a polyline (the reference positions of the
        same run, or any denser sampling of it).

    Returns
    -------
    ndarray, shape (n,)
        Shortest distance from every actual point to the polyline's segments within a window
        around the segment nearest the previous point (the first point searches the whole
        path), about the furthest segment the walk has found.  The window is 64
        segments plus four times the path's samples per point, so it follows the path however
        the two are sampled; the work is linear in n + m.  Where the path comes back near
        itself, or over itself, this is the distance to the part of the path the tool is on,
        as a contour error should be.
    """
    p = np.ascontiguousarray(actual_xy, float)
    path = np.asarray(path_xy, float)
    # a path that stands still (a G-code program's dwells and Z moves) as one point: the walk
    # follows the path's segments, and a long stop would otherwise leave it behind
    if len(path) > 1:
        moving = np.concatenate([[True], np.abs(np.diff(path, axis=0)).max(axis=1) > STILL_M])
        path = path[moving]
    path = np.ascontiguousarray(path)
    out = np.empty(len(p))
    if len(p) == 0:
        return out
    if len(path) < 2:
        return np.hypot(*(p - path[0]).T)
    window = 64 + 4 * -(-len(path) // len(p))
    _contour_walk(p, path, window, out)
    return out


@njit(cache=True)
def _segment_distance(px, py, path, j):  # pragma: no cover - compiled
    """Distance from (px, py) to segment j of ``path`` (a zero-length one is a point)."""
    ax, ay = path[j, 0], path[j, 1]
    dx, dy = path[j + 1, 0] - ax, path[j + 1, 1] - ay
    len2 = dx * dx + dy * dy
    s = 0.0 if len2 <= 0.0 else min(max(((px - ax) * dx + (py - ay) * dy) / len2, 0.0), 1.0)
    return math.hypot(px - ax - s * dx, py - ay - s * dy)


@njit(cache=True)
def _contour_walk(p, path, window, out):  # pragma: no cover - compiled
    """:func:`contour_error`'s search: segments within ``window`` of the last nearest one."""
    n_seg = path.shape[0] - 1
    best_j, furthest, lo, hi = 0, 0, 0, n_seg
    for i in range(p.shape[0]):
        best = math.inf
        for j in range(lo, hi):
            d = _segment_distance(p[i, 0], p[i, 1], path, j)
            # of equally near segments the first for the first point (it searches the whole
            # path), the latest after: the walk moves on where the path stands still
            if d < best or (i > 0 and d == best):
                best, best_j = d, j
        out[i] = best
        # the window is about the furthest segment yet, not the last: where the
        # path turns back over itself (a zig-zag, a line cut out and back) the walk cannot
        # follow the earlier leg backwards, segment by segment, and lose the tool
        furthest = max(furthest, best_j)
        lo, hi = max(furthest - window, 0), min(furthest + window + 1, n_seg)


#: The path searched about each tick's reference point: the parts of it within this many times
#: the tick's tracking error, along the path, of that point (:func:`tick_contour_error`).
CONTOUR_REACH = 2.0


def tick_contour_error(actual: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """Distance from each actual point to the path of the reference near the same tick's
    reference point, in O(n) (times the path's samples within reach).

    Parameters
    ----------
    actual, reference : ndarray, shape (n, d)
        The tool's points and the reference's points at the same ticks, in time order (any
        number of axes: a program's planned z beside the machine's x and y gives the distance
        in 3-D, to a plunge, a ramp or a helix as well as to a move in XY).

    Returns
    -------
    ndarray, shape (n,)
        The shortest distance from ``actual[i]`` to the reference's polyline (its samples in
        time order, the path standing still left out) over the part of it within
        :data:`CONTOUR_REACH` times the tracking error ``|actual[i] - reference[i]|``, in arc
        length, of ``reference[i]``, that point itself included: never more than the tracking
        error, and the distance to the part of the path the tool is on however the path comes
        back near itself or over itself (the walk of :func:`contour_error` can lose it there).
        On a straight path the nearest point lies within the tracking error of the reference
        point along it, on an arc within about 1.4 times for a tool up to half the radius inside.
    """
    p = np.ascontiguousarray(actual, float)
    ref = np.ascontiguousarray(reference, float)
    if p.shape != ref.shape:
        raise ValueError(f"actual {p.shape} and reference {ref.shape} are not one series of ticks")
    out = np.empty(len(p))
    if len(p):
        _tick_walk(p, ref, CONTOUR_REACH, out)
    return out


@njit(cache=True)
def _point_segment(p, a, b):  # pragma: no cover - compiled
    """Distance from point p to the segment a-b (any number of axes; a zero-length one a point)."""
    len2, dot = 0.0, 0.0
    for c in range(p.shape[0]):
        d = b[c] - a[c]
        len2 += d * d
        dot += (p[c] - a[c]) * d
    s = 0.0 if len2 <= 0.0 else min(max(dot / len2, 0.0), 1.0)
    total = 0.0
    for c in range(p.shape[0]):
        d = p[c] - a[c] - s * (b[c] - a[c])
        total += d * d
    return math.sqrt(total)


@njit(cache=True)
def _tick_walk(p, ref, reach, out):  # pragma: no cover - compiled
    """:func:`tick_contour_error`'s search."""
    n, dims = ref.shape
    # the path's vertices, each sample that has moved over STILL_M (any axis) from the last kept
    vertex = np.empty(n, np.int64)  # each tick's vertex: the last kept at or before it
    kept = np.empty(n, np.int64)
    n_kept = 0
    for i in range(n):
        moved = n_kept == 0
        if not moved:
            for c in range(dims):
                if abs(ref[i, c] - ref[kept[n_kept - 1], c]) > STILL_M:
                    moved = True
        if moved:
            kept[n_kept] = i
            n_kept += 1
        vertex[i] = n_kept - 1
    path = np.empty((n_kept, dims))
    arc = np.zeros(n_kept)
    for v in range(n_kept):
        path[v] = ref[kept[v]]
        if v > 0:
            total = 0.0
            for c in range(dims):
                d = path[v, c] - path[v - 1, c]
                total += d * d
            arc[v] = arc[v - 1] + math.sqrt(total)
    for i in range(n):
        tracking = 0.0
        for c in range(dims):
            d = p[i, c] - ref[i, c]
            tracking += d * d
        best = math.sqrt(tracking)  # the reference point itself: on the path
        v = vertex[i]
        s_lo, s_hi = arc[v] - reach * best, arc[v] + reach * best
        # segments j (path[j] to path[j + 1]) whose span of arc length meets [s_lo, s_hi], from
        # the one that starts at the tick's vertex forwards and the one before it backwards
        j = v
        while j < n_kept - 1 and (j == v or arc[j] <= s_hi):
            best = min(best, _point_segment(p[i], path[j], path[j + 1]))
            j += 1
        j = v - 1
        while j >= 0 and (j == v - 1 or arc[j + 1] >= s_lo):
            best = min(best, _point_segment(p[i], path[j], path[j + 1]))
            j -= 1
        out[i] = best


def run_contour_error(result: RunResult) -> np.ndarray | None:
    """The contour error (m) of a run with a 2-D path at each recorded tick
    (:func:`tick_contour_error`), in the move's own axes: a part program's planned axes the
    machine has not (its z) are added to the tool's point and to the reference, so that a
    plunge, a ramp or a helix is measured against itself; None for a path that is not 2-D."""
    ref = result.ref[:, :, 0]
    if not (ref.shape[1] == 2 and len(ref) > 1 and (np.ptp(ref, axis=0) > 0).all()):
        return None
    actual = result.table_position_m()
    program = result.program
    extra = [] if program is None else [np.asarray(v, float)[: len(ref)] for v in program.extra_axes.values()]
    if extra and all(len(v) == len(ref) for v in extra):
        ref = np.column_stack([ref, *extra])
        actual = np.column_stack([actual, *extra])
    return tick_contour_error(actual, ref)


def tracking_summary(outcome: RunOutcome, records: RunRecords | None = None) -> dict:
    """Max and RMS tracking error per axis (um) and the largest cutting force per axis (N,
    tick means, when there is one), all over every tick of the run; for 2-D paths, max and RMS
    contour error (um) over the recorded ticks (none when only metrics were kept); a program's
    and a milling run's ``records`` (:func:`run_records`, computed when not given) as JSON."""
    result = outcome.run
    out: dict[str, Any] = {
        "max_tracking_error_um": dict(zip(result.axis_names, (result.error_max_m * 1e6).round(3).tolist())),
        "rmse_um": dict(zip(result.axis_names, (result.error_rms_m * 1e6).round(3).tolist())),
    }
    if result.force_max_N.any():  # cutting: tick-mean force on the workpiece along each axis
        out["max_cutting_force_N"] = dict(zip(result.axis_names, result.force_max_N.round(1).tolist()))
    ce = run_contour_error(result)
    records = run_records(outcome, ce) if records is None else records
    if ce is not None:  # a 2-D path
        out["max_contour_error_um"] = round(float(ce.max() * 1e6), 3)
        out["rms_contour_error_um"] = round(float(np.sqrt(np.mean(ce**2)) * 1e6), 3)
    program = result.program
    if program is not None and program.lines.size:
        out["cycle_time_s"] = round(float(program.cycle_time_s), 6)
        feeding = program.feed_mm_per_min > 0
        if ce is not None and feeding.any():  # the contour error on the feed moves, rapids left out
            out["max_contour_error_feed_um"] = round(float(ce[feeding].max() * 1e6), 3)
            out["rms_contour_error_feed_um"] = round(float(np.sqrt(np.mean(ce[feeding] ** 2)) * 1e6), 3)
        if program.engagement.size:  # with a stock: the share of the recorded time the tool cuts
            cutting = (program.engagement[:, 0] > 0) & (program.engagement[:, 1] > 0)
            out["cutting_share"] = round(float(cutting.mean()), 4)
            out["machining_warnings"] = [warning.to_json() for warning in records.machining_warnings]
            if records.machining_warnings_total > len(records.machining_warnings):
                out["machining_warnings_total"] = records.machining_warnings_total
        if records.plan_warnings:  # outside the travel, beyond the drives
            out["plan_warnings"] = [warning.to_json() for warning in records.plan_warnings]
            if records.plan_warnings_total > len(records.plan_warnings):
                out["plan_warnings_total"] = records.plan_warnings_total
        if outcome.part is not None:
            out["part"] = outcome.part.summary()
            out["inspection"] = [feature.to_json() for feature in records.inspection]
        out["lines"] = [row.to_json() for row in records.lines]
    if records.chatter is not None:
        out["chatter"] = records.chatter.to_json()
        out["chatter_warnings"] = [warning.to_json() for warning in records.chatter_warnings]
    return out


def run_records(outcome: RunOutcome, contour_m: np.ndarray | None) -> RunRecords:
    """A run's per-line rows (:func:`line_table`, each with its chatter), its machining
    warnings (with a stock), its warnings against the machine, its part's inspection and its
    chatter (:func:`chatter_check`).

    Parameters
    ----------
    outcome : RunOutcome
    contour_m : ndarray or None
        The contour error at each recorded tick (m, :func:`run_contour_error`); None: the path
        is not 2-D.
    """
    result = outcome.run
    program = result.program
    if program is None or program.lines.size == 0:
        whole, _, chatter_warnings = chatter_check(result, [])
        return RunRecords(chatter=whole, chatter_warnings=tuple(chatter_warnings))
    whole, rows, chatter_warnings = chatter_check(result, line_table(outcome, contour_m))
    return RunRecords(
        lines=tuple(rows),
        machining_warnings=outcome.machining_warnings,
        machining_warnings_total=outcome.machining_warnings_total,
        plan_warnings=outcome.plan_warnings,
        plan_warnings_total=outcome.plan_warnings_total,
        inspection=outcome.inspection,
        chatter=whole,
        chatter_warnings=tuple(chatter_warnings),
    )


def _chatter_of(result: RunResult, rows: slice) -> ChatterReading | None:
    """The chatter reading (:func:`twin.machining.chatter.chatter_reading`) of the recorded rows
    ``rows`` of a run; None where the tool did not cut for a window's worth."""
    every = max(result.info.get("record_every", 1), 1)
    dt = result.machine.model.opt.timestep
    steps = round(result.control_period_s / dt) * every
    return chatter_reading(result.vibration_probe[rows], steps, result.control_period_s * every, dt)


def chatter_check(
    result: RunResult, lines: list[LineRow]
) -> tuple[ChatterCheck | None, list[LineRow], list[ChatterWarning]]:
    """A milling run's chatter (:mod:`twin.machining.chatter`): the whole run's reading
    (indicator, frequency and verdict, :meth:`~twin.machining.chatter.ChatterReading.check`),
    the rows of ``lines`` each with its own reading, and the warnings (each program line that
    chatters, or the run); None, ``lines`` and none for a run that does not mill for a window's
    worth."""
    whole = _chatter_of(result, slice(None))
    if whole is None:
        return None, lines, []
    warnings = []
    program = result.program
    if lines and program is not None:
        starts = np.flatnonzero(np.concatenate([[True], program.lines[1:] != program.lines[:-1]]))
        ends = np.concatenate([starts[1:], [program.lines.size]])
        checked = []
        for row, a, b in zip(lines, starts, ends):
            reading = _chatter_of(result, slice(a, b))
            if reading is not None:
                row = replace(row, chatter=reading.check())
                if reading.chatters:
                    warnings.append(ChatterWarning(line=row.line, message=_chatter_message(reading), text=row.text))
            checked.append(row)
        lines = checked
    elif whole.chatters:
        warnings.append(ChatterWarning(line=None, message=_chatter_message(whole), text=""))
    return whole.check(), lines, warnings


def _chatter_message(reading: ChatterReading) -> str:
    """One warning's words: the indicator against its threshold, and the frequency."""
    hz = "" if reading.chatter_hz is None else f" at {reading.chatter_hz:.0f} Hz"
    return f"chatter{hz}: indicator {reading.indicator:.2f} over {CHATTER_THRESHOLD}"


def line_table(outcome: RunOutcome, contour_m: np.ndarray | None) -> list[LineRow]:
    """Per G-code line, over the recorded ticks the reference is on it: its text, time span,
    max and RMS contour error (um), max tracking error per axis (um), the largest cutting
    force (N, the XY magnitude) and, with a stock, the mean engaged angle (deg), the largest
    axial depth (mm) and, for a tool with ``dynamics``, the chatter check (``stability``), in
    program order.

    Parameters
    ----------
    outcome : RunOutcome
        A run of a G-code reference (its :class:`~twin.sim.runner.ProgramTrace`), with its
        program's line checks and part.
    contour_m : ndarray or None
        The contour error at each recorded tick (m); None: the path is not 2-D.
    """
    result = outcome.run
    program = result.program
    if program is None or program.lines.size == 0:
        return []
    lines = program.lines
    starts = np.flatnonzero(np.concatenate([[True], lines[1:] != lines[:-1]]))
    ends = np.concatenate([starts[1:], [lines.size]])
    error_um = np.abs(result.error_m()) * 1e6
    err_max = np.maximum.reduceat(error_um, starts, axis=0)
    force = np.hypot(result.workpiece_force_N[:, 0], result.workpiece_force_N[:, 1])
    force_max = np.maximum.reduceat(force, starts)
    if contour_m is not None:
        ce_max = np.maximum.reduceat(contour_m, starts) * 1e6
        ce_rms = np.sqrt(np.add.reduceat(contour_m**2, starts) / (ends - starts)) * 1e6
    t, period = result.t_s, result.control_period_s * max(result.info.get("record_every", 1), 1)
    if program.engagement.size:
        engaged = np.add.reduceat(program.engagement[:, 0], starts) / (ends - starts)
        depth = np.maximum.reduceat(program.engagement[:, 1], starts)
    wall_error = outcome.part.line_errors() if outcome.part is not None else {}
    rows = []
    for i, (a, b) in enumerate(zip(starts, ends)):
        line = int(lines[a])
        rows.append(
            LineRow(
                line=line,
                text=program.texts.get(line, ""),
                t_start_s=round(float(t[a]), 6),
                t_end_s=round(float(t[b - 1] + period), 6),
                max_tracking_error_um=dict(zip(result.axis_names, err_max[i].round(3).tolist())),
                max_cutting_force_N=round(float(force_max[i]), 1),
                max_contour_error_um=None if contour_m is None else round(float(ce_max[i]), 3),
                rms_contour_error_um=None if contour_m is None else round(float(ce_rms[i]), 3),
                mean_engagement_deg=round(float(engaged[i]), 2) if program.engagement.size else None,
                axial_depth_mm=round(float(depth[i]), 4) if program.engagement.size else None,
                max_wall_error_um=wall_error.get(line),
                stability=outcome.line_stability.get(line),
            )
        )
    return rows
