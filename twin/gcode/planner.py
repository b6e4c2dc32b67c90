"""The interpolator: a part program's moves planned into a jerk-limited reference, as a CNC's
trajectory planner does it, sampled at a fixed period and streamed in windows of look-ahead.

How (our design; the docs page ``gcode.md`` says why):

1. The path (:mod:`twin.gcode.path`): lines, arcs, helices and spirals in machine coordinates;
   corners between lines blended by tangent arcs within half the tolerance in force (LinuxCNC's
   G64 P rule). Each move's path mode governs the junction at its end: G64 blends, G61 stops
   at every corner that is not tangent, G61.1 stops at every junction.
2. Junctions that are not blended (an arc meeting a line or an arc at a kink) are passed at the
   speed the smoothing filter below can absorb: its rounding of the kink within half the
   tolerance, the velocity step per axis within half of what the filter turns into the axis's
   acceleration and sampled jerk; junctions where the curvature jumps (an S between two arcs)
   at the speed whose acceleration step the filter ramps within the jerk limit.
3. Speed limits along the path: the programmed feed times the override (rapids: the axis
   limits), each axis's velocity limit over its share of the tangent, and on arcs the
   centripetal acceleration ``v <= sqrt(a R)`` and the jerk of the turning acceleration ``v <=
   0.97 (j R^2)^(1/3)``; on corner blends the contour shrink of the filter (``v^2 T^2 / (24 R)``
   within half the tolerance). On programmed arcs the shrink is compensated instead (the raw
   samples put out by it, :func:`_shrink_compensation`), the speed held where an arc meets what
   does not continue it so that the compensation is nothing there, and ``v <= 2 R / T``.
4. Look-ahead: backward and forward passes over an arc-length grid with the tangential
   acceleration the axes have left beside the centripetal one (the time-optimal
   acceleration-limited speed profile), over a window of the path: the part of the window whose
   speeds a stop at the window's end and full speed there agree on is final and handed on (cut
   at a cruise, where the speed is constant for twice the filter's reach at that speed), the
   rest planned again with more of the path (a window with no cruise yet: once it is half as
   long again, so that planning stays linear in the program's length). Neither the program nor
   the reference is ever held whole.
5. Jerk: each axis's position passes a moving-average filter of length ``T = max(a_i / j_i)``
   (FIR interpolation, Tajima and Sencer 2016): a trapezoidal acceleration becomes an S-curve.
   Where the profile turns from accelerating to braking (or back) in less than ``T`` the filter
   would see a swing of twice the acceleration, so the speed there is lowered until a cruise of
   ``T`` separates the two.
6. Check: every axis's velocity, acceleration and jerk on the sampled reference are measured
   before a window is handed on; where one exceeds its limit the window is planned again with
   the speed lowered there (locally, not the whole program), and what still exceeds after
   :data:`MAX_REPAIRS` tries is reported with its line and axis (:attr:`Plan.violations`).
"""

from __future__ import annotations

import copy
import math
from collections.abc import Generator, Iterable, Iterator, Sequence
from dataclasses import dataclass, field
from typing import Literal, NamedTuple

import numba
import numpy as np
from pydantic import Field, field_validator

from twin.gcode.linuxcnc_planner import LinuxcncStream
from twin.gcode.moves import Move
from twin.gcode.path import TANGENT_TOLERANCE_RAD, Segment, SegmentKind, blend, move_segment, turn_angle
from twin.gcode.planned import (
    LIMIT_SLACK,
    SAMPLE_PERIOD_S,
    Limits,
    PlanChunk,
    PlanningError,
    ProgramFacts,
    Violation,
    limit_ratios,
)
from twin.numba_cache import configure as configure_numba_cache
from twin.spec import StrictSpec

configure_numba_cache()  # before the first @njit(cache=True): see twin.numba_cache

#: Most samples a reference held whole may have (``plan()``; about 33 minutes at 1 ms). A run
#: without a stock streams its reference and has no such limit.
MAX_SAMPLES = 2_000_000
#: Arc-length grid of the look-ahead (m): finer on short segments (:data:`MIN_SEGMENT_POINTS`).
GRID_M = 5e-5
#: Grid points of a segment at least (a short move's peak is capped between them).
MIN_SEGMENT_POINTS = 16
#: Grid points the look-ahead plans at once before it looks for a cruise to hand on at.
WINDOW_POINTS = 40_000
#: Motion (s) the look-ahead plans at once at most before it looks for a cruise to hand on at
#: (bounds the samples a window makes: a slow feed along a long move).
WINDOW_TIME_S = 20.0
#: Grid points of a piece at most: a longer segment enters the look-ahead in pieces (so that a
#: window over a long, slow move plans no more than it hands on).
PIECE_POINTS = 4_000
#: Samples a program's reference may have (10 hours at 1 ms; ours: a run streams it, but its
#: length is counted first, and a program longer than this is refused).
MAX_PROGRAM_SAMPLES = 36_000_000
#: Longest stretch (s) the look-ahead may sample at once: a program's longest (it cuts one at a
#: cruise within :data:`WINDOW_TIME_S` where it can); a stretch that takes longer (repairs that
#: slowed a place to rest) is refused before it is sampled.
MAX_STRETCH_S = MAX_PROGRAM_SAMPLES * SAMPLE_PERIOD_S
#: Most grid points the look-ahead window may grow to; a path with no cruise over that length
#: (more than 50 m of continuous motion without one) comes to a stop there, reported.
MAX_WINDOW_POINTS = 1_000_000
#: Tolerance (mm) for G64 without P (LinuxCNC's "best speed": no bound, which a twin cannot
#: check a path against; ours), unless the scenario's ``[planner] tolerance_mm`` gives one.
DEFAULT_TOLERANCE_MM = 0.01
#: Share of each axis's acceleration and sampled jerk a kink's velocity step may take (ours).
KINK_SHARE = 0.5
#: Share of the tolerance the moving-average filter's shrink of an arc may take uncompensated:
#: at an arc's ends (where its speed is held to it) and where its compensation starts (ours).
SHRINK_HELD_SHARE = 0.4
#: Share of the tolerance from which an arc's shrink is compensated whole (ours).
SHRINK_FULL_SHARE = 0.6
#: Most angle (rad) an arc may turn within the filter's length (``v <= 2 R / T``): the
#: compensation ``r (1 / sinc - 1)`` stays under a fifth of the radius (ours).
MAX_FILTER_TURN_RAD = 2.0
#: Share of the jerk limit an arc's turning acceleration may take, ``(j R^2)^(1/3)``: the speed
#: changes on the arc add their own (ours).
JERK_SHARE = 0.97
#: Tries at planning a window again slower where its sampled reference exceeds a limit.
MAX_REPAIRS = 8


class _Context(NamedTuple):
    """What the planner plans with: the limits, the feed override, the smoothing filter's length
    (s) and samples, and the acceleration change (m/s^2) the filter may see within its length."""

    limits: Limits
    override: float
    filter_s: float
    n_filter: int
    budget: float


