# SPDX-License-Identifier: GPL-2.0-only
# A translation of LinuxCNC's trajectory planner (GPL Version 2): this file is under the GPL-2.0
# (twin/gcode/COPYING.linuxcnc), not the MIT licence of the rest of the twin.
"""A segment of LinuxCNC 2.9's trajectory planner, ported: ``TC_STRUCT`` (its geometry, speeds
and motion state), its terminal conditions and the ``tc.c`` functions on one segment or a pair
(lengths, tangents, the acceleration it may use, kinks).

Units: mm, mm/s, mm/s^2, s. Source: LinuxCNC ``src/emc/tp/tc.c``, ``tc_types.h`` and the
acceleration shares of ``blendmath.h`` (v2.9.0-pre1, GPL-2.0; the port is a translation). The
blend arcs (:mod:`twin.gcode.linuxcnc_blend`) and the queue (:mod:`twin.gcode.linuxcnc_tp`) build
on this module.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from twin.gcode.linuxcnc_geometry import (
    DOUBLE_FUZZ,
    Circle,
    Line,
    SphericalArc,
    SpiralFit,
    Vec,
    add,
    cross,
    scale,
    sub,
    unit,
)

#: Terminal conditions (tc_types.h).
STOP, EXACT, PARABOLIC, TANGENT = 0, 1, 2, 3
#: Optimization states (tc_types.h).
TC_OPTIM_UNTOUCHED, TC_OPTIM_AT_MAX = 0, 1
#: blendmath.h: the share of the acceleration a curve spends along and across its path (a
#: segment's :meth:`Segment.tangential_max_accel` and the blend arcs read them).
BLEND_ACC_RATIO_TANGENTIAL = 0.5
BLEND_ACC_RATIO_NORMAL = math.sqrt(1.0 - BLEND_ACC_RATIO_TANGENTIAL**2)


@dataclass(eq=False)
class Segment:
    """``TC_STRUCT``: one segment of the queue and its motion state."""

    kind: str  # "line", "circle", "arc" (a spherical blend arc)
    traverse: bool
    line_number: int
    cycle_time: float
    maxaccel: float = 0.0
    maxvel: float = 0.0
    reqvel: float = 0.0
    target_vel: float = 0.0
    finalvel: float = 0.0
    target: float = 0.0
    nominal_length: float = 0.0
    progress: float = 0.0
    currentvel: float = 0.0
    term_cond: int = PARABOLIC
    tolerance: float = 0.0
    kink_vel: float = -1.0
    kink_accel_reduce: float = 0.0
    kink_accel_reduce_prev: float = 0.0
    blend_prev: bool = False
    acc_ratio_tan: float = BLEND_ACC_RATIO_TANGENTIAL
    finalized: bool = False
    active: bool = False
    remove: bool = False
    splitting: bool = False
    term_vel: float = 0.0
    blending_next: bool = False
    is_blending: bool = False
    on_final_decel: bool = False
    vel_at_blend_start: float = 0.0
    blend_vel: float = 0.0
    accel_ramp: bool = False
    optimization_state: int = TC_OPTIM_UNTOUCHED
    atspeed: bool = False
    active_depth: int = 1
    line: Line = field(default=None, repr=False)  # type: ignore[assignment]
    circle: Circle = field(default=None, repr=False)  # type: ignore[assignment]
    fit: SpiralFit = field(default=None, repr=False)  # type: ignore[assignment]
    arc: SphericalArc = field(default=None, repr=False)  # type: ignore[assignment]

    # --- tc.c ---------------------------------------------------------------------------

    def max_target_vel(self, max_scale: float) -> float:
        """``tcGetMaxTargetVel``."""
        return min(self.reqvel * max_scale, self.maxvel)

    def overall_max_accel(self) -> float:
        """``tcGetOverallMaxAccel``: halved under a parabolic blend."""
        a_scale = 1.0 - max(self.kink_accel_reduce, self.kink_accel_reduce_prev)
        if self.blend_prev or self.term_cond == PARABOLIC:
            a_scale *= 0.5
        return self.maxaccel * a_scale

    def tangential_max_accel(self) -> float:
        """``tcGetTangentialMaxAccel``: on a curve, the share left beside the normal one."""
        a = self.overall_max_accel()
        if self.kind != "line":
            a *= self.acc_ratio_tan
        return a

    def position(self, progress: float) -> Vec:
        """``tcGetPosReal``: the point ``progress`` (mm) along the segment."""
        if self.kind == "line":
            return self.line.point(progress * self.line.tmag / self.target)
        if self.kind == "circle":
            return self.circle.point(self.fit.angle_at(self.circle, progress))
        return self.arc.point(progress)

    def end_point(self) -> Vec:
        return self.position(self.target)

    def start_tangent(self) -> Vec:
        """``tcGetStartTangentUnitVector``."""
        if self.kind == "line":
            return self.line.u_vec
        return self.circle.tangent(0.0)

    def end_tangent(self) -> Vec:
        """``tcGetEndTangentUnitVector``."""
        if self.kind == "line":
            return self.line.u_vec
        return self.circle.tangent(self.circle.angle)

    def start_accel_unit(self) -> Vec:
        """``tcGetStartAccelUnitVector`` (a blend arc has none: LinuxCNC leaves the vector unset,
        and only a parabolic blend, which never follows an arc, would use it)."""
        if self.kind == "line":
            return self.line.u_vec
        if self.kind == "arc":
            return (0.0, 0.0, 0.0)
        c = self.circle
        start = c.point(0.0)
        tan = unit(cross(c.normal, sub(start, c.center)))
        perp = unit(sub(c.center, start))
        tan = scale(tan, self.overall_max_accel())
        perp = scale(perp, (0.5 * self.reqvel) ** 2 / c.radius)
        return unit(add(tan, perp))

    def end_accel_unit(self) -> Vec:
        """``tcGetEndAccelUnitVector`` (a blend arc has none, as at the start)."""
        if self.kind == "line":
            return self.line.u_vec
        if self.kind == "arc":
            return (0.0, 0.0, 0.0)
        c = self.circle
        end = c.point(c.angle)
        return unit(cross(c.normal, sub(end, c.center)))

    def set_circle(self, circle: Circle) -> None:
        """``tcSetCircleXYZ``."""
        self.circle = circle
        self.fit = SpiralFit.of(circle)
        self.target = self.fit.length(circle)

    def set_line(self, line: Line) -> None:
        """``tcSetLineXYZ``."""
        self.line = line
        self.target = line.tmag

    def clamp_velocity_by_length(self) -> None:
        """``tcClampVelocityByLength``."""
        self.maxvel = min(self.maxvel, self.target / self.cycle_time)

    def finalize_length(self) -> None:
        """``tcFinalizeLength``: length fixed; a circle's speed and tangential share set."""
        if self.finalized:
            return
        self.clamp_velocity_by_length()
        if self.kind == "circle":
            a_max = self.overall_max_accel()
            a_n_max_cutoff = BLEND_ACC_RATIO_NORMAL * a_max
            eff_radius = self.circle.effective_min_radius()
            a_n_vmax = self.maxvel * self.maxvel / max(eff_radius, DOUBLE_FUZZ)
            if a_n_vmax > a_n_max_cutoff:
                self.maxvel = math.sqrt(a_n_max_cutoff * eff_radius)
                self.acc_ratio_tan = BLEND_ACC_RATIO_TANGENTIAL
            else:
                self.acc_ratio_tan = math.sqrt(1.0 - (a_n_vmax / a_max) ** 2)
        self.finalized = True


def set_term_cond(prev: Segment | None, seg: Segment | None, term_cond: int) -> None:
    """``tcSetTermCond``."""
    if seg is not None:
        seg.blend_prev = term_cond == PARABOLIC
    if prev is not None:
        prev.term_cond = term_cond


def set_kink(prev: Segment, seg: Segment, kink_vel: float, reduction: float) -> None:
    """``tcSetKinkProperties``."""
    prev.kink_vel = kink_vel
    prev.kink_accel_reduce = max(reduction, prev.kink_accel_reduce)
    seg.kink_accel_reduce_prev = max(reduction, seg.kink_accel_reduce_prev)


def remove_kink(prev: Segment, seg: Segment) -> None:
    """``tcRemoveKinkProperties``."""
    prev.kink_vel = -1.0
    prev.kink_accel_reduce = 0.0
    seg.kink_accel_reduce_prev = 0.0
