# SPDX-License-Identifier: GPL-2.0-only
# A translation of LinuxCNC's trajectory planner (GPL Version 2): this file is under the GPL-2.0
# (twin/gcode/COPYING.linuxcnc), not the MIT licence of the rest of the twin.
"""The geometry of LinuxCNC 2.9's trajectory planner, ported: posemath's lines and circles
(``PmCartLine``, ``PmCircle``), the spiral arc-length fit of a circle, the spherical blend arc
(``spherical_arc.c``) and the vector helpers they use, with LinuxCNC's order of operations so
that the positions agree with the real planner's to rounding.

Units are LinuxCNC's: mm, mm/s, mm/s^2, radians. Vectors are tuples (x, y, z).
Source: LinuxCNC ``src/libnml/posemath/_posemath.c``, ``src/emc/tp/blendmath.c`` and
``src/emc/tp/spherical_arc.c`` (v2.9.0-pre1, GPL-2.0; the port is a translation).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

Vec = tuple[float, float, float]

#: posemath's fuzz values.
DOUBLE_FUZZ = 2.2204460492503131e-16
CART_FUZZ = 1.0e-8
CIRCLE_FUZZ = 1.0e-9
#: spherical_arc.h: the smallest radius and angle of a blend arc.
ARC_MIN_RADIUS = 1e-12
ARC_MIN_ANGLE = 1e-6
#: tp_types.h
TP_ANGLE_EPSILON = 1e-6


def add(a: Vec, b: Vec) -> Vec:
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])


def sub(a: Vec, b: Vec) -> Vec:
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def scale(a: Vec, k: float) -> Vec:
    return (a[0] * k, a[1] * k, a[2] * k)


def dot(a: Vec, b: Vec) -> float:
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def cross(a: Vec, b: Vec) -> Vec:
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def mag(a: Vec) -> float:
    return math.sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2])


def mag_sq(a: Vec) -> float:
    return a[0] * a[0] + a[1] * a[1] + a[2] * a[2]


def unit(a: Vec) -> Vec:
    """``pmCartUnit``: ``a`` over its length (a zero vector is returned as it is)."""
    size = math.sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2])
    if size == 0.0:
        return a
    return (a[0] / size, a[1] / size, a[2] / size)


def project(v: Vec, onto: Vec) -> Vec:
    """``pmCartCartProj``: ``v``'s component along ``onto``."""
    return scale(onto, dot(v, onto) / dot(onto, onto))


def plane_project(v: Vec, normal: Vec) -> Vec:
    """``pmCartPlaneProj``: ``v`` without its component along ``normal``."""
    return sub(v, project(v, normal))


def parallel(u1: Vec, u2: Vec, tol: float) -> bool:
    return mag_sq(sub(u1, u2)) < tol


def anti_parallel(u1: Vec, u2: Vec, tol: float) -> bool:
    return mag_sq(add(u1, u2)) < tol


def colinear(u1: Vec, u2: Vec) -> bool:
    """``pmUnitCartsColinear``: parallel or anti-parallel unit vectors."""
    tol = TP_ANGLE_EPSILON * TP_ANGLE_EPSILON
    return parallel(u1, u2, tol) or anti_parallel(u1, u2, tol)


def abs_max(v: Vec) -> float:
    return max(max(abs(v[0]), abs(v[1])), abs(v[2]))


@dataclass
class Line:
    """``PmCartLine``: start, end, unit vector and length (mm)."""

    start: Vec
    end: Vec
    u_vec: Vec
    tmag: float
    tmag_zero: bool

    @classmethod
    def between(cls, start: Vec, end: Vec) -> Line:
        """``pmCartLineInit``."""
        u = sub(end, start)
        tmag = mag(u)
        if abs_max(u) <= CART_FUZZ:
            return cls(start, end, (1.0, 0.0, 0.0), tmag, True)
        return cls(start, end, unit(u), tmag, False)

    def point(self, length: float) -> Vec:
        """``pmCartLinePoint``: the point ``length`` (mm) from the start."""
        if self.tmag_zero:
            return self.end
        return add(self.start, scale(self.u_vec, length))

    def stretched(self, new_length: float, from_end: bool) -> Line | None:
        """``pmCartLineStretch``: the line cut to ``new_length`` (keeping its end when
        ``from_end``, else its start); None where LinuxCNC fails."""
        if self.tmag_zero or new_length <= DOUBLE_FUZZ:
            return None
        if from_end:
            return Line(add(scale(self.u_vec, -new_length), self.end), self.end, self.u_vec, new_length, False)
        return Line(self.start, add(self.start, scale(self.u_vec, new_length)), self.u_vec, new_length, False)