class PlannerSettings(StrictSpec):
    """The scenario's ``[planner]`` table (``twin gcode --set planner.KEY=VALUE``).

    Each axis's limits default to the machine's (its README says where they come from);
    ``velocity_m_per_s = { x = 0.2 }`` and the like override them.
    """

    mode: Literal["jerk_limited", "linuxcnc"] = Field(
        "jerk_limited",
        description="jerk_limited: the twin's planner; linuxcnc: LinuxCNC 2.9's trajectory planner as it behaves "
        "(per-axis velocity and acceleration limits, no jerk limit; twin.gcode.linuxcnc_planner)",
    )
    tolerance_mm: float | None = Field(
        None,
        gt=0.0,
        le=10.0,
        description="how far the path may leave the programmed one, mm, for every G64 block (default: "
        "each block's G64 P, 0.01 where G64 has none)",
    )
    feed_override: float = Field(1.0, gt=0.0, le=10.0, description="factor on every programmed feed")
    velocity_m_per_s: dict[str, float] = Field(default_factory=dict, description="axis velocity limits, m/s")
    acceleration_m_per_s2: dict[str, float] = Field(default_factory=dict, description="axis acceleration limits, m/s^2")
    jerk_m_per_s3: dict[str, float] = Field(default_factory=dict, description="axis jerk limits, m/s^3")
    travel: Literal["refuse", "warn"] = Field(
        "refuse", description="a move outside the machine's travel: refuse the program, or warn of each line"
    )

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

    def tolerance_m(self, move: Move) -> float:
        """The tolerance (m) in force on ``move``: this table's, else its G64 P, else (G64
        without P, G61, G61.1) :data:`DEFAULT_TOLERANCE_MM`."""
        if self.tolerance_mm is not None:
            return self.tolerance_mm * 1e-3
        return (move.tolerance_mm if move.tolerance_mm is not None else DEFAULT_TOLERANCE_MM) * 1e-3


@dataclass
class Plan:
    """A planned reference sampled every ``period_s``, held whole (:func:`plan`).

    Attributes
    ----------
    period_s : float
        Sample period (s).
    position, velocity, acceleration : ndarray (n, 3)
        Machine axes x, y, z (m, m/s, m/s^2).
    line : ndarray (n,) of int
        The program line each sample is on (before the smoothing filter's delay of half its
        window, which the reference leads by).
    sample_tolerance_m : ndarray (n,)
        The tolerance in force at each sample (m).
    feed_only_time_s : float
        The program at its programmed feeds alone (rapids at the axis limits, dwells).
    time_scale : float
        The largest local slow-down the check needed (1: none).
    filter_s : float
        The smoothing filter's length (s).
    tolerance_m : float
        The largest tolerance in force anywhere in the program (m).
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
    violations : list of Violation
        Limits the reference still exceeds (empty: every axis within its limits).
    notes : list of str
        What the planner had to do that a user should know (a stop it added).
    """

    period_s: float
    position: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray
    line: np.ndarray
    sample_tolerance_m: np.ndarray
    feed_only_time_s: float
    time_scale: float
    filter_s: float
    tolerance_m: float
    segments: list[Segment] = field(repr=False)
    texts: dict[int, str] = field(default_factory=dict, repr=False)
    spindle_rpm: dict[int, float] = field(default_factory=dict, repr=False)
    tools: dict[int, int] = field(default_factory=dict, repr=False)
    feeds: dict[int, float] = field(default_factory=dict, repr=False)
    violations: list[Violation] = field(default_factory=list, repr=False)
    notes: list[str] = field(default_factory=list, repr=False)

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


def _filter_length(limits: Limits) -> tuple[float, int]:
    """The smoothing filter's length (s) and samples: ``max(a_i / j_i)``."""
    filter_s = max(a / j for a, j in zip(limits.acceleration_m_per_s2, limits.jerk_m_per_s3))
    n = max(1, round(filter_s / SAMPLE_PERIOD_S))
    return (n * SAMPLE_PERIOD_S if n > 1 else 0.0), n


def _context(limits: Limits, settings: PlannerSettings) -> _Context:
    filter_s, n_filter = _filter_length(limits)
    window = max(filter_s, SAMPLE_PERIOD_S)
    budget = min(j * window for j in limits.jerk_m_per_s3)
    return _Context(limits, settings.feed_override, filter_s, n_filter, budget)


# --- path ---------------------------------------------------------------------------------


def _programmed(moves: Iterable[Move], settings: PlannerSettings, facts: ProgramFacts | None) -> Iterator[Segment]:
    """The programmed segments (machine m), null moves dropped; the facts gathered (if given)."""
    position = None
    for move in moves:
        if position is None:
            position = (np.asarray(move.start_mm) + np.asarray(move.offset_mm)) * 1e-3
        seg = move_segment(move, position, settings.tolerance_m(move))
        if facts is not None:
            facts.record(move, seg)
        if seg is None:
            continue
        position = seg.end
        yield seg


def _blended(programmed: Iterable[Segment]) -> Iterator[Segment]:
    """The path: G64 corners between lines (both feeds or both rapids) blended within half the
    tolerance of the move that ends there."""
    previous: Segment | None = None
    for seg in programmed:
        if previous is None:
            previous = seg
            continue
        pieces = None
        if (
            previous.kind == SegmentKind.LINE
            and seg.kind == SegmentKind.LINE
            and previous.rapid == seg.rapid
            and previous.mode == "G64"
        ):
            pieces = blend(previous, seg, 0.5 * previous.tolerance_m)
        if pieces is not None:
            yield pieces[0]
            yield pieces[1]
            previous = pieces[2]
        else:
            yield previous
            previous = seg
    if previous is not None:
        yield previous


def _least_time(path: Iterable[Segment], ctx: _Context, most_s: float, limit: str) -> Iterator[Segment]:
    """The path's segments as they pass, and a lower bound of the motion's time counted on the way:
    each segment at its speed limit (:func:`_segment_speed_limit`, which the look-ahead never
    exceeds), each dwell its time. Where the bound passes ``most_s`` the program is refused at
    that segment's line, before it is planned.

    Raises
    ------
    PlanningError
        Naming the line, the bound and ``limit`` (what ``most_s`` is).
    """
    total = 0.0
    for seg in path:
        if seg.kind == SegmentKind.DWELL:
            total += seg.dwell_s
        else:
            total += seg.length / _segment_speed_limit(seg, ctx.limits, ctx.override, ctx.filter_s)
        if total > most_s:
            raise PlanningError(
                f"line {seg.line}: the program runs longer than {limit}: its moves to this line take at least "
                f"{total:.0f} s ({total / 3600:.1f} h) at their feeds and the axes' velocity limits"
            )
        yield seg


def refuse_long(moves: Iterable[Move], limits: Limits, settings: PlannerSettings, *, most_s: float, limit: str) -> None:
    """Count a lower bound of the program's motion time from its moves alone, before (and
    without) planning them: time linear in its length, memory bounded.

    Raises
    ------
    PlanningError
        The bound passes ``most_s`` (``limit`` says what that is): the line where it does, and
        the bound.
    """
    for _seg in _least_time(_blended(_programmed(moves, settings, None)), _context(limits, settings), most_s, limit):
        pass


