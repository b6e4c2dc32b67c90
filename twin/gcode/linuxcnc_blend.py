# SPDX-License-Identifier: GPL-2.0-only
# A translation of LinuxCNC's trajectory planner (GPL Version 2): this file is under the GPL-2.0
# (twin/gcode/COPYING.linuxcnc), not the MIT licence of the rest of the twin.
"""The blend arcs of LinuxCNC 2.9's trajectory planner, ported from ``blendmath.c``: the corner
between two segments (line-line, line-arc, arc-line, arc-arc) under G64 replaced by a tangent
arc within the tolerance, its size chosen from the segments' lengths, the tolerance (G64 P, or a
quarter of the shorter segment without P) and the speed the arc allows (normal acceleration
``sqrt(3)/2`` of the plane's axis limit).

Units: mm, mm/s, mm/s^2, rad. Source: LinuxCNC ``src/emc/tp/blendmath.c`` (v2.9.0-pre1,
GPL-2.0; the port is a translation).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from twin.gcode.linuxcnc_geometry import (
    TP_ANGLE_EPSILON,
    Circle,
    Vec,
    add,
    colinear,
    cross,
    dot,
    mag,
    scale,
    sub,
    unit,
)
from twin.gcode.linuxcnc_tc import BLEND_ACC_RATIO_NORMAL, Segment

#: blendmath.h
BLEND_KINK_FACTOR = 0.25
#: tc_types.h: the share of a segment a blend may take.
BLEND_DIST_FRACTION = 0.5
TP_POS_EPSILON = 1e-12
TP_MIN_ARC_LENGTH = 1e-6


@dataclass
class Geometry:
    """``BlendGeom3``: the corner's point, tangents and normals, the arcs' centres and radii."""

    u_tan1: Vec = (0.0, 0.0, 0.0)
    u_tan2: Vec = (0.0, 0.0, 0.0)
    u1: Vec = (0.0, 0.0, 0.0)
    u2: Vec = (0.0, 0.0, 0.0)
    P: Vec = (0.0, 0.0, 0.0)
    theta_tan: float = 0.0
    binormal: Vec = (0.0, 0.0, 0.0)
    normal: Vec = (0.0, 0.0, 0.0)
    center1: Vec = (0.0, 0.0, 0.0)
    center2: Vec = (0.0, 0.0, 0.0)
    radius1: float = 0.0
    radius2: float = 0.0


@dataclass
class Parameters:
    """``BlendParameters``: the blend arc's size and speed."""

    theta: float = 0.0
    phi: float = 0.0
    tolerance: float = 0.0
    L1: float = 0.0
    L2: float = 0.0
    a_max: float = 0.0
    a_n_max: float = 0.0
    v_req: float = 0.0
    v_goal: float = 0.0
    v_plan: float = 0.0
    v_actual: float = 0.0
    R_plan: float = 0.0
    d_plan: float = 0.0
    s_arc: float = 0.0
    phi1_max: float = 0.0
    phi2_max: float = 0.0
    convex1: bool = False
    convex2: bool = False
    consume: bool = False
    line_length: float = 0.0


@dataclass
class Points:
    """``BlendPoints3``: the arc's start, end and centre, and how much each segment loses."""

    arc_start: Vec = (0.0, 0.0, 0.0)
    arc_end: Vec = (0.0, 0.0, 0.0)
    arc_center: Vec = (0.0, 0.0, 0.0)
    trim1: float = 0.0
    trim2: float = 0.0
    extra: dict = field(default_factory=dict)


class BlendFailed(Exception):
    """LinuxCNC's blend routines returned an error: no arc at this corner."""


def intersection_angle(u1: Vec, u2: Vec) -> float:
    """``findIntersectionAngle``: half the angle between ``-u1`` and ``u2`` (rad)."""
    d = max(-1.0, min(1.0, dot(u1, u2)))
    return math.acos(-d) / 2.0


