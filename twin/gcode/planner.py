"""The interpolator: a part program's moves planned into a jerk-limited reference, as a CNC's
trajectory planner does it, sampled at a fixed period.

How (our design; the docs page ``gcode.md`` says why):

1. The path (:mod:`twin.gcode.path`): lines and arcs in machine coordinates; corners between
   lines blended by tangent arcs within half the tolerance (LinuxCNC's G64 P rule).
2. Speed limits along it: the programmed feed times the override (rapids: the axis limits),
   each axis's velocity limit over its share of the tangent, and on arcs the centripetal
   acceleration ``v <= sqrt(a R)``, the jerk of the turning acceleration ``v <= (j R^2)^(1/3)``
   and the contour shrink of the smoothing filter (``v^2 T^2 / (24 R)`` within half the
   tolerance); stops at the ends, dwells, rapid/feed changes and corners that are not blended.
3. Look-ahead: backward and forward passes over the whole path on a grid of arc length with
   the tangential acceleration the axes have left beside the centripetal one
   (``a - v^2 / R``): the time-optimal acceleration-limited speed profile.
4. Jerk: each axis's position passes a moving-average filter of length ``T = max(a_i / j_i)``
   (FIR interpolation, Tajima and Sencer 2016): a trapezoidal acceleration becomes an S-curve,
   so a long straight move takes exactly ``L/v + v/a + a/j``, and an acceleration step (where the
   curvature changes) becomes a ramp of jerk ``<= a/T``.
5. Check: every axis's velocity, acceleration and jerk on the sampled reference are measured;
   where the filter's window holds an acceleration swing from +a to -a (short moves), the jerk
   can reach ``2a/T``: the whole reference is then slowed by the time scale that brings every
   axis within its limits (``time_scale`` in the result).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Iterable
from dataclasses import dataclass, field

import numba
import numpy as np
from pydantic import Field, field_validator

from twin.gcode.path import TANGENT_TOLERANCE_RAD, Segment, blend, move_segment
from twin.gcode.reader import Move
from twin.numba_cache import configure as configure_numba_cache
from twin.spec import StrictSpec

configure_numba_cache()  # before the first @njit(cache=True): see twin.numba_cache

#: Planning and sampling period of the reference (s): positions are Hermite-interpolated between.
SAMPLE_PERIOD_S = 1e-3
#: Most samples a planned reference may hold (about 33 minutes of motion at 1 ms): bounded memory.
MAX_SAMPLES = 2_000_000
#: Arc-length grid of the look-ahead (m): finer on short segments (at least 4 points each).
GRID_M = 5e-5
#: Most grid points of the look-ahead over a whole program.
MAX_GRID_POINTS = 4_000_000


@dataclass(frozen=True)
class Limits:
    """Per-axis kinematic limits (x, y, z), SI units."""

    velocity_m_per_s: tuple[float, ...]
    acceleration_m_per_s2: tuple[float, ...]
    jerk_m_per_s3: tuple[float, ...]

    def as_dict(self) -> dict:
        """Per axis, as ``twin gcode --json`` prints them."""
        return {
            axis: {
                "velocity_m_per_s": self.velocity_m_per_s[i],
                "acceleration_m_per_s2": self.acceleration_m_per_s2[i],
                "jerk_m_per_s3": self.jerk_m_per_s3[i],
            }
            for i, axis in enumerate("xyz")
        }


class PlannerSettings(StrictSpec):
    """The scenario's ``[planner]`` table (``twin gcode --set planner.KEY=VALUE``).

    Each axis's limits default to the machine's (its README says where they come from);
    ``velocity_m_per_s = { x = 0.2 }`` and the like override them.
    """

    tolerance_mm: float | None = Field(
        None, gt=0.0, le=10.0, description="how far the path may leave the programmed one, mm (default: G64 P)"
    )
    feed_override: float = Field(1.0, gt=0.0, le=10.0, description="factor on every programmed feed")
    velocity_m_per_s: dict[str, float] = Field(default_factory=dict, description="axis velocity limits, m/s")
    acceleration_m_per_s2: dict[str, float] = Field(default_factory=dict, description="axis acceleration limits, m/s^2")
    jerk_m_per_s3: dict[str, float] = Field(default_factory=dict, description="axis jerk limits, m/s^3")

    @field_validator("velocity_m_per_s", "acceleration_m_per_s2", "jerk_m_per_s3")
    @classmethod
    def _positive(cls, value: dict) -> dict:
        for axis, limit in value.items():
            if axis not in ("x", "y", "z"):
                raise ValueError(f"{axis!r} is not an axis: use x, y or z")
            if not 1e-6 <= limit <= 1e9:
                raise ValueError(f"{axis} = {limit!r}: a limit is from 1e-6 to 1e9")
        return value

    def limits(self, machine_limits: dict) -> Limits:
        """The limits to plan within: the machine's (``MotionLimits`` per axis x, y, z) with
        this table's overrides."""
        return Limits(
            tuple(self.velocity_m_per_s.get(a, machine_limits[a].velocity_m_per_s) for a in "xyz"),
            tuple(self.acceleration_m_per_s2.get(a, machine_limits[a].acceleration_m_per_s2) for a in "xyz"),
            tuple(self.jerk_m_per_s3.get(a, machine_limits[a].jerk_m_per_s3) for a in "xyz"),
        )