def _junction_speed(a: Segment, b: Segment, ctx: _Context) -> float:
    """The speed (m/s) the motion may keep through the junction of ``a`` and ``b``; 0: a stop.
    Into and out of a corner blend: the blend's speed (held on the lines around it)."""
    if a.kind == SegmentKind.DWELL or b.kind == SegmentKind.DWELL or a.rapid != b.rapid or a.mode == "G61.1":
        return 0.0
    limits, filter_s = ctx.limits, ctx.filter_s
    blended = [seg for seg in (a, b) if seg.blend]
    if blended:
        return min(_segment_speed_limit(seg, limits, ctx.override, filter_s) for seg in blended)
    window = max(filter_s, SAMPLE_PERIOD_S)
    dt = SAMPLE_PERIOD_S
    speed = math.inf
    turn = turn_angle(a, b)
    if turn >= TANGENT_TOLERANCE_RAD:
        if a.mode != "G64" or turn > math.pi / 2:
            return 0.0
        # the filter rounds the kink by (v T / 8) sin(turn) between straight legs: within 90 % of
        # half the tolerance (an arc's leg adds its own rounding, which has the other half)
        speed = 0.9 * 4.0 * a.tolerance_m / (window * math.sin(turn))
        step = np.abs(b.tangent(False) - a.tangent(True))
        for i in range(3):
            if step[i] > 0:
                budget = KINK_SHARE * min(
                    limits.acceleration_m_per_s2[i] * window, limits.jerk_m_per_s3[i] * window * dt
                )
                speed = min(speed, budget / step[i])
    # an acceleration step of v^2 |d(kappa n)| the filter ramps within the jerk limit
    jump = np.abs(b.acceleration_direction(False) - a.acceleration_direction(True))
    for i in range(3):
        if jump[i] > 1e-12:
            speed = min(speed, math.sqrt(limits.jerk_m_per_s3[i] * window / jump[i]))
    # an arc's compensation of the filter's shrink is weighed out before its end, unless the
    # next arc goes on with the same
    if not _continues(a, b, filter_s):
        if _compensated(a, filter_s):
            speed = min(speed, _arc_end_speed(a, True, filter_s))
        if _compensated(b, filter_s):
            speed = min(speed, _arc_end_speed(b, False, filter_s))
    return speed


def _segment_speed_limit(seg: Segment, limits: Limits, override: float, filter_s: float) -> float:
    """The highest path speed (m/s) on ``seg`` (worked out once per segment and limits)."""
    known = seg.planned.get("speed_limit")  # (limits, override, filter, speed): the same limits object
    if known is None or known[0] is not limits or known[1] != override or known[2] != filter_s:
        known = (limits, override, filter_s, _speed_limit(seg, limits, override, filter_s))
        seg.planned["speed_limit"] = known
    return known[3]


def _speed_limit(seg: Segment, limits: Limits, override: float, filter_s: float) -> float:
    share = seg.axis_share()
    v_axis = math.inf
    for axis in range(3):
        if share[axis] > 1e-12:
            v_axis = min(v_axis, limits.velocity_m_per_s[axis] / float(share[axis]))
    v = v_axis if seg.rapid else min(seg.feed_m_per_s * override, v_axis)
    if seg.kind == SegmentKind.ARC:
        # the turning acceleration and its jerk lie in the arc's plane (a helix's rise is at
        # constant speed): the plane's axes bound them
        assert seg.u is not None and seg.v is not None
        plane = np.hypot(seg.u, seg.v) > 1e-12
        a = min(x for x, p in zip(limits.acceleration_m_per_s2, plane) if p)
        j = min(x for x, p in zip(limits.jerk_m_per_s3, plane) if p)
        r = 1.0 / seg.curvature
        v = min(v, math.sqrt(a * r), JERK_SHARE * (j * r * r) ** (1.0 / 3.0))
        if filter_s > 0 and not seg.blend:
            # the filter's shrink is compensated (:func:`_shrink_compensation`) up to a turn of
            # MAX_FILTER_TURN_RAD within the filter's length
            r_least = min(seg.radius, seg.radius_end)
            q = math.hypot(r_least, (seg.radius_end - seg.radius) / seg.sweep, seg.rise / seg.sweep)
            v = min(v, MAX_FILTER_TURN_RAD * q / filter_s)
        elif filter_s > 0:
            # a blend: the filter shrinks it by v^2 T^2 / (24 R): within half the tolerance; and a
            # blend shorter than the filter's window the filter cuts as a sharp corner, by
            # (v T / 8) sin(turn) (Tajima and Sencer 2016): within 90 % of the other half
            v = min(v, math.sqrt(24.0 * r * 0.5 * seg.tolerance_m) / filter_s)
            v = min(v, 0.9 * 4.0 * seg.tolerance_m / (filter_s * math.sin(min(seg.sweep, math.pi / 2))))
    return v


def _compensated(seg: Segment, filter_s: float) -> bool:
    """Whether the filter's shrink of ``seg`` is compensated: a programmed arc (not a corner
    blend), with a filter."""
    return seg.kind == SegmentKind.ARC and not seg.blend and filter_s > 0


def _arc_end_speed(seg: Segment, at_end: bool, filter_s: float) -> float:
    """The speed (m/s) a compensated arc is held at where it meets what does not continue it:
    its shrink there, uncompensated, ``r (w T)^2 / 24`` (above ``r (1 - sinc(w T / 2))``) within
    :data:`SHRINK_HELD_SHARE` of the tolerance (``w``: the angle turned per second)."""
    there = seg.outward(np.array([seg.length if at_end else 0.0]))
    turn_rate = math.sqrt(24.0 * SHRINK_HELD_SHARE * seg.tolerance_m / float(there.radius[0])) / filter_s
    return turn_rate / float(there.turn_per_m[0])


def _continues(a: Segment, b: Segment, filter_s: float) -> bool:
    """Whether compensated arc ``b`` goes on from compensated arc ``a`` as the same curve (the
    same radius, turn rate, outward direction and tolerance at the junction: the shrink's
    compensation the same on both sides)."""
    if not (_compensated(a, filter_s) and _compensated(b, filter_s)) or a.tolerance_m != b.tolerance_m:
        return False
    end, start = a.outward(np.array([a.length])), b.outward(np.array([0.0]))
    return (
        float(end.direction[0] @ start.direction[0]) > 1.0 - 1e-12
        and abs(float(end.radius[0] - start.radius[0])) <= 1e-9 * float(end.radius[0])
        and abs(float(end.turn_per_m[0] - start.turn_per_m[0])) <= 1e-9 * float(end.turn_per_m[0])
    )


def _shrink_compensation(
    seg: Segment, s: np.ndarray, speed: np.ndarray, filter_s: float
) -> tuple[np.ndarray, np.ndarray]:
    """How far (m) out from the arc the raw samples at arc lengths ``s`` (m) and path speeds
    ``speed`` (m/s) are put so that the moving average of length ``T`` lands on the arc, and
    the direction, (n,) and (n, 3).

    An arc turning at ``w`` rad/s comes out of the filter at radius ``r sinc(w T / 2)``: a raw
    arc of radius ``r / sinc`` comes out at ``r``. The compensation is weighed in from nothing,
    where the shrink is :data:`SHRINK_HELD_SHARE` of the tolerance, to whole at
    :data:`SHRINK_FULL_SHARE` (smoothstep): the path stays within the held share, and an arc's
    end, where the speed is held below that (:func:`_arc_end_speed`), gets none.
    """
    at = seg.outward(s)
    half_turn = np.maximum(0.5 * speed * at.turn_per_m * filter_s, 1e-12)
    sinc = np.sin(half_turn) / half_turn
    shrink = at.radius * (1.0 - sinc)
    held, full = SHRINK_HELD_SHARE * seg.tolerance_m, SHRINK_FULL_SHARE * seg.tolerance_m
    x = np.clip((shrink - held) / (full - held), 0.0, 1.0)
    weight = x * x * (3.0 - 2.0 * x)
    return weight * at.radius * (1.0 / sinc - 1.0), at.direction


