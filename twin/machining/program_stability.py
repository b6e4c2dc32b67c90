"""Every cutting line of a program checked against chatter: from the engagement the twin computes
along the planned path (:func:`twin.machining.engagement.engagement_table`: the engaged arcs and
their axial depths), the spindle speed, the feed's direction and the tool at each sample, the
zero-order critical depth (:mod:`twin.machining.stability`) at that speed, the margin (critical
over actual depth), and the nearest speeds at which the line's cut is stable.

A sample's two engaged arcs each push with their own depth: the cut's mean force matrix is
``sum_k (a_k / a) H0_k`` with ``a`` the larger arc depth, so its critical depth is in units of
that ``a`` (the "depth" a line reports).  A line's figures are those of its sample of least
margin.  Samples of one tool, speed, feed per tooth (Kienzle materials only), feed direction
(to :data:`ANGLE_STEP_DEG`) and arcs (to :data:`ANGLE_STEP_DEG`, their depth ratio to 1 %) share
one computation.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from twin.machining.cutting import MIN_SPINDLE_RPM, kienzle_coefficients
from twin.machining.engagement import COLUMNS, ToolSpec
from twin.machining.materials import CuttingCoefficients
from twin.machining.stability import Cut, frequency_grid_hz, zoa_boundaries
from twin.records import LineStability

#: Angles (arcs, feed direction) are compared to this step (deg).
ANGLE_STEP_DEG = 1.0
#: Speeds on which a line's stable speeds are searched.
STABLE_SPEEDS = 2000
#: Engagement states computed at most (the program's distinct ones, coarsened beyond).
MAX_STATES = 20_000


def milling_cut(
    coefficients: CuttingCoefficients,
    n_flutes: int,
    arcs: tuple[tuple[float, float, float], ...],
    feed_angle_rad: float = 0.0,
    feed_per_tooth_mm: float = 0.1,
) -> Cut:
    """The :class:`~twin.machining.stability.Cut` of a tool's material and flutes on ``arcs``
    (entry, exit (rad), depth share); a Kienzle material's coefficients linearised at the mean
    chip thickness of the first arc at ``feed_per_tooth_mm`` (as the force kernels do)."""
    st, ex, _share = arcs[0]
    k = kienzle_coefficients(coefficients.as_array(), feed_per_tooth_mm, st, ex)
    return Cut(n_flutes, float(k[0]) * 1e6, float(k[1] / k[0]), arcs, feed_angle_rad)


@dataclass(frozen=True)
class ProgramSamples:
    """What the planned program does at each sample: the engagement table
    (:data:`~twin.machining.engagement.COLUMNS`), spindle speed (rpm), index into ``tools``,
    program line, and the XY velocity (m/s)."""

    table: np.ndarray
    spindle_rpm: np.ndarray
    tool_index: np.ndarray
    tools: list[ToolSpec]
    line: np.ndarray
    velocity_xy: np.ndarray


def line_stability(samples: ProgramSamples, rpm_range: tuple[float, float]) -> dict[int, LineStability]:
    """Per program line that cuts with a tool that has ``dynamics``, its check: the depth,
    speed, critical depth, margin and chatter frequency at its sample of least margin, the
    stable speeds within ``rpm_range`` nearest the line's own (its own if it is stable) and the
    one line a user reads.

    Parameters
    ----------
    samples : ProgramSamples
    rpm_range : (float, float)
        Where stable speeds are searched (rpm).
    """
    col = {name: samples.table[:, COLUMNS.index(name)] for name in COLUMNS}
    d1, d2 = col["depth1_mm"], col["depth2_mm"]
    depth = np.maximum(d1, d2)
    has_dynamics = np.array([t.dynamics is not None for t in samples.tools], bool)
    cutting = (depth > 0) & (samples.spindle_rpm >= MIN_SPINDLE_RPM)
    cutting &= has_dynamics[samples.tool_index] if len(samples.tools) else False
    k_all = np.flatnonzero(cutting)
    if k_all.size == 0:
        return {}
    step = math.radians(ANGLE_STEP_DEG)
    feed_angle = np.arctan2(samples.velocity_xy[:, 1], samples.velocity_xy[:, 0])
    isotropic = np.array([t.dynamics is not None and t.dynamics.is_isotropic() for t in samples.tools], bool)
    feed_angle = np.where(isotropic[samples.tool_index], 0.0, feed_angle)  # any frame is the same
    flutes = np.array([t.n_flutes for t in samples.tools])[samples.tool_index]
    speed_mm_min = np.hypot(samples.velocity_xy[:, 0], samples.velocity_xy[:, 1]) * 6e4
    fz = speed_mm_min / (flutes * np.maximum(samples.spindle_rpm, MIN_SPINDLE_RPM))
    kienzle = np.array([t.cutting_coefficients().mc > 0 for t in samples.tools])[samples.tool_index]
    with np.errstate(divide="ignore", invalid="ignore"):
        share1, share2 = d1 / depth, d2 / depth
    key = np.column_stack(
        [
            samples.tool_index,
            np.round(samples.spindle_rpm, 1),
            np.where(kienzle, np.round(fz, 3), 0.0),
            np.round(feed_angle / step),
            np.round(col["phi_st1"] / step),
            np.round(col["phi_ex1"] / step),
            np.round(share1, 2),
            np.round(col["phi_st2"] / step),
            np.round(col["phi_ex2"] / step),
            np.round(share2, 2),
        ]
    )[k_all]
    states, first, inverse = np.unique(key, axis=0, return_index=True, return_inverse=True)
    if len(states) > MAX_STATES:  # coarser: the feed direction and speeds to 10 degrees and rpm
        key[:, 1], key[:, 3] = np.round(key[:, 1], -1), np.round(key[:, 3] / 10) * 10
        states, first, inverse = np.unique(key[:, :], axis=0, return_index=True, return_inverse=True)
    inverse = inverse.ravel()
    low, high = rpm_range
    speeds = np.linspace(low, high, STABLE_SPEEDS)
    critical = np.full(len(states), np.nan)
    chatter = np.full(len(states), np.nan)
    cuts: list[Cut | None] = [None] * len(states)
    for s, k in enumerate(k_all[first]):
        tool = samples.tools[samples.tool_index[k]]
        arcs = tuple(
            (float(col[f"phi_st{i}"][k]), float(col[f"phi_ex{i}"][k]), float(share))
            for i, share in ((1, share1[k]), (2, share2[k]))
            if share > 0 and col[f"phi_ex{i}"][k] > col[f"phi_st{i}"][k]
        )
        cuts[s] = milling_cut(tool.cutting_coefficients(), tool.n_flutes, arcs, float(feed_angle[k]), float(fz[k]))
    tools_of_states = samples.tool_index[k_all[first]]
    grids = {}
    for t in np.unique(tools_of_states):
        dynamics = samples.tools[t].dynamics
        assert dynamics is not None  # cutting samples' tools have dynamics
        which = np.flatnonzero(tools_of_states == t)
        rpm = samples.spindle_rpm[k_all[first[which]]]
        n_flutes = samples.tools[t].n_flutes
        longest = 60.0 / (n_flutes * min(float(rpm.min()), low))
        freq = frequency_grid_hz(dynamics, longest)
        g = dynamics.receptance(freq)
        grids[int(t)] = (freq, g)
        mean_h = np.array([cuts[s].mean_matrix() for s in which])  # type: ignore[union-attr]
        a, f = zoa_boundaries(mean_h, freq, g, (60.0 / (n_flutes * rpm))[:, None])
        critical[which], chatter[which] = a[:, 0], f[:, 0]
    margin = critical[inverse] * 1e3 / depth[k_all]
    margin = np.where(np.isfinite(margin), margin, np.inf)
    lines = samples.line[k_all]
    worst = {int(line): (mine := np.flatnonzero(lines == line))[np.argmin(margin[mine])] for line in np.unique(lines)}
    over_speeds = _critical_over(
        speeds, sorted({int(inverse[w]) for w in worst.values()}), cuts, tools_of_states, samples, grids
    )
    out: dict[int, LineStability] = {}
    for line, w in worst.items():
        k, s = k_all[w], int(inverse[w])
        stable = _stable_range(speeds, over_speeds[s] * 1e3, float(depth[k]), float(samples.spindle_rpm[k]))
        depth_mm = round(float(depth[k]), 4)
        spindle_rpm = round(float(samples.spindle_rpm[k]), 1)
        critical_mm = round(float(critical[s]) * 1e3, 4) if np.isfinite(critical[s]) else None
        out[line] = LineStability(
            depth_mm=depth_mm,
            spindle_rpm=spindle_rpm,
            critical_depth_mm=critical_mm,
            margin=round(float(margin[w]), 3) if np.isfinite(margin[w]) else None,
            chatter_hz=round(float(chatter[s]), 1) if np.isfinite(chatter[s]) else None,
            stable_rpm=stable,
            text=describe(
                line, depth_mm=depth_mm, spindle_rpm=spindle_rpm, critical_depth_mm=critical_mm, stable_rpm=stable
            ),
        )
    return out


def _critical_over(speeds, states, cuts, tools_of_states, samples, grids) -> dict[int, np.ndarray]:
    """The zero-order critical depth (m) of each of ``states`` at every one of ``speeds``."""
    out: dict[int, np.ndarray] = {}
    for t in np.unique(tools_of_states[states]):
        mine = [s for s in states if tools_of_states[s] == t]
        freq, g = grids[int(t)]
        mean_h = np.array([cuts[s].mean_matrix() for s in mine])
        periods = np.broadcast_to(60.0 / (samples.tools[t].n_flutes * speeds), (len(mine), len(speeds)))
        depths = zoa_boundaries(mean_h, freq, g, periods)[0]
        out.update(zip(mine, depths))
    return out


def default_rpm_range(spindle_rpm: np.ndarray) -> tuple[float, float]:
    """Where stable speeds are searched by default (rpm): a quarter of the program's lowest
    turning speed to twice its highest (none turning: 1000 to 30 000)."""
    turning = spindle_rpm[spindle_rpm >= MIN_SPINDLE_RPM]
    if turning.size == 0:
        return 1000.0, 30000.0
    return 0.25 * float(turning.min()), 2.0 * float(turning.max())


def _stable_range(
    speeds: np.ndarray, critical_mm: np.ndarray, depth_mm: float, rpm: float
) -> tuple[float, float] | None:
    """The stretch of ``speeds`` (rpm) whose critical depth is over ``depth_mm`` holding
    ``rpm`` or nearest it, as (low, high) (rpm, to 10); None: none."""
    ok = ~(critical_mm <= depth_mm)  # nan: no boundary, stable
    if not ok.any():
        return None
    edges = np.flatnonzero(np.diff(np.concatenate([[0], ok.astype(int), [0]])))
    runs = list(zip(edges[0::2], edges[1::2] - 1))
    distance = [
        0.0 if speeds[a] <= rpm <= speeds[b] else min(abs(speeds[a] - rpm), abs(speeds[b] - rpm)) for a, b in runs
    ]
    a, b = runs[int(np.argmin(distance))]
    return round(float(speeds[a]), -1), round(float(speeds[b]), -1)


def describe(
    line: int,
    *,
    depth_mm: float,
    spindle_rpm: float,
    critical_depth_mm: float | None,
    stable_rpm: tuple[float, float] | None,
) -> str:
    """A line's check as a user reads it: "line 57: 4.00 mm at 12 000 rpm, critical 2.10 mm;
    stable at 13 400-15 100 rpm" (depths in mm, speeds in rpm; None: no boundary, no stable
    speed)."""
    critical = "no boundary" if critical_depth_mm is None else f"critical {critical_depth_mm:.2f} mm"
    where = (
        "no stable speed in the range"
        if stable_rpm is None
        else f"stable at {_rpm(stable_rpm[0])}-{_rpm(stable_rpm[1])} rpm"
    )
    return f"line {line}: {depth_mm:.2f} mm at {_rpm(spindle_rpm)} rpm, {critical}; {where}"


def _rpm(value: float) -> str:
    return f"{value:,.0f}".replace(",", " ")
