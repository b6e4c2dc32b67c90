"""The programmed path as geometry in machine coordinates (m): lines and arcs (helical where the
normal axis moves), with corner blends between lines, each a function of its arc length.

Corners between two feed lines (or two rapids) get a tangent blend arc whose distance to the
corner is at most the blend tolerance (LinuxCNC's G64 P rule; we put the arc in the plane of the
two lines); other corners, rapid-to-feed changes, dwells and the ends stop the motion.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from twin.gcode.reader import PLANES, Move

#: Moves shorter than this (m) are dropped: rs274 emits null moves (G28 to where the tool is).
MIN_LENGTH_M = 1e-9
#: Two unit tangents closer than this (rad) meet without a corner.
TANGENT_TOLERANCE_RAD = 1e-4


@dataclass
class Segment:
    """One piece of the path.

    Attributes
    ----------
    line : int
        The program line it comes from (a blend: the line of the move it leads into).
    kind : {"line", "arc", "dwell"}
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
        Arcs: radius (m), swept angle (rad, > 0), travel along the normal (m).
    normal : ndarray (3,)
        Arcs: unit normal (u x v).
    dwell_s : float
        Dwells: the time.
    blend : bool
        An arc the planner put in a corner (not programmed).
    """

    line: int
    kind: str
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
    dwell_s: float = 0.0
    blend: bool = False

    @property
    def curvature(self) -> float:
        """Curvature (1/m) of the path: 0 on lines."""
        if self.kind != "arc":
            return 0.0
        return self.radius / (self.radius**2 + (self.rise / self.sweep) ** 2)

    def points(self, s: np.ndarray) -> np.ndarray:
        """Points (m) at arc lengths ``s`` (m), shape (len(s), 3)."""
        s = np.asarray(s, float)
        if self.kind == "line":
            frac = s / self.length if self.length > 0 else np.zeros_like(s)
            return self.start + frac[:, None] * (self.end - self.start)
        if self.kind == "dwell":
            return np.broadcast_to(self.start, (s.size, 3)).copy()
        assert self.center is not None and self.u is not None and self.v is not None and self.normal is not None
        frac = s / self.length
        angle = frac * self.sweep
        return (
            self.center
            + self.radius * (np.cos(angle)[:, None] * self.u + np.sin(angle)[:, None] * self.v)
            + (frac * self.rise)[:, None] * self.normal
        )

    def tangent(self, at_end: bool) -> np.ndarray:
        """Unit tangent at the start or the end."""
        if self.kind == "line":
            d = self.end - self.start
            return d / np.linalg.norm(d)
        assert self.u is not None and self.v is not None and self.normal is not None
        angle = self.sweep if at_end else 0.0
        t = self.radius * self.sweep * (-math.sin(angle) * self.u + math.cos(angle) * self.v) + self.rise * self.normal
        return t / np.linalg.norm(t)

    def axis_share(self) -> np.ndarray:
        """The largest share of the path speed each axis takes anywhere on the segment, (3,):
        |tangent_i| for lines, the in-plane radius share plus the rise share for arcs."""
        if self.kind == "line":
            return np.abs(self.tangent(False))
        assert self.u is not None and self.v is not None and self.normal is not None
        in_plane = self.radius * self.sweep / self.length
        return np.minimum(1.0, in_plane * np.hypot(self.u, self.v) + self.rise / self.length * np.abs(self.normal))


def _unit(axis: int) -> np.ndarray:
    e = np.zeros(3)
    e[axis] = 1.0
    return e


def move_segment(move: Move, start_m: np.ndarray) -> Segment | None:
    """The segment of one move, starting at ``start_m`` (machine m); None for a null move."""
    offset = np.asarray(move.offset_mm) * 1e-3
    end = np.asarray(move.end_mm) * 1e-3 + offset
    feed = move.feed_mm_per_min * 1e-3 / 60.0
    if move.kind == "dwell":
        return Segment(move.line, "dwell", False, 0.0, start_m, start_m, dwell_s=move.dwell_s)
    if move.kind in ("rapid", "feed"):
        length = float(np.linalg.norm(end - start_m))
        if length < MIN_LENGTH_M:
            return None
        return Segment(move.line, "line", move.kind == "rapid", feed, start_m, end, length)
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
    length = math.hypot(radius * sweep, rise)
    seg = Segment(move.line, "arc", False, feed, start_m, end, length, center, u, v, normal, radius, sweep, abs(rise))
    return seg


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
    bisector /= np.linalg.norm(bisector)
    center = corner + bisector * radius / math.cos(turn / 2)
    u = (p0 - center) / radius
    v = ta
    normal = np.cross(u, v)
    arc = Segment(b.line, "arc", a.rapid, min(a.feed_m_per_s, b.feed_m_per_s), p0, p1, radius * turn)
    arc.center, arc.u, arc.v, arc.normal, arc.radius, arc.sweep = center, u, v, normal, radius, turn
    arc.blend = True
    short_a = Segment(a.line, "line", a.rapid, a.feed_m_per_s, a.start, p0, a.length - reach)
    short_b = Segment(b.line, "line", b.rapid, b.feed_m_per_s, p1, b.end, b.length - reach)
    return short_a, arc, short_b