def _path_acceleration(segments: list[Segment], limits: Limits) -> np.ndarray:
    """The acceleration (m/s^2) every axis allows along each segment, centripetal share
    included: the smallest a_i over the axis's share of the tangent."""
    share = np.array([seg.axis_share() for seg in segments])
    per_axis = np.array(limits.acceleration_m_per_s2) / np.maximum(share, 1e-300)
    return np.where(share > 1e-12, per_axis, math.inf).min(axis=1)


def _arc_damping(curvature: np.ndarray, v_limit: np.ndarray, filter_s: float) -> np.ndarray:
    """The share of what the centripetal part leaves that the speed may change by on an arc:
    ``1 / (1 + 3 v T / R)`` (``v`` its speed limit, ``T`` the filter), as the acceleration vector
    turns (``a_t v / R``) and the centripetal part grows (``2 v a_t / R``) while the speed
    changes, and the filter keeps the jerk within ``a / T`` only for what changes by steps."""
    return 1.0 / (1.0 + 3.0 * v_limit * filter_s * curvature)


# --- the look-ahead ---------------------------------------------------------------------------


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


@numba.njit(cache=True)
def _swings(s, v, filter_s, budget):  # pragma: no cover - compiled
    """Where the profile's acceleration changes by more than ``budget`` within ``filter_s``
    (the filter would turn that into more than the jerk limit): for each such place the grid
    index of the speed's extremum between the two and +1 (a peak) or -1 (a valley)."""
    n = v.size
    acc = np.zeros(n - 1)
    t = np.zeros(n)
    for k in range(n - 1):
        ds = s[k + 1] - s[k]
        mean = 0.5 * (v[k] + v[k + 1])
        if ds > 0.0 and mean > 0.0:
            acc[k] = (v[k + 1] * v[k + 1] - v[k] * v[k]) / (2.0 * ds)
            t[k + 1] = t[k] + ds / mean
        else:
            t[k + 1] = t[k]
    out_index = []
    out_kind = []
    m = 0
    last = -1
    for k in range(n - 1):
        while t[m + 1] < t[k] - filter_s:
            m += 1
        for q in range(m, k):
            if abs(acc[k] - acc[q]) > budget and acc[k] * acc[q] < 0.0:
                kind = 1 if acc[q] > 0.0 else -1
                best = q + 1
                for r in range(q + 1, k + 1):
                    if (kind > 0 and v[r] > v[best]) or (kind < 0 and v[r] < v[best]):
                        best = r
                if best != last:
                    out_index.append(best)
                    out_kind.append(kind)
                    last = best
                break
    return np.array(out_index, dtype=np.int64), np.array(out_kind, dtype=np.int64)


class _Grid:
    """The look-ahead's arc-length grid over some segments: cumulative s (m), speed limit,
    acceleration, damping and curvature at each point, and the segment each lies on."""

    def __init__(self, segments: list[Segment], junctions: list[float], *, v_start: float, v_end: float, ctx):
        limits, override, filter_s = ctx.limits, ctx.override, ctx.filter_s
        n = len(segments)
        length = np.array([seg.length for seg in segments])
        limit = np.array([_segment_speed_limit(seg, limits, override, filter_s) for seg in segments])
        # each segment's points: MIN_SEGMENT_POINTS at least, GRID_M apart at most (numpy's
        # linspace, vectorized)
        counts = np.maximum(MIN_SEGMENT_POINTS, np.ceil(length / GRID_M).astype(np.int64) + 1)
        owner = np.repeat(np.arange(n), counts)
        first = np.cumsum(counts) - counts
        local = (np.arange(owner.size) - first[owner]) * (length / (counts - 1))[owner]
        local[first + counts - 1] = length
        # a junction passed below the speeds around it is held for v T on either side (grid
        # points put where the hold ends), so every window of the filter around it sees no
        # change of speed and it rounds the junction no more than the junction's speed allows
        into = np.array([math.inf, *junctions])  # the junction each segment starts at (none: inf)
        out_of = np.array([*junctions, math.inf])
        held = np.nan_to_num(np.array(junctions, dtype=float), posinf=0.0) * filter_s
        before = np.minimum(np.concatenate([[0.0], held]), length)
        after = np.minimum(np.concatenate([held, [0.0]]), length)
        cut_owner = np.concatenate([np.arange(n), np.arange(n)])
        cut = np.concatenate([before, length - after])
        inside = (cut > 0.0) & (cut < length[cut_owner])
        owner = np.concatenate([owner, cut_owner[inside]])
        local = np.concatenate([local, cut[inside]])
        order = np.lexsort((local, owner))
        owner, local = owner[order], local[order]
        fresh = np.concatenate([[True], (owner[1:] != owner[:-1]) | (local[1:] != local[:-1])])
        owner, local = owner[fresh], local[fresh]
        vmax = limit[owner]
        at_start = local <= before[owner]
        vmax[at_start] = np.minimum(vmax[at_start], into[owner[at_start]])
        at_end = local >= (length - after)[owner]
        vmax[at_end] = np.minimum(vmax[at_end], out_of[owner[at_end]])
        offset = np.concatenate([[0.0], np.cumsum(length)[:-1]])  # as a running sum adds them
        self.segments = segments
        self.s = offset[owner] + local
        self.vmax = vmax
        self.vmax[0] = min(self.vmax[0], v_start)
        self.vmax[-1] = min(self.vmax[-1], v_end)
        curvature = np.array([seg.curvature for seg in segments])
        self.a_t = _path_acceleration(segments, limits)[owner]
        self.damping = _arc_damping(curvature, limit, filter_s)[owner]
        self.curvature = curvature[owner]
        self.index = owner

    def ending_at(self, v_end: float) -> _Grid:
        """The same grid, with speed limits and accelerations of its own (what planning changes)
        and the end's speed at most ``v_end`` (m/s)."""
        other = copy.copy(self)
        other.vmax, other.a_t = self.vmax.copy(), self.a_t.copy()
        other.vmax[-1] = min(other.vmax[-1], v_end)
        return other

    def speeds(self, filter_s: float, budget: float) -> np.ndarray:
        """The profile: passes, then the speed lowered at every swing the filter cannot take
        (peaks until a cruise of ``T`` tops them, valleys held for ``T``)."""
        ds = np.diff(self.s)
        for _ in range(64):
            v = _passes(ds, self.vmax, self.a_t, self.damping, self.curvature)
            if filter_s <= 0:
                return v
            where, kinds = _swings(self.s, v, filter_s, budget)
            if where.size == 0:
                return v
            for k, kind in zip(where, kinds):
                if kind > 0:
                    self._cap_peak(v, int(k), filter_s)
                else:
                    reach = 0.5 * v[k] * filter_s + GRID_M
                    near = np.abs(self.s - self.s[k]) <= reach
                    self.vmax[near] = np.minimum(self.vmax[near], v[k])
        return _passes(ds, self.vmax, self.a_t, self.damping, self.curvature)

    def _cap_peak(self, v: np.ndarray, k: int, filter_s: float) -> None:
        """Lower the peak at grid point ``k`` to the speed whose plateau lasts ``filter_s``."""
        lo, hi = 0.0, float(v[k])
        left, right = k, k
        while left > 0 and v[left - 1] <= v[left]:
            left -= 1
        while right < v.size - 1 and v[right + 1] <= v[right]:
            right += 1
        for _ in range(40):
            cap = 0.5 * (lo + hi)
            above = np.nonzero(v[left : right + 1] >= cap)[0]
            span = self.s[left + above[-1]] - self.s[left + above[0]] if above.size else 0.0
            if cap > 0 and span / cap >= filter_s:
                lo = cap
            else:
                hi = cap
        above = np.nonzero(v[left : right + 1] >= lo)[0] + left
        if above.size:
            self.vmax[above[0] : above[-1] + 1] = np.minimum(self.vmax[above[0] : above[-1] + 1], lo)

    def lower(self, s_lo: float, s_hi: float, speed: float, acceleration: float) -> None:
        """A repair: the speed limit and the acceleration between ``s_lo`` and ``s_hi`` times
        these factors."""
        near = (self.s >= s_lo) & (self.s <= s_hi)
        self.vmax[near] *= speed
        self.a_t[near] *= acceleration


