# SPDX-License-Identifier: GPL-2.0-only
# A translation of LinuxCNC's trajectory planner (GPL Version 2): this file is under the GPL-2.0
# (twin/gcode/COPYING.linuxcnc), not the MIT licence of the rest of the twin.
"""The LinuxCNC planning mode (``[planner] mode = "linuxcnc"``): a program's moves planned as
LinuxCNC 2.9 plans them, sampled every servo period (LinuxCNC's 1 ms, the jerk-limited planner's
sample period :data:`twin.gcode.planned.SAMPLE_PERIOD_S`).

The chain, as in LinuxCNC:

1. The canonical layer (``emccanon.cc``): each move's requested speed, its largest speed and
   acceleration from the axis limits (``getStraightVelocity``, ``getStraightAcceleration``; an
   arc's from its plane's axes with ``sqrt(3)/2`` of their acceleration across it), G64 P's
   "naive CAM" tolerance merging nearly collinear feeds (and arcs in G17 whose chord deviates
   less) into one line.
2. The task (``milltask``): one motion command reaches the motion module per servo period; a
   dwell, a spindle or coolant change and a tool change wait for the motion to end (a queue
   sync), then the motion restarts a few servo periods later (:data:`SYNC_CYCLES`, measured on
   the real planner).
3. The trajectory planner (:mod:`twin.gcode.linuxcnc_tp`), one cycle per servo period.
4. The motion module's cubic interpolator (``cubic.c``), which LinuxCNC runs on every joint
   even at one trajectory point per servo period: the commanded position is
   ``(x[k-2] + 4 x[k-1] + x[k]) / 6`` of the planner's positions.

LinuxCNC has no jerk limit: the sampled reference's jerk is whatever this gives (the twin's
report shows it against the machine's jerk limits, and it is above them).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Iterable, Iterator
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from twin.gcode.linuxcnc_geometry import Vec
from twin.gcode.linuxcnc_tc import EXACT, PARABOLIC, STOP
from twin.gcode.linuxcnc_tp import Config, Planner
from twin.gcode.moves import PLANES, Move
from twin.gcode.path import move_segment
from twin.gcode.planned import (
    LIMIT_SLACK,
    SAMPLE_PERIOD_S,
    PlanChunk,
    PlanningError,
    ProgramFacts,
    Violation,
    limit_ratios,
)

#: Servo periods between the end of the motion before a queue sync and the first motion after
#: it, by what the task waited for (LinuxCNC 2.9's milltask, measured on the real planner; a
#: dwell adds its own time; "no time": a dwell of 0 s, ``G4 P0``).
SYNC_CYCLES = {"dwell": 2, "no time": 1, "spindle": 3, "other": 2}
#: Segments in the motion queue at which the task waits before it sends more (``tcqFull``: the
#: queue of 2000 less its margin of 220).
QUEUE_FULL = 2000 - 220
#: The smallest displacement of an axis LinuxCNC counts (``CART_FUZZ``, mm).
TINY_MM = 1e-8


@dataclass(frozen=True)
class AxisLimits:
    """Per-axis limits of the LinuxCNC mode, LinuxCNC's units: velocity (mm/s) and
    acceleration (mm/s^2), x y z."""

    velocity: tuple[float, float, float]
    acceleration: tuple[float, float, float]


@dataclass
class _Motion:
    """A motion command for the planner: a line or a circle with its speeds."""

    kind: str  # "line", "circle"
    line_number: int
    end: tuple[float, float, float]
    vel: float
    ini_maxvel: float
    acc: float
    traverse: bool = False
    center: tuple[float, float, float] = (0.0, 0.0, 0.0)
    normal: tuple[float, float, float] = (0.0, 0.0, 1.0)
    turn: int = 0


@dataclass
class _TermCond:
    cond: int
    tolerance: float


@dataclass
class _Sync:
    """Wait for the motion to end, then ``cycles`` servo periods (a dwell's time included)."""

    cycles: int
    line_number: int


class _Canon:
    """The canonical layer between the reader's moves and the motion commands."""

    def __init__(self, limits: AxisLimits, period_s: float):
        self.limits = limits
        self.period_s = period_s
        self.end: tuple[float, float, float] | None = None
        self.mode: tuple[str, float | None] | None = None
        self.naivecam = 0.0
        self.chain: list[tuple[float, float, float, int]] = []
        self.feed = 0.0
        self.state: tuple | None = None
        self.start: tuple[float, float, float] = (0.0, 0.0, 0.0)

    # --- speeds -------------------------------------------------------------------------

    def _deltas(self, end) -> list[float]:
        assert self.end is not None
        d = [abs(end[i] - self.end[i]) for i in range(3)]
        return [x if x >= TINY_MM else 0.0 for x in d]

    def straight_velocity(self, end) -> tuple[float, float]:
        """``getStraightVelocity``: (velocity mm/s, time at the axis limits s)."""
        d = self._deltas(end)
        if not any(d):
            return self.feed, 0.0
        tmax = max(d[i] / self.limits.velocity[i] if d[i] else 0.0 for i in range(3))
        return math.sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]) / tmax, tmax

    def straight_acceleration(self, end) -> tuple[float, float]:
        """``getStraightAcceleration``: (acceleration mm/s^2, its time measure)."""
        d = self._deltas(end)
        if not any(d):
            return 0.0, 0.0
        tmax = max(d[i] / self.limits.acceleration[i] if d[i] else 0.0 for i in range(3))
        return math.sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]) / tmax, tmax

    # --- moves ------------------------------------------------------------------------------

    def commands(self, move: Move) -> Iterator[object]:
        """The commands of one move (after what it changes)."""
        end = _machine(move.end_mm, move.offset_mm)
        if self.end is None:
            self.end = self.start = _machine(move.start_mm, move.offset_mm)
        state = (move.spindle, move.spindle_rpm, move.coolant, move.tool)
        if self.state is not None and state != self.state:
            yield from self.flush()
            kind = "spindle" if self.state[0] == "off" and move.spindle != "off" else "other"
            yield _Sync(SYNC_CYCLES[kind], move.line)
        self.state = state
        mode = (move.path_mode, move.tolerance_mm)
        if mode != self.mode:
            yield from self.flush()
            self.mode = mode
            if move.path_mode == "G64":
                self.naivecam = move.tolerance_mm or 0.0
                yield _TermCond(PARABOLIC, move.tolerance_mm or 0.0)
            else:
                self.naivecam = 0.0
                yield _TermCond(EXACT if move.path_mode == "G61" else STOP, 0.0)
        if move.kind == "dwell":
            yield from self.flush()
            extra = SYNC_CYCLES["dwell"] if move.dwell_s > 0 else SYNC_CYCLES["no time"]
            yield _Sync(extra + round(move.dwell_s / self.period_s), move.line)
            return
        if move.kind == "rapid":
            yield from self.flush()
            vel, _t = self.straight_velocity(end)
            acc, _t = self.straight_acceleration(end)
            if vel and acc:
                yield _Motion("line", move.line, end, vel, vel, acc, traverse=True)
            self.end = end
            return
        feed = move.feed_mm_per_min / 60.0
        if feed != self.feed:  # SET_FEED_RATE: a new feed ends the chain
            yield from self.flush()
            self.feed = feed
        if move.kind == "feed":
            yield from self._see(end, move.line)
            return
        yield from self._arc(move, end)

    def _see(self, point, line_number: int) -> Iterator[object]:
        """``see_segment``: a feed joins the chain of nearly collinear ones, or flushes it."""
        if self.chain and not self._linkable(point):
            yield from self.flush()
        self.chain.append((*point, line_number))

    def _linkable(self, point) -> bool:
        """``linkable``: every chained point within the naive-CAM tolerance of the new line."""
        if self.naivecam == 0 or len(self.chain) > 100:
            return False
        assert self.end is not None
        b = self.end
        if point == b:
            return False
        m = (point[0] - b[0], point[1] - b[1], point[2] - b[2])
        mm = m[0] * m[0] + m[1] * m[1] + m[2] * m[2]
        for px, py, pz, _line in self.chain:
            t0 = (m[0] * (px - b[0]) + m[1] * (py - b[1]) + m[2] * (pz - b[2])) / mm
            t0 = min(max(t0, 0.0), 1.0)
            q = (px - (b[0] + t0 * m[0]), py - (b[1] + t0 * m[1]), pz - (b[2] + t0 * m[2]))
            if math.sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2]) > self.naivecam:
                return False
        return True

    def flush(self) -> Iterator[object]:
        """``flush_segments``: the chain as one line to its last point."""
        if not self.chain:
            return
        x, y, z, line_number = self.chain[-1]
        self.chain = []
        end = (x, y, z)
        vel_max, _t = self.straight_velocity(end)
        vel = min(vel_max, self.feed)
        acc, _t = self.straight_acceleration(end)
        if vel and acc:
            yield _Motion("line", line_number, end, vel, vel_max, acc)
        self.end = end

    def _arc(self, move: Move, end) -> Iterator[object]:
        """``ARC_FEED``: a circle with its speed and acceleration (small arcs in G17 under G64 P
        as two feeds through the arc's middle, within the naive-CAM tolerance)."""
        assert self.end is not None
        first, second, normal_axis = PLANES[move.plane]
        center = [0.0, 0.0, 0.0]
        center[first] = move.center_mm[0] + move.offset_mm[first]
        center[second] = move.center_mm[1] + move.offset_mm[second]
        center[normal_axis] = end[normal_axis]
        if move.plane == "xy" and self.naivecam > 0:
            start = self.chain[-1][:3] if self.chain else self.end
            dev, mid = _chord_deviation(start, end, center, move.turns)
            if dev < self.naivecam:
                yield from self._see((mid[0], mid[1], (start[2] + end[2]) / 2), move.line)
                yield from self._see(end, move.line)
                return
        yield from self.flush()
        normal = [0.0, 0.0, 0.0]
        normal[normal_axis] = 1.0
        s = [self.end[i] - center[i] for i in range(3)]
        e = [end[i] - center[i] for i in range(3)]
        theta_start = math.atan2(s[second], s[first])
        theta_end = math.atan2(e[second], e[first])
        start_radius = math.hypot(s[first], s[second])
        end_radius = math.hypot(e[first], e[second])
        if move.turns < 0:
            if theta_end + 1e-12 >= theta_start:
                theta_end -= 2.0 * math.pi
        elif theta_end - 1e-12 <= theta_start:
            theta_end += 2.0 * math.pi
        rotation = move.turns
        full_turns = rotation - 1 if rotation > 1 else (rotation + 1 if rotation < -1 else 0)
        full_angle = theta_end - theta_start + 2.0 * math.pi * full_turns
        spiral = end_radius - start_radius
        dr = spiral / abs(full_angle)
        min_radius = min(start_radius, end_radius)
        effective_radius = math.sqrt(dr * dr + min_radius * min_radius)
        axis1, axis2 = (normal_axis + 1) % 3, (normal_axis + 2) % 3
        v_max_axes = min(self.limits.velocity[axis1], self.limits.velocity[axis2])
        a_max_axes = min(self.limits.acceleration[axis1], self.limits.acceleration[axis2])
        a_max_normal = a_max_axes * math.sqrt(3.0) / 2.0
        v_max_planar = min(math.sqrt(a_max_normal * effective_radius), v_max_axes)
        _vel, t_max_motion = self.straight_velocity(end)
        circular_length = min_radius * abs(full_angle)
        spiral_length = math.hypot(circular_length, spiral)
        axis_len = end[normal_axis] - self.end[normal_axis]
        total_xyz_length = math.hypot(spiral_length, axis_len)
        t_max = max(t_max_motion, spiral_length / v_max_planar)
        v_max = total_xyz_length / t_max
        _acc, tt_max_motion = self.straight_acceleration(end)
        tt_max = max(tt_max_motion, spiral_length / a_max_axes)
        a_max = total_xyz_length / tt_max
        vel = min(self.feed, v_max)
        turn = rotation - 1 if rotation > 0 else rotation
        if vel and a_max:
            yield _Motion("circle", move.line, end, vel, v_max, a_max, False, _vec(center), _vec(normal), turn)
        self.end = end