#: Tolerance (mm) where neither the scenario nor the program's G64 P gives one (ours).
DEFAULT_TOLERANCE_MM = 0.01


class PlanningError(ValueError):
    """A program the planner cannot turn into a bounded reference."""


@dataclass
class Plan:
    """A planned reference sampled every ``period_s``.

    Attributes
    ----------
    period_s : float
        Sample period (s).
    position, velocity, acceleration : ndarray (n, 3)
        Machine axes x, y, z (m, m/s, m/s^2).
    line : ndarray (n,) of int
        The program line each sample is on (before the smoothing filter's delay of half its
        window, which the reference leads by).
    feed_only_time_s : float
        The program at its programmed feeds alone (rapids at the axis limits, dwells).
    time_scale : float
        The slow-down applied to keep every axis within its limits (1: none).
    filter_s : float
        The smoothing filter's length (s).
    tolerance_m : float
        The path tolerance used (m).
    segments : list of Segment
        The programmed path (unblended), for deviation checks.
    texts : dict of int to str
        The text of each program line that moved or dwelt.
    spindle_rpm : dict of int to float
        The spindle speed of each line's moves (0 where M5 stops it).
    tools : dict of int to int
        The tool in the spindle on each line (0: none).
    feeds : dict of int to float
        The programmed feed of each line's moves (mm/min; 0 for rapids and dwells).
    """

    period_s: float
    position: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray
    line: np.ndarray
    feed_only_time_s: float
    time_scale: float
    filter_s: float
    tolerance_m: float
    segments: list[Segment] = field(repr=False)
    texts: dict[int, str] = field(default_factory=dict, repr=False)
    spindle_rpm: dict[int, float] = field(default_factory=dict, repr=False)
    tools: dict[int, int] = field(default_factory=dict, repr=False)
    feeds: dict[int, float] = field(default_factory=dict, repr=False)

    def per_sample(self, by_line: dict, default) -> np.ndarray:
        """A per-line value (``spindle_rpm``, ``tools``) at each sample."""
        lines, where = np.unique(self.line, return_inverse=True)
        return np.array([by_line.get(int(line), default) for line in lines])[where]

    @property
    def cycle_time_s(self) -> float:
        """Time from the first sample to the last (s)."""
        return (len(self.position) - 1) * self.period_s

    def max_abs(self) -> dict:
        """The largest |velocity|, |acceleration| and |jerk| of each axis on the samples."""
        jerk = np.diff(self.acceleration, axis=0, prepend=0.0, append=0.0) / self.period_s
        out = {}
        for i, axis in enumerate("xyz"):
            out[axis] = {
                "velocity_m_per_s": float(np.abs(self.velocity[:, i]).max()),
                "acceleration_m_per_s2": float(np.abs(self.acceleration[:, i]).max()),
                "jerk_m_per_s3": float(np.abs(jerk[:, i]).max()),
            }
        return out