def _bounded(grid: _Grid, v: np.ndarray) -> None:
    """Refuse a stretch whose profile would take longer than :data:`MAX_STRETCH_S` (a speed of 0,
    or next to it, over a grid interval: repairs that multiplied a place's speed limit and
    acceleration down to nothing), before its samples are made.

    Raises
    ------
    PlanningError
        Naming the line of the slowest interval, its speed and the stretch's time.
    """
    ds = np.diff(grid.s)
    mean = 0.5 * (v[1:] + v[:-1])
    slow = ds > mean * MAX_STRETCH_S  # an interval alone over the bound (or at rest)
    total = float(np.sum(np.where(ds > 0, ds / np.maximum(mean, 1e-300), 0.0))) if not slow.any() else math.inf
    if total > MAX_STRETCH_S:
        k = int(np.argmin(np.where(ds > 0, mean, math.inf)))
        line = grid.segments[int(grid.index[k])].line
        raise PlanningError(
            f"line {line}: the planned speed falls to {float(mean[k]):.3g} m/s here (its feed, or its limits lowered "
            f"where the sampled reference was over one): a stretch of more than {MAX_STRETCH_S:.0f} s of motion "
            "between two cruises, longer than a program may run"
        )


def _time_of(s: np.ndarray, v: np.ndarray, v0: float = 0.0) -> np.ndarray:
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
    speed = np.maximum(v0 + acc * tau, 0.0)
    return s_grid[k] + np.minimum(v0 * tau + 0.5 * acc * tau * tau, ds), speed, k


@dataclass
class _Raw:
    """Raw (unfiltered) samples of a stretch: positions (n, 3), line and tolerance of each."""

    position: np.ndarray
    line: np.ndarray
    tolerance: np.ndarray


def _window_mean(x: np.ndarray, width: int) -> np.ndarray:
    """The mean of ``x`` over ``width`` samples about each, centred as the filter centres its
    window; beyond the ends ``x`` holds its end values (a stretch ends at rest or within a
    cruise of twice the filter's length, where it holds)."""
    centre = (width - 1) // 2
    padded = np.concatenate([np.full(width - 1 - centre, x[0]), x, np.full(centre, x[-1])])
    summed = np.concatenate([[0.0], np.cumsum(padded)])
    return (summed[width:] - summed[:-width]) / width


def _sample(grid: _Grid, v: np.ndarray, *, phase: float, to_end: bool, filter_s: float) -> tuple[_Raw, float]:
    """Positions every :data:`SAMPLE_PERIOD_S` along the planned stretch from time ``phase``
    after its start (on arcs put out by the filter's shrink, :func:`_shrink_compensation`); the
    phase of the next stretch. ``to_end``: a stretch that ends at rest gets a sample at its end
    (the last one clipped to it)."""
    dt = SAMPLE_PERIOD_S
    t_grid = _time_of(grid.s, v)
    total = float(t_grid[-1])
    if to_end:
        n = max(1, math.ceil((total - phase) / dt - 1e-9) + 1)
    else:
        n = max(0, math.ceil((total - phase) / dt - 1e-9))
    t = phase + np.arange(n) * dt
    s_t, speed, k = _sample_arc_length(np.minimum(t, total), t_grid, grid.s, v)
    width = round(filter_s / SAMPLE_PERIOD_S)
    if width > 1 and n:
        # the speed over the filter's window about each sample (what the filter's shrink depends
        # on): a compensation that follows it has no velocity step where the profile's
        # acceleration steps, which the filter would turn into a jerk
        speed = _window_mean(speed, width)
    seg_t = grid.index[k]
    segments = grid.segments
    offsets = np.concatenate([[0.0], np.cumsum([seg.length for seg in segments])])
    position = np.empty((n, 3))
    out, radial = np.zeros(n), np.zeros((n, 3))
    bounds = np.searchsorted(seg_t, np.arange(len(segments) + 1))  # seg_t never decreases
    # the lines' and the circles' (corner blends among them) samples at once, each spiral's on
    # its own (most of a CAM program's segments are lines and blends)
    lengths = np.array([seg.length for seg in segments])
    frac = np.clip((s_t - offsets[seg_t]) / np.maximum(lengths[seg_t], 1e-300), 0.0, 1.0)
    at_end = s_t - offsets[seg_t] >= lengths[seg_t]
    on_line = np.array([seg.kind != SegmentKind.ARC for seg in segments])[seg_t]
    if on_line.any():
        starts = np.array([seg.start for seg in segments])
        steps = np.array([seg.end - seg.start for seg in segments])
        owner = seg_t[on_line]
        position[on_line] = starts[owner] + frac[on_line, None] * steps[owner]
    circular = np.array([seg.kind == SegmentKind.ARC and seg.radius_end == seg.radius for seg in segments])
    on_circle = circular[seg_t]
    if on_circle.any():
        arcs = [seg if circular[i] else segments[int(np.argmax(circular))] for i, seg in enumerate(segments)]
        owner = seg_t[on_circle]
        angle = (frac[on_circle] * np.array([seg.sweep for seg in arcs])[owner])[:, None]
        radius = np.array([seg.radius for seg in arcs])[owner][:, None]
        rise = (frac[on_circle] * np.array([seg.rise for seg in arcs])[owner])[:, None]
        position[on_circle] = (
            np.array([seg.center for seg in arcs])[owner]
            + radius * (np.cos(angle) * np.array([seg.u for seg in arcs])[owner])
            + radius * (np.sin(angle) * np.array([seg.v for seg in arcs])[owner])
            + rise * np.array([seg.normal for seg in arcs])[owner]
        )
    ends = (on_line | on_circle) & at_end
    position[ends] = np.array([seg.end for seg in segments])[seg_t[ends]]  # the programmed end exactly
    for i in range(len(segments)):
        lo, hi = bounds[i], bounds[i + 1]
        if hi > lo and segments[i].kind == SegmentKind.ARC and (not circular[i] or _compensated(segments[i], filter_s)):
            s_local = np.clip(s_t[lo:hi] - offsets[i], 0.0, segments[i].length)
            if not circular[i]:
                position[lo:hi] = segments[i].points(s_local)
            if _compensated(segments[i], filter_s):
                out[lo:hi], radial[lo:hi] = _shrink_compensation(segments[i], s_local, speed[lo:hi], filter_s)
    if width > 1 and n:
        # the filter averages the compensation too: where it changes, by what its window mean
        # differs from it (one step of Van Cittert's deconvolution)
        out = 2.0 * out - _window_mean(out, width)
    position += out[:, None] * radial
    lines = np.array([seg.line for seg in segments])[seg_t]
    tolerance = np.array([seg.tolerance_m for seg in segments])[seg_t]
    next_phase = 0.0 if to_end else phase + n * dt - total
    return _Raw(position, lines, tolerance), next_phase