def _vec(values) -> Vec:
    return (float(values[0]), float(values[1]), float(values[2]))


def _machine(work_mm, offset_mm) -> Vec:
    """A point in machine coordinates (mm) from work coordinates and the offsets."""
    return _vec([w + o for w, o in zip(work_mm, offset_mm)])


def _chord_deviation(start, end, center, rotation: int):
    """``chord_deviation``: how far an arc in G17 leaves its chord (mm), and its middle."""
    sx, sy, ex, ey, cx, cy = start[0], start[1], end[0], end[1], center[0], center[1]
    th1 = math.atan2(sy - cy, sx - cx)
    th2 = math.atan2(ey - cy, ex - cx)
    r = math.hypot(sy - cy, sx - cx)
    dth = th2 - th1
    if rotation < 0:
        if dth >= -1e-5:
            th2 -= 2 * math.pi
        dth = th2 - th1
        if dth >= -1e-5:
            th2 -= 2 * math.pi
    else:
        if dth <= 1e-5:
            th2 += 2 * math.pi
        dth = th2 - th1
        if dth <= 1e-5:
            th2 += 2 * math.pi
    included = abs(th2 - th1)
    mid = (th2 + th1) / 2
    return r * (1 - math.cos(included / 2)), (cx + r * math.cos(mid), cy + r * math.sin(mid))


