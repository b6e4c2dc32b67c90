"""The programmed path as geometry in machine coordinates (m): lines and arcs (helical where the
normal axis moves, spiral where the end radius differs from the start radius, as LinuxCNC moves
an arc whose end its arc rule lets lie off the circle), with corner blends between lines, each a
function of its arc length; and the exact distance of points to them.

Corners between two feed lines (or two rapids) under G64 get a tangent blend arc whose distance
to the corner is at most the blend tolerance (LinuxCNC's G64 P rule; we put the arc in the plane
of the two lines); what the other junctions do is the planner's (:mod:`twin.gcode.planner`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from enum import StrEnum
from typing import NamedTuple

import numpy as np

from twin.gcode.moves import PLANES, Move, MoveKind

#: Moves shorter than this (m) are dropped: rs274 emits null moves (a bare G0, G28 where the tool is).
MIN_LENGTH_M = 1e-9
#: Two unit tangents closer than this (rad) meet without a corner.
TANGENT_TOLERANCE_RAD = 1e-6
#: Newton steps that put a spiral's angle at an arc length (each squares the error).
SPIRAL_NEWTON_STEPS = 4


class SegmentKind(StrEnum):
    """The geometry of a :class:`Segment`."""

    #: A straight line (a G0 or G1 move).
    LINE = "line"
    #: An arc, helix or spiral (a G2 / G3 move, or a blend the planner put in a corner).
    ARC = "arc"
    #: A dwell: no motion.
    DWELL = "dwell"


class Outward(NamedTuple):
    """Where an arc's points lie about its axis.

    Attributes
    ----------
    direction : ndarray (n, 3)
        The in-plane unit vector from the axis out to each point.
    radius : ndarray (n,)
        The radius there (m).
    turn_per_m : ndarray (n,)
        The angle turned per metre of path there (rad/m).
    """

    direction: np.ndarray
    radius: np.ndarray
    turn_per_m: np.ndarray


@dataclass
class Segment:
    """One piece of the path.

    Attributes
    ----------
    line : int
        The program line it comes from (a blend: the line of the move it leads into).
    kind : SegmentKind
        Geometry.
    rapid : bool
        A G0 move (runs at the axis limits, not at a feed).
    feed_m_per_s : float
        Programmed feed (0 for rapids and dwells).
    start, end : ndarray (3,)
        End points (m).
    length : float
        Arc length (m).
    center, u, v : ndarray (3,)
        Arcs: centre, and the in-plane unit vectors from the centre to the start and a quarter
        turn further in the direction of motion.
    radius, sweep, rise : float
        Arcs: start radius (m), swept angle (rad, > 0), travel along the normal (m).
    normal : ndarray (3,)
        Arcs: unit normal (u x v) signed with the rise.
    radius_end : float
        Arcs: the end radius (m); it differs from ``radius`` on a spiral.
    dwell_s : float
        Dwells: the time.
    blend : bool
        An arc the planner put in a corner (not programmed).
    mode : {"G64", "G61", "G61.1"}
        The path control of the move (it governs the junction at the segment's end).
    tolerance_m : float
        How far the path may leave the programmed one here (m): G64's tolerance, which a blend
        at the segment's end takes half of; under G61 and G61.1 (no blend) what the smoothing
        filter's rounding of arcs may take.
    """

    line: int
    kind: SegmentKind
    rapid: bool
    feed_m_per_s: float
    start: np.ndarray
    end: np.ndarray
    length: float = 0.0
    center: np.ndarray | None = None
    u: np.ndarray | None = None
    v: np.ndarray | None = None
    normal: np.ndarray | None = None
    radius: float = 0.0
    sweep: float = 0.0
    rise: float = 0.0
    radius_end: float = 0.0
    dwell_s: float = 0.0
    blend: bool = False
    mode: str = "G64"
    tolerance_m: float = 0.0
    #: What the planner works out of the segment once (its speed limit, tangents, axis shares),
    #: by name; a copy (:meth:`copy_with`, :meth:`split`, :func:`dataclasses.replace`) starts with none.
    planned: dict = field(default_factory=dict, init=False, repr=False, compare=False)

    def copy_with(self, **changes) -> Segment:
        """A copy with ``changes`` (fields by name), none of :attr:`planned` (what
        :func:`dataclasses.replace` gives, at a tenth of its cost: a blend at every corner)."""
        other = object.__new__(Segment)
        other.__dict__.update(self.__dict__)
        other.__dict__.update(changes)
        other.planned = {}
        return other

    @property
    def curvature(self) -> float:
        """The largest curvature (1/m) of the path along the segment: 0 on lines."""
        if self.kind != SegmentKind.ARC:
            return 0.0
        r = min(self.radius, self.radius_end)
        return r / (r * r + (self.rise / self.sweep) ** 2)

    def _angle_of(self, s: np.ndarray) -> np.ndarray:
        """The angle (rad) at arc lengths ``s``: linear on circles and helices, by Newton's
        method on spirals (whose arc length has the closed form of :func:`_spiral_length`)."""
        frac = s / self.length
        angle = frac * self.sweep
        if self.radius_end == self.radius:
            return angle
        k = (self.radius_end - self.radius) / self.sweep
        h = self.rise / self.sweep
        for _ in range(SPIRAL_NEWTON_STEPS):
            r = self.radius + k * angle
            length = _spiral_length(self.radius, k, h, angle)
            angle = np.clip(angle - (length - s) / np.sqrt(r * r + k * k + h * h), 0.0, self.sweep)
        return angle

    def points(self, s: np.ndarray) -> np.ndarray:
        """Points (m) at arc lengths ``s`` (m), shape (len(s), 3)."""
        s = np.asarray(s, float)
        if self.kind == SegmentKind.LINE:
            frac = s / self.length if self.length > 0 else np.zeros_like(s)
            return self.start + frac[:, None] * (self.end - self.start)
        if self.kind == SegmentKind.DWELL:
            return np.broadcast_to(self.start, (s.size, 3)).copy()
        assert self.center is not None and self.u is not None and self.v is not None and self.normal is not None
        angle = self._angle_of(s)
        frac = angle / self.sweep
        r = self.radius + (self.radius_end - self.radius) * frac
        out = (
            self.center
            + r[:, None] * (np.cos(angle)[:, None] * self.u + np.sin(angle)[:, None] * self.v)
            + (frac * self.rise)[:, None] * self.normal
        )
        if s.size and s[-1] >= self.length:
            out[s >= self.length] = self.end  # the programmed end exactly
        return out

    def outward(self, s: np.ndarray) -> Outward:
        """Arcs: at arc lengths ``s`` (m), the direction out from the axis, the radius and the
        angle turned per metre of path (:class:`Outward`)."""
        assert self.u is not None and self.v is not None
        angle = self._angle_of(np.asarray(s, float))
        k = (self.radius_end - self.radius) / self.sweep
        h = self.rise / self.sweep
        r = self.radius + k * angle
        radial = np.cos(angle)[:, None] * self.u + np.sin(angle)[:, None] * self.v
        return Outward(radial, r, 1.0 / np.sqrt(r * r + k * k + h * h))

    def tangent(self, at_end: bool) -> np.ndarray:
        """Unit tangent at the start or the end (worked out once)."""
        key = "tangent_end" if at_end else "tangent_start"
        if key not in self.planned:
            self.planned[key] = self._tangent(at_end)
        return self.planned[key]

    def _tangent(self, at_end: bool) -> np.ndarray:
        if self.kind == SegmentKind.LINE:
            d = self.end - self.start
            return d / math.sqrt(float(d @ d))
        assert self.u is not None and self.v is not None and self.normal is not None
        angle = self.sweep if at_end else 0.0
        r = self.radius_end if at_end else self.radius
        radial = math.cos(angle) * self.u + math.sin(angle) * self.v
        along = -math.sin(angle) * self.u + math.cos(angle) * self.v
        t = r * along + (self.radius_end - self.radius) / self.sweep * radial + self.rise / self.sweep * self.normal
        return t / math.sqrt(float(t @ t))

    def acceleration_direction(self, at_end: bool) -> np.ndarray:
        """The curvature vector (1/m) at the start or the end: towards the centre, 0 on lines."""
        if self.kind != SegmentKind.ARC:
            return np.zeros(3)
        assert self.u is not None and self.v is not None
        angle = self.sweep if at_end else 0.0
        inward = -(math.cos(angle) * self.u + math.sin(angle) * self.v)
        return inward * self.curvature

    def axis_share(self) -> np.ndarray:
        """The largest share of the path speed each axis takes anywhere on the segment, (3,):
        |tangent_i| for lines, the in-plane radius share plus the rise share for arcs (worked
        out once)."""
        if "axis_share" not in self.planned:
            self.planned["axis_share"] = self._axis_share()
        return self.planned["axis_share"]

    def _axis_share(self) -> np.ndarray:
        if self.kind == SegmentKind.LINE:
            return np.abs(self.tangent(False))
        assert self.u is not None and self.v is not None and self.normal is not None
        in_plane = max(self.radius, self.radius_end) * self.sweep / self.length
        return np.minimum(1.0, in_plane * np.hypot(self.u, self.v) + self.rise / self.length * np.abs(self.normal))

    def split(self, s: float) -> tuple[Segment, Segment]:
        """The segment cut at arc length ``s`` (0 < s < length) into two that make it up."""
        point = self.points(np.array([s]))[0]
        if self.kind == SegmentKind.LINE:
            return self.copy_with(end=point, length=s, mode="G64"), self.copy_with(start=point, length=self.length - s)
        assert self.u is not None and self.v is not None and self.normal is not None
        angle = float(self._angle_of(np.array([s]))[0])
        frac = angle / self.sweep
        r_mid = self.radius + (self.radius_end - self.radius) * frac
        first = self.copy_with(end=point, length=s, sweep=angle, rise=self.rise * frac, radius_end=r_mid, mode="G64")
        u2 = math.cos(angle) * self.u + math.sin(angle) * self.v
        v2 = -math.sin(angle) * self.u + math.cos(angle) * self.v
        second = self.copy_with(
            start=point,
            length=self.length - s,
            center=self.center + self.normal * self.rise * frac if self.center is not None else None,
            u=u2,
            v=v2,
            sweep=self.sweep - angle,
            rise=self.rise * (1.0 - frac),
            radius=r_mid,
        )
        return first, second

    def distance(self, p: np.ndarray) -> np.ndarray:
        """The exact distance (m) of each point of ``p`` (n, 3) to the segment."""
        if self.kind == SegmentKind.DWELL:
            return np.linalg.norm(p - self.start, axis=1)
        if self.kind == SegmentKind.LINE:
            d = self.end - self.start
            f = np.clip((p - self.start) @ d / max(float(d @ d), 1e-300), 0.0, 1.0)
            return np.linalg.norm(p - (self.start + f[:, None] * d), axis=1)
        return _arc_distance(self, p)


def _spiral_length(r0: float, k: float, h: float, angle):
    """Arc length of ``r = r0 + k phi``, ``z = h phi`` from 0 to ``angle``: the integral of
    ``sqrt(r^2 + k^2 + h^2)`` in closed form (``q^2 = k^2 + h^2``)."""
    q2 = k * k + h * h
    if abs(k) < 1e-15:
        return angle * math.sqrt(r0 * r0 + q2)

    def primitive(x):
        root = np.sqrt(x * x + q2)
        return 0.5 * x * root + 0.5 * q2 * np.log(x + root)

    return (primitive(r0 + k * angle) - primitive(r0)) / k


def _arc_distance(seg: Segment, p: np.ndarray) -> np.ndarray:
    """Distance to an arc: the nearest of its end points and, at the turns the point's angle
    may fall nearest on, the point of the arc at that angle refined by Newton's method on the
    squared distance (exact for a circle in one step, a helix or spiral in a few).

    The turns looked at: the first two and the last two (all alike on a circle but where the
    ends clip them), and those the point's height along the normal (a helix) or its radius (a
    spiral) puts within the distance found of it: a few per point near the arc, whatever its
    turns (a pass over every point for each turn made a 1 000-turn arc's check quadratic)."""
    assert seg.center is not None and seg.u is not None and seg.v is not None and seg.normal is not None
    rel = p - seg.center
    along_u, along_v = rel @ seg.u, rel @ seg.v
    angle = np.mod(np.arctan2(along_v, along_u), 2 * math.pi)
    best = np.minimum(np.linalg.norm(p - seg.start, axis=1), np.linalg.norm(p - seg.end, axis=1))
    k = (seg.radius_end - seg.radius) / seg.sweep
    h = seg.rise / seg.sweep
    last = math.ceil(seg.sweep / (2 * math.pi))
    rows = [np.repeat(np.arange(len(p)), 4)]
    turns = [np.tile(np.array([0, 1, last - 1, last]), len(p))]
    estimates = []  # (the turn the point's height or radius puts it on, the turns per metre off it)
    if h != 0.0:
        estimates.append((np.rint(((rel @ seg.normal) / h - angle) / (2 * math.pi)), 1.0 / (2 * math.pi * h)))
    if k != 0.0:
        radius = np.hypot(along_u, along_v)
        estimates.append((np.rint(((radius - seg.radius) / k - angle) / (2 * math.pi)), 1.0 / (2 * math.pi * abs(k))))
    estimates = [(np.clip(turn, 0, last), per_m) for turn, per_m in estimates]
    for turn, _per_m in estimates:
        rows.append(np.repeat(np.arange(len(p)), 3))
        turns.append((turn[:, None] + np.array([-1, 0, 1])).ravel())
    _nearest_on_turns(seg, p, rows=np.concatenate(rows), turns=np.concatenate(turns), angle=angle, best=best, last=last)
    for turn, per_m in estimates:
        # the turns whose height (radius) is within the distance found of the point's
        reach = np.minimum(np.ceil(best * per_m + 0.5), last + 1).astype(int)  # the estimate rounds by half a turn
        far = np.nonzero(reach > 1)[0]
        if far.size:
            counts = 2 * reach[far] + 1
            row = np.repeat(far, counts)
            step = (
                np.arange(counts.sum()) - np.repeat(np.cumsum(counts) - counts, counts) - np.repeat(reach[far], counts)
            )
            _nearest_on_turns(seg, p, rows=row, turns=turn[row] + step, angle=angle, best=best, last=last)
    return best


def _nearest_on_turns(seg, p, *, rows, turns, angle, best, last) -> None:
    """Lower ``best`` (per point of ``p``) to the distance of the arc's point that Newton's
    method finds from each point's ``angle`` on each of its ``turns`` (rows: the point of each)."""
    k = (seg.radius_end - seg.radius) / seg.sweep
    h = seg.rise / seg.sweep
    keep = (turns >= 0) & (turns <= last)
    span = last + 1
    key = np.sort(rows[keep].astype(np.int64) * span + turns[keep].astype(np.int64))  # by point, then turn
    key = key[np.concatenate([[True], key[1:] != key[:-1]])]
    rows = key // span
    phi = angle[rows] + 2 * math.pi * (key % span)
    inside = phi <= seg.sweep
    rows, phi = rows[inside], phi[inside]
    q = p[rows]
    for _ in range(SPIRAL_NEWTON_STEPS):
        c, s = np.cos(phi), np.sin(phi)
        r = seg.radius + k * phi
        point = seg.center + r[:, None] * (c[:, None] * seg.u + s[:, None] * seg.v) + (h * phi)[:, None] * seg.normal
        d1 = k * (c[:, None] * seg.u + s[:, None] * seg.v) + r[:, None] * (-s[:, None] * seg.u + c[:, None] * seg.v)
        d1 += h * seg.normal
        d2 = 2 * k * (-s[:, None] * seg.u + c[:, None] * seg.v) - r[:, None] * (c[:, None] * seg.u + s[:, None] * seg.v)
        diff = point - q
        grad = np.einsum("ij,ij->i", diff, d1)
        curv = np.einsum("ij,ij->i", d1, d1) + np.einsum("ij,ij->i", diff, d2)
        phi = np.clip(phi - grad / np.where(curv > 0, curv, 1.0), 0.0, seg.sweep)
    c, s = np.cos(phi), np.sin(phi)
    r = seg.radius + k * phi
    point = seg.center + r[:, None] * (c[:, None] * seg.u + s[:, None] * seg.v) + (h * phi)[:, None] * seg.normal
    if rows.size:
        starts = np.flatnonzero(np.concatenate([[True], rows[1:] != rows[:-1]]))
        nearest = np.minimum.reduceat(np.linalg.norm(point - q, axis=1), starts)
        best[rows[starts]] = np.minimum(best[rows[starts]], nearest)


def _unit(axis: int) -> np.ndarray:
    e = np.zeros(3)
    e[axis] = 1.0
    return e


def move_segment(move: Move, start_m: np.ndarray, tolerance_m: float) -> Segment | None:
    """The segment of one move, starting at ``start_m`` (machine m), with the tolerance in
    force (m); None for a null move."""
    offset = np.asarray(move.offset_mm) * 1e-3
    end = np.asarray(move.end_mm) * 1e-3 + offset
    feed = move.feed_mm_per_min * 1e-3 / 60.0
    mode = move.path_mode
    tol = tolerance_m
    if move.kind == MoveKind.DWELL:
        return Segment(
            move.line, SegmentKind.DWELL, False, 0.0, start_m, start_m, dwell_s=move.dwell_s, mode=mode, tolerance_m=tol
        )
    if move.kind in (MoveKind.RAPID, MoveKind.FEED):
        step = end - start_m
        length = math.sqrt(float(step @ step))
        if length < MIN_LENGTH_M:
            return None
        return Segment(
            move.line,
            SegmentKind.LINE,
            move.kind == MoveKind.RAPID,
            feed,
            start_m,
            end,
            length,
            mode=mode,
            tolerance_m=tol,
        )
    first, second, normal_axis = PLANES[move.plane]
    e1, e2, n = _unit(first), _unit(second), _unit(normal_axis)
    center = start_m.copy()
    center[first] = move.center_mm[0] * 1e-3 + offset[first]
    center[second] = move.center_mm[1] * 1e-3 + offset[second]
    center[normal_axis] = start_m[normal_axis]
    rel0, rel1 = start_m - center, end - center
    a0 = math.atan2(rel0[second], rel0[first])
    a1 = math.atan2(rel1[second], rel1[first])
    radius = math.hypot(rel0[first], rel0[second])
    radius_end = math.hypot(rel1[first], rel1[second])
    if abs(radius_end - radius) < 1e-12:
        radius_end = radius
    ccw = move.turns > 0
    sweep = (a1 - a0) % (2 * math.pi) if ccw else (a0 - a1) % (2 * math.pi)
    if sweep < 1e-12:
        sweep = 2 * math.pi  # a full circle
    sweep += 2 * math.pi * (abs(move.turns) - 1)
    u = math.cos(a0) * e1 + math.sin(a0) * e2
    quarter = -math.sin(a0) * e1 + math.cos(a0) * e2
    v = quarter if ccw else -quarter
    rise = float(end[normal_axis] - start_m[normal_axis])
    normal = n * (1.0 if rise >= 0 else -1.0)
    if radius_end == radius:
        length = math.hypot(radius * sweep, rise)
    else:
        k = (radius_end - radius) / sweep
        length = float(_spiral_length(radius, k, abs(rise) / sweep, sweep))
    return Segment(
        move.line,
        SegmentKind.ARC,
        False,
        feed,
        start_m,
        end,
        length,
        center,
        u,
        v,
        normal,
        radius,
        sweep,
        abs(rise),
        radius_end,
        mode=mode,
        tolerance_m=tol,
    )


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``np.cross`` of two 3-vectors, the same operations without its axis handling (a tenth of
    the time: a blend at every corner)."""
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


def turn_angle(a: Segment, b: Segment) -> float:
    """The angle (rad) between ``a``'s end tangent and ``b``'s start tangent."""
    return math.acos(max(-1.0, min(1.0, float(a.tangent(True) @ b.tangent(False)))))


def blend(a: Segment, b: Segment, tolerance_m: float) -> tuple[Segment, Segment, Segment] | None:
    """A tangent arc between lines ``a`` and ``b`` whose closest point to their corner is within
    ``tolerance_m`` of it, taking at most half of each line; the shortened lines and the arc, or
    None where the corner needs none (tangent) or cannot have one (zero tolerance, a reversal)."""
    ta, tb = a.tangent(True), b.tangent(False)
    turn = math.acos(max(-1.0, min(1.0, float(ta @ tb))))
    if turn < TANGENT_TOLERANCE_RAD or tolerance_m <= 0 or turn > math.pi - 1e-3:
        return None
    # radius from the tolerance: corner-to-arc distance R (1/cos(turn/2) - 1)
    radius = tolerance_m / (1.0 / math.cos(turn / 2) - 1.0)
    reach = radius * math.tan(turn / 2)
    limit = 0.5 * min(a.length, b.length)
    if reach > limit:
        reach = limit
        radius = reach / math.tan(turn / 2)
    corner = a.end
    p0, p1 = corner - ta * reach, corner + tb * reach
    bisector = tb - ta
    bisector /= math.sqrt(float(bisector @ bisector))
    center = corner + bisector * radius / math.cos(turn / 2)
    u = (p0 - center) / radius
    v = ta
    normal = _cross(u, v)
    arc = Segment(b.line, SegmentKind.ARC, a.rapid, min(a.feed_m_per_s, b.feed_m_per_s), p0, p1, radius * turn)
    arc.center, arc.u, arc.v, arc.normal, arc.radius, arc.sweep = center, u, v, normal, radius, turn
    arc.radius_end, arc.blend, arc.mode, arc.tolerance_m = radius, True, "G64", a.tolerance_m
    short_a = a.copy_with(end=p0, length=a.length - reach, mode="G64")
    short_b = b.copy_with(start=p1, length=b.length - reach)
    return short_a, arc, short_b