class _Smoother:
    """The moving-average filter over the raw sample stream, and the central differences of
    its output (velocity, acceleration), one stretch at a time; what a stretch completes is
    given back, the filter's and the differences' look-back kept."""

    def __init__(self, n_filter: int, start: np.ndarray, line: int, tolerance: float):
        self.n = n_filter
        self.tail = np.repeat(start[None, :], n_filter - 1, axis=0)  # raw samples before the next
        self.tail_line = np.full(n_filter - 1, line)
        self.tail_tolerance = np.full(n_filter - 1, tolerance)
        self.held = np.repeat(start[None, :], 2, axis=0)  # the last two filtered samples
        self.held_line = np.full(2, line)
        self.held_tolerance = np.full(2, tolerance)
        self.previous_acceleration = np.zeros(3)
        self.emitted = 0

    def smooth(self, raw: _Raw):
        """The filtered samples ``raw`` completes: (position, line, tolerance), and the look-back
        after it (to keep with :meth:`accept`)."""
        n = self.n
        x = np.concatenate([self.tail, raw.position]) if n > 1 else raw.position
        lines = np.concatenate([self.tail_line, raw.line]) if n > 1 else raw.line
        tolerance = np.concatenate([self.tail_tolerance, raw.tolerance]) if n > 1 else raw.tolerance
        if n > 1:
            c = np.concatenate([np.zeros((1, 3)), np.cumsum(x, axis=0)])
            out = (c[n:] - c[:-n]) / n
            centre = (n - 1) // 2
            out_line = lines[n - 1 - centre : len(lines) - centre]
            # the tolerance a filtered sample answers to: the largest in its window (it averages
            # the raw samples there; a corner blended under one tolerance reaches into the next move)
            out_tol = np.lib.stride_tricks.sliding_window_view(tolerance, n).max(axis=1)
            tail = (x[-(n - 1) :], lines[-(n - 1) :], tolerance[-(n - 1) :])
        else:
            out, out_line, out_tol = x.copy(), lines, tolerance
            tail = (self.tail, self.tail_line, self.tail_tolerance)
        return (out, out_line, out_tol), tail

    def differences(self, filtered: np.ndarray, last: bool):
        """Velocity and acceleration of the held samples and ``filtered`` (the reference at rest
        after the last sample when ``last``): positions, velocities, accelerations of the samples
        now complete, and the new held samples."""
        p = np.concatenate([self.held, filtered])
        if last:
            p = np.concatenate([p, p[-1:]])
        dt = SAMPLE_PERIOD_S
        velocity = (p[2:] - p[:-2]) / (2 * dt)
        acceleration = (p[2:] - 2 * p[1:-1] + p[:-2]) / (dt * dt)
        return p[1:-1], velocity, acceleration

    def accept(self, tail, filtered) -> None:
        out, out_line, out_tol = filtered
        self.tail, self.tail_line, self.tail_tolerance = tail
        if len(out):
            held = np.concatenate([self.held, out])[-2:]
            self.held_line = np.concatenate([self.held_line, out_line])[-2:]
            self.held_tolerance = np.concatenate([self.held_tolerance, out_tol])[-2:]
            self.held = held