@dataclass
class Circle:
    """``PmCircle``: centre, unit normal, start radius vector (``r_tan``), the perpendicular in
    the plane (``r_perp``), the helix rise (``r_helix``), radius, angle (rad) and spiral (radius
    change, mm)."""

    center: Vec
    normal: Vec
    r_tan: Vec
    r_perp: Vec
    r_helix: Vec
    radius: float
    angle: float
    spiral: float

    @classmethod
    def init(cls, start: Vec, end: Vec, *, center: Vec, normal: Vec, turn: int) -> Circle:
        """``pmCircleInit``: ``turn`` as LinuxCNC's canon sends it (0: less than a turn
        counter-clockwise about ``normal``; -1: clockwise; more: added full turns)."""
        v = project(sub(start, center), normal)
        c = add(v, center)
        n = unit(normal)
        if turn < 0:
            turn = -1 - turn
            n = scale(n, -1.0)
        d = start
        radius = math.sqrt((c[0] - d[0]) ** 2 + (c[1] - d[1]) ** 2 + (c[2] - d[2]) ** 2)
        r_tan = sub(start, c)
        r_perp = cross(n, r_tan)
        r_helix = sub(end, c)
        r_end = plane_project(r_helix, n)
        spiral = mag(r_end) - radius
        r_helix = sub(r_helix, r_end)
        r_end = scale(unit(r_end), radius)
        if mag(r_end) == 0.0:
            r_end = add(r_end, scale(n, DOUBLE_FUZZ))
        cosine = dot(r_tan, r_end) / (radius * radius)
        if cosine > 1.0:
            angle = 0.0
        elif cosine < -1.0:
            angle = math.pi
        else:
            angle = math.acos(cosine)
        if dot(cross(r_tan, r_end), n) < DOUBLE_FUZZ:
            angle = 2.0 * math.pi - angle
        p1 = plane_project(start, normal)
        p2 = plane_project(end, normal)
        if math.sqrt((p2[0] - p1[0]) ** 2 + (p2[1] - p1[1]) ** 2 + (p2[2] - p1[2]) ** 2) < CART_FUZZ:
            angle = 2.0 * math.pi
        if turn > 0:
            angle += turn * 2.0 * math.pi
        if angle == 0:
            angle += CIRCLE_FUZZ / 2
        return cls(c, n, r_tan, r_perp, r_helix, radius, angle, spiral)

    def point(self, angle: float) -> Vec:
        """``pmCirclePoint``: the point at ``angle`` (rad) from the start."""
        p = add(scale(self.r_tan, math.cos(angle)), scale(self.r_perp, math.sin(angle)))
        k = angle / self.angle
        p = add(p, scale(unit(p), k * self.spiral))
        p = add(p, scale(self.r_helix, k))
        return add(self.center, p)

    def stretched(self, new_angle: float, from_end: bool) -> Circle | None:
        """``pmCircleStretch``: the circle cut to ``new_angle`` (keeping its end when
        ``from_end``); None where LinuxCNC fails (a helix)."""
        if new_angle <= DOUBLE_FUZZ or mag_sq(self.r_helix) > 1e-6:
            return None
        out = Circle(**self.__dict__)
        if from_end:
            new_start = self.point(self.angle - new_angle)
            out.r_tan = sub(new_start, self.center)
            out.r_perp = cross(self.normal, out.r_tan)
            out.radius = mag(out.r_tan)
        out.spiral = self.spiral * (new_angle / self.angle)
        out.angle = new_angle
        return out

    def tangent(self, angle: float) -> Vec:
        """``pmCircleTangentVector``: the unit tangent at ``angle``."""
        p = self.point(angle)
        radius = sub(p, self.center)
        u = cross(self.normal, radius)
        u = add(u, scale(self.r_helix, 1.0 / self.angle))
        u = add(u, scale(unit(radius), self.spiral / self.angle))
        return unit(u)

    def effective_min_radius(self) -> float:
        """``pmCircleEffectiveMinRadius``: the radius of curvature that bounds the normal
        acceleration, helix and spiral included."""
        dr = self.spiral / self.angle
        h2 = mag_sq(self.r_helix)
        n_inner = dr * dr + self.radius * self.radius
        den = n_inner + dr * dr
        num = math.sqrt(n_inner * n_inner * n_inner)
        r_spiral = num / den
        return h2 / r_spiral + r_spiral