def commands(moves: Iterable[Move], limits: AxisLimits, period_s: float) -> Iterator[object]:
    """The motion commands of a program, as LinuxCNC's canonical layer sends them."""
    canon = _Canon(limits, period_s)
    for move in moves:
        yield from canon.commands(move)
    yield from canon.flush()


@dataclass
class _Start:
    """Where the program's first move starts (mm)."""

    position: tuple[float, float, float]


def sampled(moves: Iterable[Move], limits: AxisLimits, period_s: float = 1e-3, block: int = 4096):
    """The commanded positions every servo period, in blocks: (positions (n, 3) mm, program
    line of each), from the last sample at rest before the motion to the last that moves
    (as ``run_tp.sh`` cuts LinuxCNC's)."""
    config = Config(limits.acceleration, limits.velocity, cycle_time=period_s)
    canon = _Canon(limits, period_s)

    def stream() -> Iterator[object]:
        for move in moves:
            yield from canon.commands(move)
        yield from canon.flush()

    source = stream()
    head: list[object] = []
    for item in source:
        head.append(item)
        if isinstance(item, _Motion):
            break
    if canon.end is None or not head:
        return
    first_line = next(item.line_number for item in head if isinstance(item, _Motion))
    yield from _run(config, start=canon.start, line=first_line, items=itertools.chain(head, source), block=block)