def inscribed_diameter(normal: Vec, bounds: Vec) -> float:
    """``calculateInscribedDiameter``: the largest per-axis bound every direction in the plane
    normal to ``normal`` keeps."""
    if abs(1.0 - dot(normal, normal)) > math.sqrt(TP_POS_EPSILON):
        raise BlendFailed("normal")
    planar = []
    for i in range(3):
        p = [-normal[i] * normal[0], -normal[i] * normal[1], -normal[i] * normal[2]]
        p[i] += 1.0
        p = [abs(x) for x in p]
        p[i] = max(p[i], TP_POS_EPSILON)
        planar.append(mag((p[0], p[1], p[2])))
    extents = [bounds[i] / planar[i] if bounds[i] != 0 else 0.0 for i in range(3)]
    diameter = max(extents)
    for i in range(3):
        if bounds[i] != 0:
            diameter = min(diameter, extents[i])
    return diameter


def _convex(center: Vec, P: Vec, u_vec: Vec, reverse: bool) -> bool:
    """``arcConvexTest``."""
    return reverse ^ (dot(sub(P, center), u_vec) < 0)


def _spiral_approximation(circle: Circle, base: Vec, u_tan: Vec) -> tuple[Vec, float]:
    """``findSpiralApproximation``: the centre and radius of the circle that osculates a
    spiral at ``base``."""
    dr = circle.spiral / circle.angle
    center = add(scale(u_tan, dr), circle.center)
    return center, mag(sub(base, center))


def _trim_angle(P: Vec, arc_center: Vec, center: Vec) -> float:
    """``findTrimAngle``."""
    u_p = unit(sub(P, center))
    u_c = unit(sub(arc_center, center))
    return math.acos(max(-1.0, min(1.0, dot(u_c, u_p))))


def _geometry(prev: Segment, seg: Segment) -> Geometry:
    """``blendGeom3Init``."""
    geom = Geometry()
    geom.u_tan1 = prev.end_tangent()
    geom.u_tan2 = seg.start_tangent()
    geom.u1, geom.u2 = geom.u_tan1, geom.u_tan2
    if seg.kind == "line":
        geom.P = seg.line.start
    elif prev.kind == "line":
        geom.P = prev.line.end
    else:
        geom.P = seg.circle.point(0.0)
    geom.theta_tan = intersection_angle(geom.u_tan1, geom.u_tan2)
    if math.pi / 2.0 - geom.theta_tan < TP_ANGLE_EPSILON or geom.theta_tan < TP_ANGLE_EPSILON:
        raise BlendFailed("tolerance")
    _normals(geom)
    return geom


def _normals(geom: Geometry) -> None:
    """``blendCalculateNormals3``."""
    geom.binormal = unit(cross(geom.u_tan1, geom.u_tan2))
    geom.normal = unit(sub(geom.u_tan2, geom.u_tan1))


def blend_tolerance(prev: Segment, seg: Segment) -> float:
    """``tcFindBlendTolerance``: G64 P, or a quarter of the segment's length without it, and
    at most a quarter of either segment."""
    ratio = 0.25
    t1 = prev.tolerance if prev.tolerance != 0 else prev.nominal_length * ratio
    t2 = seg.tolerance if seg.tolerance != 0 else seg.nominal_length * ratio
    nominal = min(t1, t2)
    return min(min(nominal, prev.nominal_length * ratio), seg.nominal_length * ratio)


def _kinematics(geom: Geometry, param: Parameters, *, prev: Segment, seg: Segment, acc: Vec, vel: Vec, feed_scale):
    """``blendParamKinematics``."""
    param.phi = math.pi - param.theta * 2.0
    param.tolerance = blend_tolerance(prev, seg)
    param.a_max = inscribed_diameter(geom.binormal, acc)
    param.a_n_max = param.a_max * BLEND_ACC_RATIO_NORMAL
    param.v_req = max(prev.max_target_vel(1.0), seg.max_target_vel(1.0))
    param.v_goal = max(prev.max_target_vel(feed_scale), seg.max_target_vel(feed_scale))
    v_planar_max = inscribed_diameter(geom.binormal, vel)
    phi_effective = min(param.phi, math.pi * 0.49)
    v_max1 = min(prev.maxvel, seg.maxvel / math.cos(phi_effective))
    v_max2 = min(seg.maxvel, prev.maxvel / math.cos(phi_effective))
    v_area = v_max1 * v_max2 / 2.0 * math.sin(param.phi)
    base = mag(sub(scale(geom.u2, v_max2), scale(geom.u1, v_max1)))
    v_max_alt = 2.0 * v_area / base
    if prev.kind != "line" or seg.kind != "line":
        v_max_alt = 0.0
    param.v_goal = min(param.v_goal, max(v_max_alt, v_planar_max))