def _segment_speed_limit(seg: Segment, limits: Limits, override: float, filter_s: float, tolerance_m: float) -> float:
    """The highest path speed (m/s) on ``seg``."""
    share = seg.axis_share()
    v_axis = min(v / s for v, s in zip(limits.velocity_m_per_s, share) if s > 1e-12)
    v = v_axis if seg.rapid else min(seg.feed_m_per_s * override, v_axis)
    if seg.kind == "arc":
        plane = share > 1e-12
        a = min(x for x, p in zip(limits.acceleration_m_per_s2, plane) if p)
        j = min(x for x, p in zip(limits.jerk_m_per_s3, plane) if p)
        r = 1.0 / seg.curvature
        v = min(v, math.sqrt(a * r), (j * r * r) ** (1.0 / 3.0))
        if filter_s > 0:
            # the filter shrinks an arc by v^2 T^2 / (24 R): within half the tolerance
            v = min(v, math.sqrt(24.0 * r * 0.5 * tolerance_m) / filter_s)
            if seg.blend:
                # a blend shorter than the window: the filter cuts the corner as a sharp one,
                # by (v T / 8) sin(turn) (Tajima and Sencer 2016): within the other half
                v = min(v, 4.0 * tolerance_m / (filter_s * (math.sin(seg.sweep) if seg.sweep < math.pi / 2 else 1.0)))
    return v


def _path_acceleration(seg: Segment, limits: Limits) -> float:
    """The acceleration (m/s^2) every axis allows along ``seg``, centripetal share included:
    the smallest a_i over the axis's share of the tangent."""
    share = seg.axis_share()
    return min(a / s for a, s in zip(limits.acceleration_m_per_s2, share) if s > 1e-12)


def _arc_damping(seg: Segment, v_limit: float, filter_s: float) -> float:
    """The share of what the centripetal part leaves that the speed may change by on an arc:
    ``1 / (1 + 3 v T / R)`` (``v`` its speed limit, ``T`` the filter), as the acceleration vector
    turns (``a_t v / R``) and the centripetal part grows (``2 v a_t / R``) while the speed
    changes, and the filter keeps the jerk within ``a / T`` only for what changes by steps."""
    return 1.0 / (1.0 + 3.0 * v_limit * filter_s * seg.curvature)


def build_path(moves: Iterable[Move], tolerance_m: float) -> tuple[list[Segment], list[Segment]]:
    """The programmed segments and the path with corners blended (machine m)."""
    programmed: list[Segment] = []
    position = None
    for move in moves:
        if position is None:
            position = (np.asarray(move.start_mm) + np.asarray(move.offset_mm)) * 1e-3
        seg = move_segment(move, position)
        if seg is None:
            continue
        programmed.append(seg)
        position = seg.end
    path: list[Segment] = []
    for seg in programmed:
        prev = path[-1] if path else None
        if (
            prev is not None
            and prev.kind == "line"
            and seg.kind == "line"
            and prev.rapid == seg.rapid
            and (blended := blend(prev, seg, 0.5 * tolerance_m)) is not None
        ):
            path[-1] = blended[0]
            path += [blended[1], blended[2]]
        else:
            path.append(seg)
    return programmed, path


def _junction_continues(a: Segment, b: Segment) -> bool:
    """Whether the motion may go through the junction of ``a`` and ``b`` without stopping."""
    if a.kind == "dwell" or b.kind == "dwell" or a.rapid != b.rapid:
        return False
    return math.acos(max(-1.0, min(1.0, float(a.tangent(True) @ b.tangent(False))))) < TANGENT_TOLERANCE_RAD


@numba.njit(cache=True)
def _passes(ds, vmax, a_t, damping, curvature):  # pragma: no cover - compiled
    """Forward and backward passes over the arc-length grid: ``ds[k]`` between points k and k+1,
    ``vmax[k]`` the speed limit at point k, ``a_t[k]`` the acceleration there of which the
    centripetal part takes ``v^2 curvature[k]`` and the speed may change by ``damping[k]`` of
    the rest; returns the speed at each point."""
    n = vmax.size
    v = vmax.copy()
    for k in range(n - 1):  # forward: how fast it can be, accelerating from the start
        room = max(a_t[k] - v[k] * v[k] * curvature[k], 0.0) * damping[k]
        v[k + 1] = min(v[k + 1], math.sqrt(v[k] * v[k] + 2.0 * room * ds[k]))
    for k in range(n - 2, -1, -1):  # backward: how fast it can be, braking to what follows
        room = max(a_t[k + 1] - v[k + 1] * v[k + 1] * curvature[k + 1], 0.0) * damping[k + 1]
        v[k] = min(v[k], math.sqrt(v[k + 1] * v[k + 1] + 2.0 * room * ds[k]))
    return v