def _run(config: Config, *, start, line: int, items: Iterable[object], block: int):
    """The task, the planner and the interpolator, one servo period at a time (``line``: the
    program line of the samples before the first segment)."""
    planner = Planner(config, start)
    source = iter(items)
    pending = next(source, None)
    wait = -1  # servo periods left of a sync once the motion has ended (-1: none)
    raw: list[tuple[float, float, float]] = []
    lines: list[int] = []
    x0 = x1 = start  # the planner's last two positions (the cubic interpolator's look-back)
    while pending is not None or not planner.idle() or wait >= 0:
        if wait >= 0:
            if planner.idle():
                if wait == 0:
                    wait = -1
                    pending = next(source, None)
                else:
                    wait -= 1
        elif pending is not None and len(planner.queue) < QUEUE_FULL:
            if isinstance(pending, _Motion):
                if pending.kind == "line":
                    planner.add_line(
                        pending.end,
                        traverse=pending.traverse,
                        line_number=pending.line_number,
                        vel=pending.vel,
                        ini_maxvel=pending.ini_maxvel,
                        acc=pending.acc,
                    )
                else:
                    planner.add_circle(
                        pending.end,
                        pending.center,
                        normal=pending.normal,
                        turn=pending.turn,
                        line_number=pending.line_number,
                        vel=pending.vel,
                        ini_maxvel=pending.ini_maxvel,
                        acc=pending.acc,
                    )
                line = pending.line_number
                pending = next(source, None)
            elif isinstance(pending, _TermCond):
                planner.set_term_cond(pending.cond, pending.tolerance)
                pending = next(source, None)
            elif isinstance(pending, _Sync):
                wait = pending.cycles
                line = pending.line_number
        planner.run_cycle()
        x = planner.current_pos
        raw.append(_way_point(x0, x1, x))
        x0, x1 = x1, x
        lines.append(planner.queue[0].line_number if planner.queue else line)
        if len(raw) >= block:
            yield np.array(raw), np.array(lines)
            raw, lines = [], []
    for _ in range(2):  # the interpolator settles on the last position
        raw.append(_way_point(x0, x1, x1))
        x0 = x1
        lines.append(line)
    if raw:
        yield np.array(raw), np.array(lines)


def _way_point(a, b, c) -> tuple[float, float, float]:
    """``cubic.c`` ``wayPoint``: ``(a + 4 b + c) / 6`` per axis."""
    return ((a[0] + 4.0 * b[0] + c[0]) / 6.0, (a[1] + 4.0 * b[1] + c[1]) / 6.0, (a[2] + 4.0 * b[2] + c[2]) / 6.0)


def motion_samples(moves: Iterable[Move], limits: AxisLimits, period_s: float = 1e-3) -> np.ndarray:
    """The commanded positions (n, 3) mm as ``run_tp.sh`` cuts LinuxCNC's: from the last
    sample at rest before the motion to the last that moves (at LinuxCNC's sampler's 1 nm)."""
    blocks = [p for p, _l in sampled(moves, limits, period_s)]
    if not blocks:
        return np.zeros((0, 3))
    p = np.concatenate(blocks)
    printed = np.round(p, 6)
    moving = np.nonzero(np.any(printed[1:] != printed[:-1], axis=1))[0] + 1
    if moving.size == 0:
        return p[:1]
    return p[moving[0] - 1 : moving[-1] + 1]