def init_line_line(prev: Segment, seg: Segment, *, acc: Vec, vel: Vec, feed_scale: float):
    """``blendInit3FromLineLine``."""
    geom = _geometry(prev, seg)
    param = Parameters()
    param.theta = geom.theta_tan
    param.phi = math.pi - param.theta * 2.0
    param.L1 = min(prev.target, prev.nominal_length * BLEND_DIST_FRACTION)
    param.L2 = seg.target * BLEND_DIST_FRACTION
    _kinematics(geom, param, prev=prev, seg=seg, acc=acc, vel=vel, feed_scale=feed_scale)
    return geom, param


def init_line_arc(prev: Segment, seg: Segment, *, acc: Vec, vel: Vec, feed_scale: float):
    """``blendInit3FromLineArc``."""
    geom = _geometry(prev, seg)
    param = Parameters()
    circle = seg.circle
    geom.center2, geom.radius2 = _spiral_approximation(circle, geom.P, geom.u_tan2)
    param.convex2 = _convex(geom.center2, geom.P, geom.u_tan1, True)
    blend_angle_2 = geom.theta_tan if param.convex2 else math.pi / 2.0
    param.phi2_max = min(circle.angle / 3.0, blend_angle_2)
    param.theta = geom.theta_tan
    if param.convex2:
        geom.u2 = unit(sub(circle.point(param.phi2_max / 2.0), geom.P))
        param.theta = min(param.theta, geom.theta_tan - param.phi2_max / 4.0)
    param.phi = math.pi - param.theta * 2.0
    param.L1 = min(prev.target, prev.nominal_length / 2.0)
    if param.convex2:
        param.L2 = math.sin(param.phi2_max / 4.0) * geom.radius2
    else:
        param.L2 = param.phi2_max * geom.radius2
    _kinematics(geom, param, prev=prev, seg=seg, acc=acc, vel=vel, feed_scale=feed_scale)
    return geom, param


def init_arc_line(prev: Segment, seg: Segment, *, acc: Vec, vel: Vec, feed_scale: float):
    """``blendInit3FromArcLine``."""
    geom = _geometry(prev, seg)
    param = Parameters()
    circle = prev.circle
    geom.center1, geom.radius1 = _spiral_approximation(circle, geom.P, geom.u_tan1)
    param.convex1 = _convex(geom.center1, geom.P, geom.u_tan2, False)
    blend_angle_1 = geom.theta_tan if param.convex1 else math.pi / 2.0
    param.phi1_max = min(circle.angle * 2.0 / 3.0, blend_angle_1)
    param.theta = geom.theta_tan
    if param.convex1:
        geom.u1 = unit(sub(geom.P, circle.point(circle.angle - param.phi1_max / 2.0)))
        param.theta = min(param.theta, geom.theta_tan - param.phi1_max / 4.0)
    param.L1 = param.phi1_max * geom.radius1
    param.L2 = seg.nominal_length / 2.0
    if param.convex1:
        param.L1 = math.sin(param.phi1_max / 4.0) * geom.radius1
    _kinematics(geom, param, prev=prev, seg=seg, acc=acc, vel=vel, feed_scale=feed_scale)
    return geom, param