def blocks_of(path: list[Segment]) -> list[list[Segment]]:
    """The path cut where the motion stops: at dwells (each a block of its own), rapid/feed
    changes and corners that are not blended; each block starts and ends at rest."""
    blocks: list[list[Segment]] = []
    for seg in path:
        if seg.kind == "dwell" or not blocks or blocks[-1][-1].kind == "dwell":
            blocks.append([seg])
        elif _junction_continues(blocks[-1][-1], seg):
            blocks[-1].append(seg)
        else:
            blocks.append([seg])
    return blocks


def _speed_profile(block: list[Segment], limits: Limits, override: float, filter_s: float, tolerance_m: float):
    """The look-ahead over one block: arc-length grid (cumulative s, m), speed at each point
    (m/s, 0 at both ends) and the index in ``block`` of the segment each point lies on.

    A blend's speed is held on the lines either side for the filter's window (``v T``): every
    window around the corner then sees no acceleration, and the filter cuts the corner only
    as :func:`_segment_speed_limit` allows (the grid gets points where that hold ends)."""
    limit = [_segment_speed_limit(seg, limits, override, filter_s, tolerance_m) for seg in block]
    hold = [limit[i] * filter_s if seg.blend else 0.0 for i, seg in enumerate(block)]
    s_parts, v_parts, a_parts, d_parts, k_parts, index = [], [], [], [], [], []
    s0 = 0.0
    for i, seg in enumerate(block):
        n = max(4, math.ceil(seg.length / GRID_M) + 1)
        grid = np.linspace(0.0, seg.length, n)
        vmax = np.full(n, limit[i])
        before = hold[i - 1] if i > 0 else 0.0  # a blend ends where this segment starts
        after = hold[i + 1] if i + 1 < len(block) else 0.0
        cuts = [c for c in (min(before, seg.length), max(seg.length - after, 0.0)) if 0.0 < c < seg.length]
        if cuts:
            grid = np.union1d(grid, cuts)
            vmax = np.full(grid.size, limit[i])
        if before > 0:
            vmax[grid <= before] = np.minimum(vmax[grid <= before], limit[i - 1])
        if after > 0:
            vmax[grid >= seg.length - after] = np.minimum(vmax[grid >= seg.length - after], limit[i + 1])
        s_parts.append(s0 + grid)
        v_parts.append(vmax)
        a_parts.append(np.full(grid.size, _path_acceleration(seg, limits)))
        d_parts.append(np.full(grid.size, _arc_damping(seg, limit[i], filter_s)))
        k_parts.append(np.full(grid.size, seg.curvature))
        index.append(np.full(grid.size, i))
        s0 += seg.length
    vmax = np.concatenate(v_parts)
    vmax[0] = vmax[-1] = 0.0
    s = np.concatenate(s_parts)
    a_t, damping, curvature = np.concatenate(a_parts), np.concatenate(d_parts), np.concatenate(k_parts)
    v = _passes(np.diff(s), vmax, a_t, damping, curvature)
    return s, v, np.concatenate(index)