@dataclass
class SpiralFit:
    """``SpiralArcLengthFit``: planar length ``b0 angle^2 + b1 angle``."""

    b0: float
    b1: float
    total_planar_length: float
    spiral_in: bool

    @classmethod
    def of(cls, circle: Circle) -> SpiralFit:
        """``findSpiralArcLengthFit``."""
        spiral_coef = circle.spiral / circle.angle
        min_radius = circle.radius
        spiral_in = False
        if circle.spiral < 0.0:
            spiral_coef *= -1.0
            min_radius += circle.spiral
            spiral_in = True
        slope_start = math.sqrt(min_radius * min_radius + spiral_coef * spiral_coef)
        slope_end = math.sqrt((min_radius + spiral_coef * circle.angle) ** 2 + spiral_coef * spiral_coef)
        b0 = (slope_end - slope_start) / (2.0 * circle.angle)
        b1 = slope_start
        return cls(b0, b1, b0 * circle.angle * circle.angle + b1 * circle.angle, spiral_in)

    def angle_at(self, circle: Circle, progress: float) -> float:
        """``pmCircleAngleFromProgress``: the angle (rad) at ``progress`` (mm along the helix)."""
        s_end = math.sqrt(self.total_planar_length * self.total_planar_length + mag_sq(circle.r_helix))
        t = progress / s_end
        if self.spiral_in:
            t = 1.0 - t
        c = -(t * self.total_planar_length)
        disc = self.b1 * self.b1 - 4.0 * self.b0 * c
        angle = (2.0 * c) / (-self.b1 - math.sqrt(max(disc, 0.0)))
        if self.spiral_in:
            angle = circle.angle - angle
        return angle

    def length(self, circle: Circle) -> float:
        """``pmCircle9Target``: the helical length (mm)."""
        return math.sqrt(self.total_planar_length * self.total_planar_length + mag_sq(circle.r_helix))


@dataclass
class SphericalArc:
    """``SphericalArc``: a blend arc from ``start`` to ``end`` about ``center`` (with the
    line it consumed before it, ``line_length`` mm along ``u_tan``)."""

    start: Vec
    end: Vec
    center: Vec
    r_start: Vec
    r_end: Vec
    radius: float
    angle: float
    spiral: float
    s_angle: float
    u_tan: Vec
    binormal: Vec
    line_length: float

    @classmethod
    def from_points(
        cls, start: Vec, end: Vec, center: Vec, *, u_tan: Vec, binormal: Vec, line_length: float
    ) -> SphericalArc | None:
        """``arcInitFromPoints`` (None where LinuxCNC fails: too small a radius or angle)."""
        r_start = sub(start, center)
        r_end = sub(end, center)
        radius0 = mag(r_start)
        radius1 = mag(r_end)
        if radius0 < ARC_MIN_RADIUS or radius1 < ARC_MIN_RADIUS:
            return None
        u0 = scale(r_start, 1.0 / radius0)
        u1 = scale(r_end, 1.0 / radius1)
        angle = math.acos(dot(u0, u1))
        if angle < ARC_MIN_ANGLE:
            return None
        return cls(
            start,
            end,
            center,
            r_start,
            r_end,
            radius0,
            angle,
            radius1 - radius0,
            math.sin(angle),
            u_tan,
            binormal,
            line_length,
        )

    def point(self, progress: float) -> Vec:
        """``arcPoint``: the point ``progress`` (mm) along the consumed line and the arc."""
        net = progress - self.line_length
        if net <= 0.0 and self.line_length > 0:
            return add(scale(self.u_tan, net), self.start)
        angle_in = net / self.radius
        scale0 = math.sin(self.angle - angle_in) / self.s_angle
        scale1 = math.sin(angle_in) / self.s_angle
        return add(self.center, add(scale(self.r_start, scale0), scale(self.r_end, scale1)))

    def length(self) -> float:
        """``arcLength`` (mm)."""
        return self.radius * self.angle + self.line_length

    def tangent(self, at_end: bool) -> Vec:
        """``arcTangent``: the unit tangent at the start or the end."""
        r_perp = self.r_end if at_end else self.r_start
        r_tan = cross(self.binormal, r_perp)
        d_perp = scale(unit(r_perp), self.spiral / self.angle)
        return unit(add(d_perp, r_tan))