def init_arc_arc(prev: Segment, seg: Segment, *, acc: Vec, vel: Vec, feed_scale: float):
    """``blendInit3FromArcArc``."""
    geom = _geometry(prev, seg)
    param = Parameters()
    c1, c2 = prev.circle, seg.circle
    geom.center1, geom.radius1 = _spiral_approximation(c1, geom.P, geom.u_tan1)
    geom.center2, geom.radius2 = _spiral_approximation(c2, geom.P, geom.u_tan2)
    _normals(geom)
    geom.P = c2.point(0.0)
    param.convex1 = _convex(geom.center1, geom.P, geom.u_tan2, False)
    param.convex2 = _convex(geom.center2, geom.P, geom.u_tan1, True)
    blend_angle_1 = geom.theta_tan if param.convex1 else math.pi / 2.0
    blend_angle_2 = geom.theta_tan if param.convex2 else math.pi / 2.0
    param.phi1_max = min(c1.angle * 2.0 / 3.0, blend_angle_1)
    param.phi2_max = min(c2.angle / 3.0, blend_angle_2)
    param.theta = geom.theta_tan
    if param.convex1:
        geom.u1 = unit(sub(geom.P, c1.point(c1.angle - param.phi1_max / 2.0)))
        param.theta = min(param.theta, geom.theta_tan - param.phi1_max / 4.0)
    if param.convex2:
        geom.u2 = unit(sub(c2.point(param.phi2_max / 2.0), geom.P))
        param.theta = min(param.theta, geom.theta_tan - param.phi2_max / 4.0)
    if param.theta < math.pi / 12.0:
        raise BlendFailed("theta")
    param.phi = math.pi - param.theta * 2.0
    param.L1 = param.phi1_max * geom.radius1
    param.L2 = param.phi2_max * geom.radius2
    if param.convex1:
        param.L1 = math.sin(param.phi1_max / 4.0) * geom.radius1
    if param.convex2:
        param.L2 = math.sin(param.phi2_max / 4.0) * geom.radius2
    _kinematics(geom, param, prev=prev, seg=seg, acc=acc, vel=vel, feed_scale=feed_scale)
    return geom, param


def compute_parameters(param: Parameters) -> None:
    """``blendComputeParameters``: the arc's radius, speed and how far it reaches back."""
    h_tol = param.tolerance / (1.0 - math.sin(param.theta))
    d_tol = math.cos(param.theta) * h_tol
    d_geom = min(min(param.L1, param.L2), d_tol)
    R_geom = math.tan(param.theta) * d_geom
    v_normal = math.sqrt(param.a_n_max * R_geom)
    param.v_plan = min(v_normal, param.v_goal)
    a_parabolic = param.a_max * 0.5
    v_triangle = math.sqrt(2.0 * a_parabolic * d_geom)
    t_blend = min(v_triangle, param.v_plan) / a_parabolic
    s_blend = t_blend * param.v_plan
    R_blend = min(s_blend / param.phi, R_geom)
    param.R_plan = max(param.v_plan * param.v_plan / param.a_n_max, R_blend)
    param.d_plan = param.R_plan / math.tan(param.theta)
    param.v_actual = param.v_req if param.v_plan > param.v_req else param.v_plan
    param.s_arc = param.R_plan * param.phi
    if param.R_plan < TP_POS_EPSILON or param.s_arc < TP_MIN_ARC_LENGTH:
        raise BlendFailed("radius")


def find_points(geom: Geometry, param: Parameters) -> Points:
    """``blendFindPoints3``."""
    points = Points()
    points.arc_center = add(scale(geom.normal, param.R_plan / math.sin(param.theta)), geom.P)
    points.arc_start = add(scale(geom.u1, -param.d_plan), geom.P)
    points.arc_end = add(scale(geom.u2, param.d_plan), geom.P)
    points.trim1 = param.d_plan
    points.trim2 = param.d_plan
    return points


def _quadratic(a: float, b: float, c: float) -> tuple[float, float]:
    disc = b * b - 4.0 * a * c
    if disc < 0:
        raise BlendFailed("quadratic")
    t1 = math.sqrt(disc)
    return (-b + t1) / (2.0 * a), (-b - t1) / (2.0 * a)


def _line_circle_center(
    geom: Geometry, param: Parameters, *, u_line: Vec, center: Vec, radius: float, convex: bool, sign
):
    """The blend arc's centre beside a line and a circle (``blendLineArcPostProcess``,
    ``blendArcLinePostProcess``): its distance along the line and the centre."""
    d = (-param.R_plan if convex else param.R_plan) + radius
    n = unit(cross(geom.binormal, u_line))
    r_pc = sub(center, geom.P)
    c_u = dot(r_pc, u_line)
    c_n = dot(r_pc, n)
    root0, root1 = _quadratic(1.0, 2.0 * c_u, c_u * c_u - d * d + (param.R_plan - c_n) ** 2)
    d_line = min(abs(root0), abs(root1))
    r = add(scale(u_line, sign * d_line), scale(n, param.R_plan))
    arc_center = add(geom.P, r)
    if mag(r) - param.R_plan > param.tolerance:
        raise BlendFailed("tolerance")
    return d_line, arc_center