class _Stream:
    """The planner over a stream of moves (:func:`plan_stream`)."""

    def __init__(
        self,
        moves: Iterable[Move],
        limits: Limits,
        settings: PlannerSettings,
        *,
        keep_programmed: bool,
        most_s: float = math.inf,
        limit: str = "",
    ):
        self.limits, self.settings = limits, settings
        self.ctx = _context(limits, settings)
        self.facts = ProgramFacts(limits)
        self.programmed: list[Segment] | None = [] if keep_programmed else None
        self.path = _blended(self._keep(_programmed(moves, settings, self.facts)))
        if most_s < math.inf:
            self.path = _least_time(self.path, self.ctx, most_s, limit)
        self.smoother: _Smoother | None = None
        self.first = 0

    def _keep(self, segments: Iterator[Segment]) -> Iterator[Segment]:
        """The programmed segments, kept for :attr:`Plan.segments` while asked."""
        for seg in segments:
            if self.programmed is not None:
                self.programmed.append(seg)
            yield seg

    def _pieces(self) -> Iterator[Segment]:
        """The path with its long segments cut into pieces of :data:`PIECE_POINTS` grid points."""
        for seg in self.path:
            while seg.kind != SegmentKind.DWELL and _grid_points(seg) > 2 * PIECE_POINTS:
                piece, seg = seg.split(PIECE_POINTS * GRID_M)
                yield piece
            yield seg

    def chunks(self) -> Iterator[PlanChunk]:
        buffer: list[Segment] = []
        junctions: list[float] = []  # the speed through each junction of the buffer's segments
        points = 0
        v_start = phase = least_time = 0.0
        window_points, window_time = float(WINDOW_POINTS), WINDOW_TIME_S  # the window is planned at this size
        for seg in self._pieces():
            if self.smoother is None:
                self.smoother = _Smoother(self.ctx.n_filter, seg.start, seg.line, seg.tolerance_m)
                yield from self._rest(seg.start, seg.line, 2, seg.tolerance_m)
            speed = _junction_speed(buffer[-1], seg, self.ctx) if buffer else 0.0
            if buffer and speed == 0.0:  # a stop: the buffer is planned to rest
                yield from self._stretch(buffer, junctions, v_start=v_start, v_end=0.0, phase=phase, to_end=True)
                buffer, junctions, points, v_start, phase, least_time = [], [], 0, 0.0, 0.0, 0.0
                window_points, window_time = float(WINDOW_POINTS), WINDOW_TIME_S
            if seg.kind == SegmentKind.DWELL:
                yield from self._rest(
                    seg.start, seg.line, max(1, round(seg.dwell_s / SAMPLE_PERIOD_S)), seg.tolerance_m
                )
                continue
            if buffer:
                junctions.append(speed)
            buffer.append(seg)
            points += _grid_points(seg)
            least_time += seg.length / _segment_speed_limit(seg, self.limits, self.ctx.override, self.ctx.filter_s)
            while points >= window_points or least_time >= window_time:
                rest = yield from self._hand_on(
                    buffer, junctions, v_start=v_start, phase=phase, full=points >= MAX_WINDOW_POINTS
                )
                if rest is None:  # no cruise yet: planned again once the window is half as long again
                    window_points, window_time = min(1.5 * points, MAX_WINDOW_POINTS), 1.5 * least_time
                    break
                window_points, window_time = float(WINDOW_POINTS), WINDOW_TIME_S
                buffer, junctions, v_start, phase = rest
                points = sum(_grid_points(s) for s in buffer)
                least_time = sum(
                    s.length / _segment_speed_limit(s, self.limits, self.ctx.override, self.ctx.filter_s)
                    for s in buffer
                )
        if buffer:
            yield from self._stretch(buffer, junctions, v_start=v_start, v_end=0.0, phase=phase, to_end=True)
        if self.smoother is not None:
            yield from self._finish()

    def _rest(self, position: np.ndarray, line: int, count: int, tolerance: float) -> Iterator[PlanChunk]:
        """``count`` raw samples at rest (a dwell, the ends), in pieces of at most a window's time."""
        piece = round(WINDOW_TIME_S / SAMPLE_PERIOD_S)
        for start in range(0, count, piece):
            n = min(piece, count - start)
            raw = _Raw(np.repeat(position[None, :], n, axis=0), np.full(n, line), np.full(n, tolerance))
            yield from self._emit(raw)

    def _stretch(self, segments, junctions, *, v_start, v_end, phase, to_end) -> Generator[PlanChunk, None, float]:
        """Plan, sample, check (and repair) and emit one stretch of the path; return the phase
        of the next one. A stretch that ends at rest is followed by the filter's window of rest."""
        ctx = self.ctx
        grid = _Grid(segments, junctions, v_start=v_start, v_end=v_end, ctx=ctx)
        settle = ctx.n_filter - 1 if to_end else 0  # after a stop, the filter's window of rest
        for attempt in range(MAX_REPAIRS + 1):
            v = grid.speeds(ctx.filter_s, ctx.budget)
            _bounded(grid, v)
            raw, next_phase = _sample(grid, v, phase=phase, to_end=to_end, filter_s=ctx.filter_s)
            if settle:
                raw = _Raw(
                    np.concatenate([raw.position, np.repeat(raw.position[-1:], settle, axis=0)]),
                    np.concatenate([raw.line, np.full(settle, raw.line[-1])]),
                    np.concatenate([raw.tolerance, np.full(settle, raw.tolerance[-1])]),
                )
            over = self._check(raw, record=attempt == MAX_REPAIRS)
            if not over:
                break
            t_grid = _time_of(grid.s, v)
            reach_t = 2.0 * max(ctx.filter_s, SAMPLE_PERIOD_S)
            for raw_index, (v_ratio, a_ratio, j_ratio) in over:
                t = phase + raw_index * SAMPLE_PERIOD_S
                lo = min(int(np.searchsorted(t_grid, t - reach_t)), len(grid.s) - 1)
                hi = min(int(np.searchsorted(t_grid, t + reach_t)), len(grid.s) - 1)
                # velocity scales with the speed; acceleration with it squared and with the
                # profile's acceleration; jerk with the speed cubed and the acceleration's steps
                speed = min(1.0, 0.99 / v_ratio, (0.99 / a_ratio) ** 0.5, (0.99 / j_ratio) ** (1 / 3))
                acceleration = min(1.0, 0.99 / a_ratio, 0.99 / j_ratio)
                grid.lower(float(grid.s[lo]) - GRID_M, float(grid.s[hi]) + GRID_M, speed, acceleration)
                self.facts.time_scale = max(self.facts.time_scale, 1.0 / speed)
        yield from self._emit(raw)
        return next_phase

    def _hand_on(self, buffer, junctions, *, v_start, phase, full: bool) -> Generator[PlanChunk, None, tuple | None]:
        """Plan the window; hand on what is final up to a cruise and return the rest (its
        segments, junctions, start speed and phase), or None to read more of the path first.
        ``full``: the window may grow no more: with no cruise it is planned to rest (a stop the
        program did not ask for, noted)."""
        ctx = self.ctx
        go = _Grid(buffer, junctions, v_start=v_start, v_end=math.inf, ctx=ctx)
        grid = go.ending_at(0.0)
        v_stop = grid.speeds(ctx.filter_s, ctx.budget)
        v_go = go.speeds(ctx.filter_s, ctx.budget)
        differ = np.nonzero(np.abs(v_go - v_stop) > 1e-9 * np.maximum(v_go, 1e-9))[0]
        final = int(differ[0]) if differ.size else len(v_stop)
        final = min(final, int(np.searchsorted(_time_of(grid.s, v_stop), WINDOW_TIME_S)) + 1)
        cut = self._cruise(grid, v_stop, final)
        if cut is None:
            if not full:
                return None
            self.facts.notes.append(
                f"line {buffer[-1].line}: the look-ahead window is full ({MAX_WINDOW_POINTS:,} grid points) with "
                "no cruise to hand on at: the motion stops there"
            )
            yield from self._stretch(buffer, junctions, v_start=v_start, v_end=0.0, phase=phase, to_end=True)
            return [], [], 0.0, 0.0
        index = int(grid.index[cut])
        first, second = buffer[index].split(float(grid.s[cut] - grid.s[grid.index == index][0]))
        speed = float(v_stop[cut])
        next_phase = yield from self._stretch(
            [*buffer[:index], first], junctions[:index], v_start=v_start, v_end=speed, phase=phase, to_end=False
        )
        return [second, *buffer[index + 1 :]], junctions[index:], speed, next_phase

    def _cruise(self, grid: _Grid, v: np.ndarray, final: int) -> int | None:
        """The last grid point inside a segment, before ``final`` by more than any later change
        of the path can reach back, where the speed is constant over the filter's length on
        either side; None if there is none."""
        ctx = self.ctx
        window = max(ctx.filter_s, SAMPLE_PERIOD_S)
        top = float(v[:final].max()) if final else 0.0
        reach_back = top * top / (2 * min(ctx.limits.acceleration_m_per_s2)) + 2 * top * window
        flat = np.abs(np.diff(v)) <= 1e-9 * np.maximum(v[1:], 1e-9)
        end = np.searchsorted(grid.s, grid.s[final - 1] - reach_back) if final else 0
        for k in range(min(end, len(v) - 2), 0, -25):
            if v[k] <= 0 or grid.index[k - 1] != grid.index[k] or grid.index[k + 1] != grid.index[k]:
                continue
            hold = 2 * float(v[k]) * window + 2 * GRID_M  # twice the filter's reach at this speed
            lo = np.searchsorted(grid.s, grid.s[k] - hold)
            hi = np.searchsorted(grid.s, grid.s[k] + hold)
            if lo > 0 and hi < len(v) - 1 and flat[lo:hi].all():
                return int(k)
        return None

    def _check(self, raw: _Raw, record: bool) -> list[tuple[int, tuple[float, ...]]]:
        """The places over a limit once ``raw`` is filtered: (raw sample index, the velocity,
        acceleration and jerk ratios to their limits there) each; with
        ``record``, what is over is recorded as violations instead (and nothing returned)."""
        assert self.smoother is not None
        filtered, _tail = self.smoother.smooth(raw)
        _positions, velocity, acceleration = self.smoother.differences(filtered[0], last=False)
        if len(velocity) == 0:
            return []
        ratios = limit_ratios(velocity, acceleration, self.smoother.previous_acceleration, self.limits)
        over = np.nonzero(np.maximum.reduce([r.max(axis=1) for r in ratios]) > LIMIT_SLACK)[0]
        if over.size == 0:
            return []
        if record:
            lines = np.concatenate([self.smoother.held_line[1:], filtered[1]])[: len(velocity)]
            for quantity, r in zip(("velocity", "acceleration", "jerk"), ratios):
                for axis in range(3):
                    bad = np.nonzero(r[:, axis] > LIMIT_SLACK)[0]
                    if bad.size:
                        at = bad[np.argmax(r[bad, axis])]
                        self.facts.violations.append(
                            Violation(int(lines[at]), "xyz"[axis], quantity, float(r[at, axis]))
                        )
            return []
        centre = (self.ctx.n_filter - 1) // 2
        return [
            (max(int(sample) - 1 - centre, 0), tuple(max(float(r[sample].max()), 1.0) for r in ratios))
            for sample in over
        ]

    def _emit(self, raw: _Raw) -> Iterator[PlanChunk]:
        """Filter ``raw`` and hand on the samples it completes."""
        assert self.smoother is not None
        filtered, tail = self.smoother.smooth(raw)
        positions, velocity, acceleration = self.smoother.differences(filtered[0], last=False)
        lines = np.concatenate([self.smoother.held_line[1:], filtered[1]])[: len(velocity)]
        tolerance = np.concatenate([self.smoother.held_tolerance[1:], filtered[2]])[: len(velocity)]
        if len(velocity):
            self.smoother.previous_acceleration = acceleration[-1]
        self.smoother.accept(tail, filtered)
        if len(velocity):
            yield PlanChunk(self.first, positions, velocity, acceleration, lines, tolerance)
            self.first += len(velocity)

    def _finish(self) -> Iterator[PlanChunk]:
        """Two samples at rest after the last, and the last held sample's differences."""
        assert self.smoother is not None
        yield from self._rest(
            self.smoother.held[-1], int(self.smoother.held_line[-1]), 2, float(self.smoother.held_tolerance[-1])
        )
        positions, velocity, acceleration = self.smoother.differences(np.zeros((0, 3)), last=True)
        yield PlanChunk(
            self.first, positions, velocity, acceleration, self.smoother.held_line[1:], self.smoother.held_tolerance[1:]
        )
        self.first += len(velocity)


