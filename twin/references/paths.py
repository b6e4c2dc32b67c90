"""2-D paths at a constant feed, in mm and mm/min as machinists state them: circle, square,
polyline.  Each needs a machine of two axes."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Annotated, Literal

import numpy as np
from pydantic import Field

from twin.references.kinds import ReferenceContext, ReferenceSpecBase, register, two_axes

#: Smallest path size (mm) and feed (mm/min) a 2-D path may have: 1 um and 1 um/min.
MIN_PATH_MM, MIN_FEED_MM_PER_MIN = 1e-3, 1e-3
#: Largest: 10 m (the runaway limit) and 1e6 mm/min (16.7 m/s, beyond any machine tool).
MAX_PATH_MM, MAX_FEED_MM_PER_MIN = 1e4, 1e6
#: A coordinate of a path point (mm): within the 10 m runaway limit either side of the origin.
PathCoordinateMm = Annotated[float, Field(ge=-MAX_PATH_MM, le=MAX_PATH_MM)]
#: A feed (mm/min) within the limits above.
FeedMmPerMin = Annotated[float, Field(ge=MIN_FEED_MM_PER_MIN, le=MAX_FEED_MM_PER_MIN)]
#: A path size (mm) within the limits above.
PathSizeMm = Annotated[float, Field(ge=MIN_PATH_MM, le=MAX_PATH_MM)]


@dataclass
class Circle:
    """Circle of ``radius_mm`` at ``feed_mm_per_min``, starting at the origin going counter-clockwise.

    The centre is at (-R, 0) so the path starts where the table stands; the feed starts at t = 0.
    """

    radius_mm: float
    feed_mm_per_min: float
    n_axes: int = 2

    def sample(self, t):
        t = np.asarray(t, float)
        r = self.radius_mm * 1e-3
        w = self.feed_mm_per_min * 1e-3 / 60.0 / r
        out = np.zeros((t.size, 2, 3))
        c, s = np.cos(w * t), np.sin(w * t)
        out[:, 0] = np.stack([r * c - r, -r * w * s, -r * w * w * c], axis=1)
        out[:, 1] = np.stack([r * s, r * w * c, -r * w * w * s], axis=1)
        return out

    @property
    def period_s(self) -> float:
        """Time for one revolution (s)."""
        return 2 * math.pi * self.radius_mm / (self.feed_mm_per_min / 60.0)


@dataclass
class Polyline:
    """Straight segments through ``points_mm`` at constant ``feed_mm_per_min``.

    Velocity is piecewise constant; acceleration is zero (corners are velocity steps).
    After the last point the reference holds still.
    """

    points_mm: list[tuple[float, float]]
    feed_mm_per_min: float
    n_axes: int = 2
    _knots_s: np.ndarray = field(init=False, repr=False)

    def __post_init__(self):
        p = np.asarray(self.points_mm, float) * 1e-3
        if p.ndim != 2 or p.shape[1] != 2 or len(p) < 2:
            raise ValueError("points_mm must hold at least two (x, y) points")
        seg = np.linalg.norm(np.diff(p, axis=0), axis=1)
        if not (seg > 0).all():
            raise ValueError(f"points_mm: point {int(np.argmin(seg > 0)) + 1} repeats the one before it")
        self._p = p
        self._knots_s = np.concatenate([[0.0], np.cumsum(seg)]) / (self.feed_mm_per_min * 1e-3 / 60.0)

    @property
    def duration_s(self) -> float:
        """Time to traverse the path (s)."""
        return float(self._knots_s[-1])

    def sample(self, t):
        t = np.asarray(t, float)
        k = self._knots_s
        out = np.zeros((t.size, 2, 3))
        for a in range(2):
            out[:, a, 0] = np.interp(t, k, self._p[:, a])
        idx = np.clip(np.searchsorted(k, t, side="right") - 1, 0, len(k) - 2)
        vel = np.diff(self._p, axis=0) / np.diff(k)[:, None]
        moving = t < k[-1]
        out[:, :, 1] = np.where(moving[:, None], vel[idx], 0.0)
        return out


def square(side_mm: float, feed_mm_per_min: float) -> Polyline:
    """Square of ``side_mm`` starting and ending at the origin, counter-clockwise."""
    s = side_mm
    return Polyline([(0, 0), (s, 0), (s, s), (0, s), (0, 0)], feed_mm_per_min)


class CircleRef(ReferenceSpecBase):
    """circle: radius_mm at feed_mm_per_min, from the origin, counter-clockwise (two axes)."""

    type: Literal["circle"]
    radius_mm: PathSizeMm
    feed_mm_per_min: FeedMmPerMin


class SquareRef(ReferenceSpecBase):
    """square: side_mm at feed_mm_per_min, from the origin, counter-clockwise (two axes)."""

    type: Literal["square"]
    side_mm: PathSizeMm
    feed_mm_per_min: FeedMmPerMin


class PolylineRef(ReferenceSpecBase):
    """polyline: straight segments through points_mm = [[x, y], ...] at feed_mm_per_min (two axes)."""

    type: Literal["polyline"]
    points_mm: list[tuple[PathCoordinateMm, PathCoordinateMm]]
    feed_mm_per_min: FeedMmPerMin


def _circle(spec: CircleRef, ctx: ReferenceContext) -> Circle:
    two_axes(spec.type, ctx.axis_names)
    return Circle(spec.radius_mm, spec.feed_mm_per_min)


def _square(spec: SquareRef, ctx: ReferenceContext) -> Polyline:
    two_axes(spec.type, ctx.axis_names)
    return square(spec.side_mm, spec.feed_mm_per_min)


def _polyline(spec: PolylineRef, ctx: ReferenceContext) -> Polyline:
    from twin.errors import TwinInputError

    two_axes(spec.type, ctx.axis_names)
    try:
        return Polyline([(x, y) for x, y in spec.points_mm], spec.feed_mm_per_min)
    except ValueError as exc:
        raise TwinInputError("reference.points_mm", spec.points_mm, str(exc)) from None


register("circle", CircleRef, _circle)
register("square", SquareRef, _square)
register("polyline", PolylineRef, _polyline)