def line_arc_points(geom: Geometry, param: Parameters) -> Points:
    """``blendLineArcPostProcess``."""
    points = Points()
    d_line, points.arc_center = _line_circle_center(
        geom, param, u_line=geom.u1, center=geom.center2, radius=geom.radius2, convex=param.convex2, sign=-1.0
    )
    points.trim1 = d_line
    points.trim2 = _trim_angle(geom.P, points.arc_center, geom.center2)
    return points


def arc_line_points(geom: Geometry, param: Parameters) -> Points:
    """``blendArcLinePostProcess``."""
    points = Points()
    d_line, points.arc_center = _line_circle_center(
        geom, param, u_line=geom.u2, center=geom.center1, radius=geom.radius1, convex=param.convex1, sign=1.0
    )
    points.trim1 = _trim_angle(geom.P, points.arc_center, geom.center1)
    points.trim2 = d_line
    return points


def arc_arc_points(geom: Geometry, param: Parameters) -> Points:
    """``blendArcArcPostProcess``."""
    d1 = (-param.R_plan if param.convex1 else param.R_plan) + geom.radius1
    d2 = (-param.R_plan if param.convex2 else param.R_plan) + geom.radius2
    r_c1c2 = sub(geom.center2, geom.center1)
    c2x = mag(r_c1c2)
    cx = (-(d1 * d1) + d2 * d2 - c2x * c2x) / (-2.0 * c2x)
    cy = math.sqrt(max(d1 * d1 - cx * cx, 0.0)) if d1 * d1 - cx * cx >= 0 else math.nan
    if c2x == 0.0 or math.isnan(cy):
        raise BlendFailed("arc-arc")
    uc = unit(r_c1c2)
    nc = cross(geom.binormal, uc)
    if dot(geom.normal, nc) < 0:
        nc = scale(nc, -1.0)
    if mag(nc) == 0.0:
        raise BlendFailed("arc-arc")
    nc = unit(nc)
    c_x = scale(uc, cx)
    c_y = scale(nc, cy)
    r_pc1 = sub(geom.center1, geom.P)
    test1 = add(r_pc1, c_x)
    test2 = test1
    test1 = add(test1, c_y)
    test2 = sub(test2, c_y)
    if mag(test2) < mag(test1):
        c_y = scale(c_y, -1.0)
    points = Points()
    points.arc_center = add(geom.center1, add(c_x, c_y))
    if mag(sub(points.arc_center, geom.P)) - param.R_plan > param.tolerance:
        raise BlendFailed("tolerance")
    points.trim1 = _trim_angle(geom.P, points.arc_center, geom.center1)
    points.trim2 = _trim_angle(geom.P, points.arc_center, geom.center2)
    return points


def max_tangent_angle(v_plan: float, acc_limit: float, cycle_time: float) -> float:
    """``findMaxTangentAngle``: the kink (rad) a blend arc may leave against a circle."""
    acc_margin = BLEND_ACC_RATIO_NORMAL * BLEND_KINK_FACTOR * acc_limit
    dx = v_plan / cycle_time
    return acc_margin / dx if dx > 0.0 else TP_ANGLE_EPSILON


def check_tangent_angle(
    circle: Circle, arc_tangent: Vec, *, param: Parameters, cycle_time: float, at_end: bool
) -> None:
    """``checkTangentAngle``: refuse an arc that meets ``circle`` at too sharp a kink."""
    u_circ = circle.tangent(0.0) if at_end else circle.tangent(circle.angle)
    u_arc = unit(arc_tangent)
    blend_angle = math.acos(max(-1.0, min(1.0, dot(u_circ, u_arc))))
    if blend_angle > max_tangent_angle(param.v_plan, param.a_max, cycle_time):
        raise BlendFailed("tangent")


def coplanar(u: Vec, v: Vec) -> bool:
    """``pmUnitCartsColinear`` on a binormal and a circle's normal."""
    return colinear(u, v)