def _grid_points(seg: Segment) -> int:
    return max(MIN_SEGMENT_POINTS, math.ceil(seg.length / GRID_M) + 1)


def _stream(moves, limits: Limits, settings: PlannerSettings, *, keep_programmed: bool, most_s=math.inf, limit=""):
    """The planner of ``settings.mode`` over a stream of moves."""
    if settings.mode == "linuxcnc":
        return LinuxcncStream(moves, limits, settings, keep_programmed)
    return _Stream(moves, limits, settings, keep_programmed=keep_programmed, most_s=most_s, limit=limit)


def plan_stream(moves: Iterable[Move], limits: Limits, settings: PlannerSettings | None = None):
    """The planned reference of a program as it is read, in :class:`PlanChunk` s, and the facts
    gathered on the way (complete once the chunks are exhausted): memory stays bounded for any
    program length.

    Returns
    -------
    chunks : iterator of PlanChunk
    facts : ProgramFacts
    """
    stream = _stream(moves, limits, settings or PlannerSettings(), keep_programmed=False)
    return stream.chunks(), stream.facts


def plan(moves: Iterable[Move], limits: Limits, settings: PlannerSettings | None = None) -> Plan:
    """Plan a program's moves into a reference sampled every :data:`SAMPLE_PERIOD_S`, held whole.

    Raises
    ------
    PlanningError
        A program with no motion, or one too long to hold (:data:`MAX_SAMPLES`).
    """
    held, _facts, _samples = hold_or_count(
        moves, limits, settings, most=MAX_SAMPLES, count_to=MAX_SAMPLES, limit=HELD_LIMIT
    )
    if held is None:
        raise PlanningError(f"the program runs longer than {HELD_LIMIT}")
    return held


#: What :func:`plan` refuses a longer program for.
HELD_LIMIT = (
    f"the {MAX_SAMPLES * SAMPLE_PERIOD_S:.0f} s of motion a reference held whole may hold (split it, or run it "
    "in a scenario without a stock, whose reference streams it)"
)
#: What a run refuses a program longer than :data:`MAX_PROGRAM_SAMPLES` for.
PROGRAM_LIMIT = f"the {MAX_PROGRAM_SAMPLES * SAMPLE_PERIOD_S / 3600:.0f} hours of motion a run may plan"


def hold_or_count(
    moves: Iterable[Move],
    limits: Limits,
    settings: PlannerSettings | None,
    *,
    most: int,
    count_to: int = MAX_PROGRAM_SAMPLES,
    limit: str | None = None,
) -> tuple[Plan | None, ProgramFacts, int]:
    """Plan a program: held whole (a :class:`Plan`) if it has at most ``most`` samples, else
    only counted (memory stays bounded; a second pass, :func:`plan_stream`, gives the samples),
    up to ``count_to`` samples (a longer program counts as ``count_to + 1``). With ``limit``
    (what ``count_to`` is, in words), a program whose moves alone take longer than
    ``count_to`` samples is refused before it is planned (:func:`refuse_long`: at once for a
    list of moves, else as each move is read).

    Returns
    -------
    plan : Plan or None
    facts : ProgramFacts
    samples : int
        The reference's length.

    Raises
    ------
    PlanningError
        A program with no motion, or (with ``limit``) one whose moves alone take longer.
    """
    settings = settings or PlannerSettings()
    most_s = math.inf if limit is None else count_to * SAMPLE_PERIOD_S
    if limit is not None and isinstance(moves, Sequence):
        refuse_long(moves, limits, settings, most_s=most_s, limit=limit)
    stream = _stream(moves, limits, settings, keep_programmed=True, most_s=most_s, limit=limit or "")
    parts: list[PlanChunk] | None = []
    total = 0
    for chunk in stream.chunks():
        total += len(chunk.position)
        if total > count_to:
            return None, stream.facts, count_to + 1
        if parts is not None:
            if total > most:
                parts, stream.programmed = None, None  # too long: counted from here on
            else:
                parts.append(chunk)
    facts = stream.facts
    if not facts.texts or total == 0:
        raise PlanningError("the program has no motion")
    if parts is None:
        return None, facts, total
    assert stream.programmed is not None
    if not stream.programmed:
        raise PlanningError("the program has no motion")
    held = Plan(
        SAMPLE_PERIOD_S,
        np.concatenate([c.position for c in parts]),
        np.concatenate([c.velocity for c in parts]),
        np.concatenate([c.acceleration for c in parts]),
        np.concatenate([c.line for c in parts]),
        np.concatenate([c.tolerance_m for c in parts]),
        facts.feed_only_time_s,
        facts.time_scale,
        stream.ctx.filter_s,
        max(seg.tolerance_m for seg in stream.programmed),
        stream.programmed,
        facts.texts,
        facts.spindle_rpm,
        facts.tools,
        facts.feeds,
        facts.violations,
        facts.notes,
    )
    return held, facts, total