def _time_of(s: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Time (s) at each grid point: ``ds / mean(v)`` per interval (exact for constant
    acceleration, where ``v^2`` is linear in s)."""
    ds = np.diff(s)
    mean = 0.5 * (v[1:] + v[:-1])
    dt = np.where(ds > 0, ds / np.maximum(mean, 1e-300), 0.0)
    return np.concatenate([[0.0], np.cumsum(dt)])


def _sample_arc_length(t, t_grid, s_grid, v_grid):
    """Arc length at times ``t`` with constant acceleration inside each grid interval, and the
    grid interval of each time."""
    k = np.clip(np.searchsorted(t_grid, t, side="right") - 1, 0, len(t_grid) - 2)
    ds = s_grid[k + 1] - s_grid[k]
    tau = np.clip(t - t_grid[k], 0.0, t_grid[k + 1] - t_grid[k])
    v0, v1 = v_grid[k], v_grid[k + 1]
    acc = np.where(ds > 0, (v1 * v1 - v0 * v0) / (2.0 * np.where(ds > 0, ds, 1.0)), 0.0)
    return s_grid[k] + np.minimum(v0 * tau + 0.5 * acc * tau * tau, ds), k


def _moving_average(x: np.ndarray, n: int) -> np.ndarray:
    """Each column of ``x`` averaged over windows of ``n`` samples, the ends held: the output is
    ``n - 1`` samples longer (the filter's delay)."""
    if n <= 1:
        return x.copy()
    padded = np.concatenate([np.repeat(x[:1], n - 1, axis=0), x, np.repeat(x[-1:], n - 1, axis=0)])
    c = np.cumsum(padded, axis=0)
    c = np.concatenate([np.zeros((1, x.shape[1])), c])
    return (c[n:] - c[:-n])[: x.shape[0] + n - 1] / n


def _derivatives(p: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """Velocity (central first difference) and acceleration (central second difference) of
    sampled positions, the reference at rest before the first sample and after the last."""
    q = np.concatenate([p[:1], p, p[-1:]])  # at rest before the first sample and after the last
    return (q[2:] - q[:-2]) / (2 * dt), (q[2:] - 2 * q[1:-1] + q[:-2]) / (dt * dt)


def feed_only_time(path: list[Segment], limits: Limits) -> float:
    """The time (s) at the programmed feeds alone: feeds at F, rapids at the axis limits, dwells."""
    total = 0.0
    for seg in path:
        if seg.kind == "dwell":
            total += seg.dwell_s
        elif seg.rapid:
            share = seg.axis_share()
            total += seg.length / min(v / s for v, s in zip(limits.velocity_m_per_s, share) if s > 1e-12)
        else:
            total += seg.length / seg.feed_m_per_s
    return total


def plan(moves: Iterable[Move], limits: Limits, settings: PlannerSettings | None = None) -> Plan:
    """Plan a program's moves into a reference sampled every :data:`SAMPLE_PERIOD_S`.

    Raises
    ------
    PlanningError
        A program with no motion, or one too long to hold (:data:`MAX_SAMPLES`).
    """
    settings = settings or PlannerSettings()
    moves = list(moves)
    if settings.tolerance_mm is not None:
        tolerance_mm = settings.tolerance_mm
    else:
        given = [m.tolerance_mm for m in moves if m.tolerance_mm]
        tolerance_mm = given[0] if given else DEFAULT_TOLERANCE_MM
    tolerance_m = tolerance_mm * 1e-3
    programmed, path = build_path(moves, tolerance_m)
    if not path:
        raise PlanningError("the program has no motion")
    dt = SAMPLE_PERIOD_S
    start = path[0].start
    positions, lines, scales, total = [start[None, :], start[None, :]], [np.array([path[0].line] * 2)], [1.0], 2
    grid_points = 0
    for block in blocks_of(path):
        if block[0].kind == "dwell":
            n = max(1, round(block[0].dwell_s / dt))
            if total + n > MAX_SAMPLES:
                raise PlanningError(f"a dwell of {block[0].dwell_s:g} s is longer than a reference holds: split it")
            positions.append(np.repeat(positions[-1][-1:], n, axis=0))
            lines.append(np.full(n, block[0].line))
        else:
            grid_points += sum(max(4, math.ceil(seg.length / GRID_M) + 1) for seg in block)
            if grid_points > MAX_GRID_POINTS:
                raise PlanningError(f"the path is too long to plan at once ({MAX_GRID_POINTS} grid points): split it")
            p, line, scale = _plan_block(block, limits, settings.feed_override, tolerance_m)
            positions.append(p)
            lines.append(line)
            scales.append(scale)
        total += len(positions[-1])
        if total > MAX_SAMPLES:
            raise PlanningError(
                f"the program runs longer than {MAX_SAMPLES * dt:.0f} s of motion, which a reference holds at once: "
                "split it"
            )
    positions.append(positions[-1][-1:].repeat(2, axis=0))
    lines.append(np.repeat(lines[-1][-1:], 2))
    position = np.concatenate(positions)
    velocity, acceleration = _derivatives(position, dt)
    return Plan(
        dt,
        position,
        velocity,
        acceleration,
        np.concatenate(lines),
        feed_only_time(programmed, limits),
        max(scales),
        _filter_length(limits)[0],
        tolerance_m,
        programmed,
        {m.line: m.text for m in moves},
        {m.line: (m.spindle_rpm if m.spindle != "off" else 0.0) for m in moves},
        {m.line: m.tool for m in moves},
        {m.line: m.feed_mm_per_min for m in moves},
    )


def _filter_length(limits: Limits) -> tuple[float, int]:
    """The smoothing filter's length (s) and samples: ``max(a_i / j_i)``."""
    filter_s = max(a / j for a, j in zip(limits.acceleration_m_per_s2, limits.jerk_m_per_s3))
    n = max(1, round(filter_s / SAMPLE_PERIOD_S))
    return (n * SAMPLE_PERIOD_S if n > 1 else 0.0), n


def _plan_block(block: list[Segment], limits: Limits, override: float, tolerance_m: float):
    """One rest-to-rest block: smoothed positions (n, 3), the program line of each, and the
    time scale it needed (1: none; the block is re-planned slower until every axis is within
    its limits: velocity scales by 1/k, acceleration 1/k^2, jerk 1/k^3)."""
    scale = 1.0
    for _attempt in range(4):
        scaled = Limits(
            tuple(v / scale for v in limits.velocity_m_per_s),
            tuple(a / scale**2 for a in limits.acceleration_m_per_s2),
            tuple(j / scale**3 for j in limits.jerk_m_per_s3),
        )
        position, lines = _sample_block(block, scaled, override / scale, tolerance_m)
        velocity, acceleration = _derivatives(position, SAMPLE_PERIOD_S)
        excess = _excess(velocity, acceleration, SAMPLE_PERIOD_S, limits)
        if excess <= 1.0005:
            break
        scale *= excess * 1.001
    return position, lines, scale


def _sample_block(block: list[Segment], limits: Limits, override: float, tolerance_m: float):
    """Positions (n, 3) of one block every :data:`SAMPLE_PERIOD_S`, smoothed by the moving
    average (so ``n`` includes the filter's length), and the program line of each."""
    dt = SAMPLE_PERIOD_S
    filter_s, n_filter = _filter_length(limits)
    s, v, index = _speed_profile(block, limits, override, filter_s, tolerance_m)
    t_grid = _time_of(s, v)
    n = math.ceil(t_grid[-1] / dt) + 1
    if n + n_filter > MAX_SAMPLES:
        raise PlanningError(
            f"a block of the program runs {t_grid[-1]:.0f} s: longer than {MAX_SAMPLES * dt:.0f} s, which a "
            "reference holds at once; split it"
        )
    s_t, k = _sample_arc_length(np.arange(n) * dt, t_grid, s, v)
    seg_t = index[k]
    offsets = np.concatenate([[0.0], np.cumsum([seg.length for seg in block])])
    position = np.empty((n, 3))
    bounds = np.searchsorted(seg_t, np.arange(len(block) + 1))  # seg_t never decreases
    for i, (lo, hi) in enumerate(itertools.pairwise(bounds)):
        if hi > lo:
            position[lo:hi] = block[i].points(np.clip(s_t[lo:hi] - offsets[i], 0.0, block[i].length))
    smooth = _moving_average(position, n_filter)
    # the line of each output sample: that of the input at its window's centre
    line_of_input = np.array([seg.line for seg in block])[seg_t]
    centre = np.clip(np.arange(smooth.shape[0]) - (n_filter - 1) // 2, 0, n - 1)
    return smooth, line_of_input[centre]


def _excess(velocity: np.ndarray, acceleration: np.ndarray, dt: float, limits: Limits) -> float:
    """The slow-down k that would bring every axis within its limits (velocity scales by 1/k,
    acceleration 1/k^2, jerk 1/k^3 when time is stretched by k); 1 when all are within."""
    jerk = np.diff(acceleration, axis=0, prepend=0.0, append=0.0) / dt
    ratios = [1.0]
    for i in range(3):
        ratios.append(float(np.abs(velocity[:, i]).max()) / limits.velocity_m_per_s[i])
        ratios.append(math.sqrt(float(np.abs(acceleration[:, i]).max()) / limits.acceleration_m_per_s2[i]))
        ratios.append((float(np.abs(jerk[:, i]).max()) / limits.jerk_m_per_s3[i]) ** (1.0 / 3.0))
    return max(ratios)