class _NoFilter(NamedTuple):
    """What :func:`twin.gcode.planner.hold_or_count` reads of a planner's context: no smoothing
    filter (s)."""

    filter_s: float


class LinuxcncStream:
    """The LinuxCNC mode behind :func:`twin.gcode.planner.plan_stream` and
    :func:`~twin.gcode.planner.hold_or_count`: the same :class:`~twin.gcode.planned.PlanChunk` s
    (machine m, m/s, m/s^2 by central differences, as the jerk-limited planner gives them) and
    :class:`~twin.gcode.planned.ProgramFacts`, with each axis's velocity, acceleration and jerk
    over the machine's limits recorded as violations (LinuxCNC has no jerk limit: its jerk is
    reported, not lowered).
    """

    def __init__(self, moves, limits, settings, keep_programmed: bool):
        if settings.feed_override != 1.0:
            raise PlanningError(
                f"planner.feed_override = {settings.feed_override}: the LinuxCNC mode runs at 100 % (the override's "
                "effect on LinuxCNC's blends is not modelled)"
            )
        self.limits, self.settings = limits, settings
        self.facts = ProgramFacts(limits)
        self.programmed: list | None = [] if keep_programmed else None
        self.moves = moves
        self.ctx = _NoFilter(0.0)
        self.tolerance: dict[int, float] = {}

    def _recorded(self, moves) -> Iterator[Move]:
        """The moves, their facts and programmed segments recorded as they pass; G64 P replaced by
        ``[planner] tolerance_mm`` where it is set."""
        position = None
        for move in moves:
            if position is None:
                position = (np.asarray(move.start_mm) + np.asarray(move.offset_mm)) * 1e-3
            tolerance_m = self.settings.tolerance_m(move)
            seg = move_segment(move, position, tolerance_m)
            self.facts.record(move, seg)
            self.tolerance[move.line] = tolerance_m if move.path_mode == "G64" else 0.0
            if seg is not None:
                position = seg.end
                if self.programmed is not None:
                    self.programmed.append(seg)
            if self.settings.tolerance_mm is not None and move.path_mode == "G64":
                move = move._replace(tolerance_mm=self.settings.tolerance_mm)
            yield move

    def chunks(self):
        """The reference in :class:`~twin.gcode.planned.PlanChunk` s, at rest one sample before and
        two after the motion."""
        limits = AxisLimits(
            tuple(v * 1e3 for v in self.limits.velocity_m_per_s),
            tuple(a * 1e3 for a in self.limits.acceleration_m_per_s2),
        )
        dt = SAMPLE_PERIOD_S
        first = 0
        held: np.ndarray | None = None  # the last two positions (m), for the differences
        held_line = np.zeros(2, dtype=int)
        previous_acceleration = np.zeros(3)
        worst: dict[tuple[str, str], tuple[float, int]] = {}
        blocks = sampled(self._recorded(self.moves), limits, dt)
        ending = False
        while True:
            block = next(blocks, None)
            if block is None:
                if held is None or ending:
                    break
                ending = True
                position, line = np.repeat(held[-1:], 2, axis=0), np.repeat(held_line[-1:], 2)
            else:
                position, line = block[0] * 1e-3, block[1]
            if held is None:
                held, held_line = np.repeat(position[:1], 2, axis=0), np.repeat(line[:1], 2)
            p = np.concatenate([held, position])
            lines = np.concatenate([held_line, line])
            velocity = (p[2:] - p[:-2]) / (2 * dt)
            acceleration = (p[2:] - 2 * p[1:-1] + p[:-2]) / (dt * dt)
            sample_lines = lines[1:-1]
            ratios = limit_ratios(velocity, acceleration, previous_acceleration, self.limits)
            for quantity, r in zip(("velocity", "acceleration", "jerk"), ratios):
                for axis in range(3):
                    k = int(np.argmax(r[:, axis]))
                    key = ("xyz"[axis], quantity)
                    if r[k, axis] > worst.get(key, (LIMIT_SLACK, 0))[0]:
                        worst[key] = (float(r[k, axis]), int(sample_lines[k]))
            previous_acceleration = acceleration[-1]
            tolerance = np.array([self.tolerance.get(int(n), 0.0) for n in sample_lines])
            yield PlanChunk(first, p[1:-1], velocity, acceleration, sample_lines, tolerance)
            first += len(velocity)
            held, held_line = p[-2:], lines[-2:]
        for (axis, quantity), (ratio, line_number) in sorted(worst.items()):
            self.facts.violations.append(Violation(line_number, axis, quantity, ratio))
