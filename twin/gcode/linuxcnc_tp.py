# SPDX-License-Identifier: GPL-2.0-only
# A translation of LinuxCNC's trajectory planner (GPL Version 2): this file is under the GPL-2.0
# (twin/gcode/COPYING.linuxcnc), not the MIT licence of the rest of the twin.
"""LinuxCNC 2.9's trajectory planner (``tp``), ported: its queue of segments, how a segment is
added (tangent or kinked junctions, blend arcs, the choice between an arc and a parabolic blend),
the look-ahead (``tpRunOptimization``, depth ``ARC_BLEND_OPTIMIZATION_DEPTH``) and the
per-servo-period update (trapezoidal speed, parabolic blends, split cycles at tangent junctions).

Units: mm, mm/s, mm/s^2, s. Source: LinuxCNC ``src/emc/tp/tp.c``, ``tc.c`` and ``tcq.c``
(v2.9.0-pre1, GPL-2.0; the port is a translation: names follow LinuxCNC's so the two can be
read side by side). Not ported: rotary and UVW axes, spindle-synchronized motion (G33, G76,
rigid tapping), pause, abort, reverse run, feed override changes while running, digital I/O.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from twin.gcode import linuxcnc_blend as bm
from twin.gcode.linuxcnc_geometry import (
    Circle,
    Line,
    SphericalArc,
    SpiralFit,
    Vec,
    abs_max,
    add,
    anti_parallel,
    scale,
    sub,
)
from twin.gcode.linuxcnc_tc import (
    BLEND_ACC_RATIO_TANGENTIAL,
    EXACT,
    PARABOLIC,
    STOP,
    TANGENT,
    TC_OPTIM_AT_MAX,
    Segment,
    remove_kink,
    set_kink,
    set_term_cond,
)

#: tp_types.h
TP_MIN_SEGMENT_CYCLES = 1.02
TP_OPTIMIZATION_CUTOFF = 4
TP_VEL_EPSILON = 1e-8
TP_POS_EPSILON = 1e-12
TP_TIME_EPSILON = 1e-12
TP_MIN_ARC_ANGLE = 1e-3


@dataclass(frozen=True)
class Config:
    """The motion module's settings (LinuxCNC's INI defaults in ``[TRAJ]``).

    Attributes
    ----------
    acc_bound, vel_bound : tuple of float
        Axis acceleration (mm/s^2) and velocity (mm/s) limits, x y z.
    cycle_time : float
        Servo period (s).
    v_limit : float
        ``[TRAJ] MAX_LINEAR_VELOCITY`` (mm/s).
    max_feed_scale : float
        ``[DISPLAY] MAX_FEED_OVERRIDE``.
    opt_depth, gap_cycles, ramp_freq, kink_ratio
        ``ARC_BLEND_OPTIMIZATION_DEPTH``, ``ARC_BLEND_GAP_CYCLES``, ``ARC_BLEND_RAMP_FREQ``
        (Hz), ``ARC_BLEND_KINK_RATIO``.
    """

    acc_bound: Vec
    vel_bound: Vec
    cycle_time: float = 1e-3
    v_limit: float = math.inf
    max_feed_scale: float = 1.0
    opt_depth: int = 50
    gap_cycles: int = 4
    ramp_freq: float = 100.0
    kink_ratio: float = 0.1


def find_v_peak(acc: float, length: float) -> float:
    """``findVPeak``: the top speed of a triangle profile over ``length``."""
    return math.sqrt(acc * length)


class Planner:
    """``TP_STRUCT``: the queue and the planner's state; :meth:`run_cycle` advances one servo
    period and :attr:`current_pos` is the commanded position (mm)."""

    def __init__(self, config: Config, start: Vec):
        self.config = config
        self.queue: list[Segment] = []
        self.current_pos: Vec = start
        self.goal_pos: Vec = start
        self.term_cond = PARABOLIC
        self.tolerance = 0.0
        self.current_vel = 0.0
        self.consumed = False

    # --- adding segments ------------------------------------------------------------------

    def set_term_cond(self, cond: int, tolerance: float) -> None:
        """``tpSetTermCond``."""
        self.term_cond = cond
        self.tolerance = tolerance

    def _new(self, kind: str, *, traverse: bool, line_number: int, vel: float, ini_maxvel: float, acc: float, atspeed):
        seg = Segment(kind, traverse, line_number, self.config.cycle_time, atspeed=atspeed)
        seg.term_cond = self.term_cond
        seg.tolerance = self.tolerance
        seg.maxaccel = acc
        seg.maxvel = ini_maxvel
        seg.reqvel = vel
        return seg

    def add_line(self, end: Vec, *, traverse: bool, line_number: int, vel, ini_maxvel, acc, atspeed=False) -> bool:
        """``tpAddLine``; False for a segment of zero length (not queued)."""
        seg = self._new(
            "line", traverse=traverse, line_number=line_number, vel=vel, ini_maxvel=ini_maxvel, acc=acc, atspeed=atspeed
        )
        seg.line = Line.between(self.goal_pos, end)
        seg.target = 0.0 if seg.line.tmag_zero else seg.line.tmag
        if seg.target < TP_POS_EPSILON:
            return False
        return self._add(seg)

    def add_circle(self, end: Vec, center: Vec, *, normal: Vec, turn: int, line_number: int, vel, ini_maxvel, acc,
                   atspeed=False) -> bool:  # fmt: skip
        """``tpAddCircle``; False for a segment of zero length (not queued)."""
        seg = self._new(
            "circle", traverse=False, line_number=line_number, vel=vel, ini_maxvel=ini_maxvel, acc=acc, atspeed=atspeed
        )
        seg.set_circle(Circle.init(self.goal_pos, end, center=center, normal=normal, turn=turn))
        if seg.target < TP_POS_EPSILON:
            return False
        return self._add(seg)

    def _add(self, seg: Segment) -> bool:
        seg.nominal_length = seg.target
        seg.clamp_velocity_by_length()
        prev = self.queue[-1] if self.queue else None
        if prev is not None and prev.traverse != seg.traverse:  # handleModeChange
            set_term_cond(prev, seg, STOP)
        self.consumed = False
        self._handle_blend_arc(seg)
        if seg.kind == "circle":
            seg.fit = SpiralFit.of(seg.circle)
        if self.consumed:  # prev was taken into a blend arc, which LinuxCNC queued in its slot
            prev = self.queue[-1]
        if prev is not None:
            prev.finalize_length()
            if seg.atspeed:  # tcFlagEarlyStop
                set_term_cond(prev, seg, STOP)
        self._enqueue(seg)
        self._run_optimization()
        return True

    def _enqueue(self, seg: Segment) -> None:
        """``tpAddSegmentToQueue``."""
        self.queue.append(seg)
        self.goal_pos = seg.end_point()

    def _handle_blend_arc(self, seg: Segment) -> None:
        """``tpHandleBlendArc``: tangent, blend arc or parabolic blend at the junction."""
        if not self.queue:
            return
        prev = self.queue[-1]
        if prev.progress > prev.target / 2.0:
            return
        result = self._setup_tangent(prev, seg)
        if result is not None:
            return
        blend = self._create_blend(prev, seg)
        if blend is not None:
            self._enqueue(blend)
        else:
            self._choose_best_blend(prev, seg, None)

    def _setup_tangent(self, prev: Segment, seg: Segment) -> bool | None:
        """``tpSetupTangent``: True (tangent), False (fail: no blend), None (a kink: go on)."""
        if self.config.opt_depth < 2 or prev.term_cond == STOP:
            return False
        prev_tan, this_tan = prev.end_tangent(), seg.start_tangent()
        if anti_parallel(prev_tan, this_tan, (math.pi * (2.0 / 180.0)) ** 2):
            set_term_cond(prev, seg, STOP)
            return False
        v_max = min(prev.max_target_vel(self.config.max_feed_scale), seg.max_target_vel(self.config.max_feed_scale))
        a_inst = v_max / self.config.cycle_time + seg.maxaccel
        acc_diff = sub(scale(this_tan, a_inst), scale(prev_tan, a_inst))
        bound = self.config.acc_bound
        acc_scale = tuple(abs(acc_diff[i] / bound[i]) if bound[i] != 0 else 0.0 for i in range(3))
        acc_scale_max = abs_max(acc_scale)  # type: ignore[arg-type]
        if prev.kind == "circle" or seg.kind == "circle":
            acc_scale_max /= BLEND_ACC_RATIO_TANGENTIAL
        kink_ratio = max(min(self.config.kink_ratio, 0.7071), 0.001)
        if acc_scale_max < kink_ratio:
            set_term_cond(prev, seg, TANGENT)
            set_kink(prev, seg, v_max, acc_scale_max)
            return True
        set_kink(prev, seg, v_max * kink_ratio / acc_scale_max, kink_ratio)
        return None

    def _create_blend(self, prev: Segment, seg: Segment) -> Segment | None:
        """``tpCreateBlendIfPossible``: the blend arc (to be queued), or None."""
        if prev.term_cond != PARABOLIC or seg.finalized or prev.finalized:
            return None
        if prev.kind not in ("line", "circle") or seg.kind not in ("line", "circle"):
            return None
        try:
            if prev.kind == "line" and seg.kind == "line":
                return self._line_line_blend(prev, seg)
            return self._curved_blend(prev, seg)
        except bm.BlendFailed:
            return None

    def _blend_segment(self, prev: Segment, arc: SphericalArc, param: bm.Parameters) -> Segment:
        """``tpInitBlendArcFromPrev``."""
        blend = Segment("arc", prev.traverse, prev.line_number, self.config.cycle_time)
        blend.term_cond = self.term_cond
        blend.tolerance = self.tolerance
        blend.maxaccel = param.a_max
        blend.maxvel = param.v_plan
        blend.reqvel = param.v_req
        blend.arc = arc
        blend.target = arc.length()
        blend.nominal_length = blend.target
        set_term_cond(blend, None, TANGENT)
        blend.finalize_length()
        return blend

    def _line_line_blend(self, prev: Segment, seg: Segment) -> Segment | None:
        """``tpCreateLineLineBlend``."""
        cfg = self.config
        geom, param = bm.init_line_line(prev, seg, acc=cfg.acc_bound, vel=cfg.vel_bound, feed_scale=cfg.max_feed_scale)
        bm.compute_parameters(param)
        points = bm.find_points(geom, param)
        self._check_consume(param, points, prev)
        arc = SphericalArc.from_points(
            points.arc_start,
            points.arc_end,
            points.arc_center,
            u_tan=geom.u_tan1,
            binormal=geom.binormal,
            line_length=param.line_length,
        )
        if arc is None:
            return None
        blend = self._blend_segment(prev, arc, param)
        if self._choose_best_blend(prev, seg, blend) != "arc":
            return None
        if param.consume:  # tcConnectBlendArc
            self.queue.pop()
            self.consumed = True
        else:
            prev.set_line(Line.between(prev.line.start, points.arc_start))
            set_term_cond(prev, seg, TANGENT)
        seg.set_line(Line.between(points.arc_end, seg.line.end))
        set_term_cond(None, seg, TANGENT)
        return blend

    def _curved_blend(self, prev: Segment, seg: Segment) -> Segment | None:
        """``tpCreateLineArcBlend``, ``tpCreateArcLineBlend``, ``tpCreateArcArcBlend``."""
        cfg = self.config
        if prev.kind == "circle" and seg.kind == "circle":
            if not bm.coplanar(prev.circle.normal, seg.circle.normal):
                return None
            geom, param = bm.init_arc_arc(
                prev, seg, acc=cfg.acc_bound, vel=cfg.vel_bound, feed_scale=cfg.max_feed_scale
            )
            if not bm.coplanar(geom.binormal, prev.circle.normal) or not bm.coplanar(geom.binormal, seg.circle.normal):
                return None
            bm.compute_parameters(param)
            points = bm.arc_arc_points(geom, param)
        elif prev.kind == "line":
            geom, param = bm.init_line_arc(
                prev, seg, acc=cfg.acc_bound, vel=cfg.vel_bound, feed_scale=cfg.max_feed_scale
            )
            if not bm.coplanar(geom.binormal, seg.circle.normal):
                return None
            bm.compute_parameters(param)
            points = bm.line_arc_points(geom, param)
        else:
            geom, param = bm.init_arc_line(
                prev, seg, acc=cfg.acc_bound, vel=cfg.vel_bound, feed_scale=cfg.max_feed_scale
            )
            if not bm.coplanar(geom.binormal, prev.circle.normal):
                return None
            bm.compute_parameters(param)
            points = bm.arc_line_points(geom, param)
        if prev.kind == "line":  # line-arc: trim2 checked first, then consume
            if points.trim2 > param.phi2_max:
                return None
            self._check_consume(param, points, prev)
        else:
            self._check_consume(param, points, prev)
            if points.trim1 > param.phi1_max:
                return None
            if seg.kind == "circle" and points.trim2 > param.phi2_max:
                return None
        # the trimmed segments
        new_prev_line = new_prev_circle = new_line = new_circle = None
        if prev.kind == "line":
            new_prev_line = prev.line.stretched(prev.line.tmag - points.trim1, False)
            if new_prev_line is None:
                return None
            points.arc_start = new_prev_line.point(new_prev_line.tmag)
        else:
            new_prev_circle = prev.circle.stretched(prev.circle.angle - points.trim1, False)
            if new_prev_circle is None:
                return None
        if seg.kind == "line":
            new_line = seg.line.stretched(seg.target - points.trim2, True)
            if new_line is None:
                return None
        else:
            new_circle = seg.circle.stretched(seg.circle.angle - points.trim2, True)
            if new_circle is None:
                return None
        if new_prev_circle is not None:
            points.arc_start = new_prev_circle.point(new_prev_circle.angle)
        if new_line is not None:
            points.arc_end = new_line.point(0.0)
        if new_circle is not None:
            points.arc_end = new_circle.point(0.0)
        arc = SphericalArc.from_points(
            points.arc_start,
            points.arc_end,
            points.arc_center,
            u_tan=geom.u_tan1,
            binormal=geom.binormal,
            line_length=param.line_length,
        )
        if arc is None:
            return None
        blend = self._blend_segment(prev, arc, param)
        try:
            if new_circle is not None:
                bm.check_tangent_angle(
                    new_circle, arc.tangent(True), param=param, cycle_time=cfg.cycle_time, at_end=True
                )
            if new_prev_circle is not None:
                bm.check_tangent_angle(
                    new_prev_circle, arc.tangent(False), param=param, cycle_time=cfg.cycle_time, at_end=False
                )
        except bm.BlendFailed:
            return None
        if self._choose_best_blend(prev, seg, blend) != "arc":
            return None
        if prev.kind == "line":
            if param.consume:
                self.queue.pop()
                self.consumed = True
            else:
                prev.set_line(new_prev_line)  # type: ignore[arg-type]
        else:
            prev.set_circle(new_prev_circle)  # type: ignore[arg-type]
        if new_circle is not None:
            seg.set_circle(new_circle)
        else:
            seg.set_line(new_line)  # type: ignore[arg-type]
        if prev.kind == "circle":
            seg.blend_prev = False
        set_term_cond(prev, seg, TANGENT)
        return blend

    def _check_consume(self, param: bm.Parameters, points: bm.Points, prev: Segment) -> None:
        """``blendCheckConsume``: a line left shorter than the gap cycles is taken into the arc."""
        param.consume = False
        param.line_length = 0.0
        if prev.kind != "line":
            return
        remaining = prev.target - points.trim1
        can_consume = not (prev.blend_prev or prev.atspeed)
        param.consume = remaining / param.v_plan < self.config.gap_cycles * prev.cycle_time and can_consume
        if param.consume:
            param.line_length = remaining

    def _choose_best_blend(self, prev: Segment, seg: Segment, blend: Segment | None) -> str:
        """``tpChooseBestBlend``: the blend of the three whose speed is highest."""
        if prev.term_cond in (EXACT, STOP):
            return "none"
        perf_parabolic = self._parabolic_performance(prev, seg) / 2.0
        perf_tangent = prev.kink_vel
        perf_arc = blend.maxvel if blend is not None else 0.0
        perf = [perf_parabolic, perf_tangent, perf_arc]
        best = perf.index(max(perf))
        if best == 0:
            remove_kink(prev, seg)
            set_term_cond(prev, seg, PARABOLIC)
            return "parabolic"
        if best == 1:
            set_term_cond(prev, seg, TANGENT)
            return "tangent"
        remove_kink(prev, seg)
        return "arc"

    def _parabolic_performance(self, prev: Segment, seg: Segment) -> float:
        """``estimateParabolicBlendPerformance``."""
        _this, _next, net = self._blend_velocity(prev, seg, self._max_target_vel(prev), self._max_target_vel(seg))
        return net

    # --- look-ahead -------------------------------------------------------------------------

    def _max_target_vel(self, seg: Segment) -> float:
        """``tpGetMaxTargetVel``."""
        max_scale = self.config.max_feed_scale
        if seg.is_blending:
            max_scale = min(max_scale, 1.0)
        return min(seg.max_target_vel(max_scale), self.config.v_limit)

    def _run_optimization(self) -> None:
        """``tpRunOptimization``: the backward pass over the queue's tangent junctions."""
        n = len(self.queue)
        hit_peaks = 0
        hit_non_tangent = False
        for x in range(1, self.config.opt_depth + 2):
            ind = n - x
            if ind - 1 < 0:
                return
            seg, prev = self.queue[ind], self.queue[ind - 1]
            if prev.term_cond != TANGENT:
                if hit_non_tangent:
                    return
                hit_non_tangent = True
                continue
            if prev.progress / prev.target >= bm.BLEND_DIST_FRACTION / 2.0:
                return
            if prev.splitting or prev.blending_next:
                return
            if seg.atspeed:
                seg.finalvel = 0.0
            if not seg.finalized:
                acc = seg.tangential_max_accel()
                initial = min(find_v_peak(acc, seg.target), self._max_target_vel(seg))
                prev.finalvel = min(prev.maxvel, initial)
                if prev.kink_vel >= 0 and prev.term_cond == TANGENT:
                    prev.finalvel = min(prev.finalvel, prev.kink_vel)
                seg.finalvel = 0.0
            else:
                self._optimal_velocity(seg, prev)
            seg.active_depth = x - 2 - hit_peaks
            if seg.optimization_state == TC_OPTIM_AT_MAX:
                hit_peaks += 1
            if hit_peaks > TP_OPTIMIZATION_CUTOFF:
                return

    def _optimal_velocity(self, seg: Segment, prev: Segment) -> None:
        """``tpComputeOptimalVelocity``."""
        acc_this = seg.tangential_max_accel()
        vs_back = math.sqrt(seg.finalvel * seg.finalvel + 2.0 * acc_this * seg.target)
        vf_limit_prev = prev.maxvel
        if prev.kink_vel >= 0 and prev.term_cond == TANGENT:
            vf_limit_prev = min(vf_limit_prev, prev.kink_vel)
        vf_limit = min(seg.maxvel, vf_limit_prev)
        if vs_back >= vf_limit:
            vs_back = vf_limit
            prev.optimization_state = TC_OPTIM_AT_MAX
        prev.finalvel = vs_back
        seg.maxvel = min(seg.maxvel, seg.target / (self.config.cycle_time * TP_MIN_SEGMENT_CYCLES))

    # --- the servo cycle ------------------------------------------------------------------

    def _feed_scale(self, seg: Segment) -> float:
        """``tpGetFeedScale`` (the override at 1: a blend never above it)."""
        return 1.0

    def _real_target_vel(self, seg: Segment | None) -> float:
        """``tpGetRealTargetVel``."""
        if seg is None:
            return 0.0
        return min(seg.reqvel * self._feed_scale(seg), self._max_target_vel(seg))

    def _real_final_vel(self, seg: Segment, nxt: Segment | None) -> float:
        """``tpGetRealFinalVel``."""
        if seg.term_cond != TANGENT:
            return 0.0
        v_target = min(self._real_target_vel(seg), self._real_target_vel(nxt) if nxt is not None else 0.0)
        return min(seg.finalvel, v_target)

    def _blend_velocity(self, seg: Segment, nxt: Segment, v_target_this: float, v_target_next: float):
        """``tpComputeBlendVelocity``: the speeds of a parabolic blend (this, next, net)."""
        acc_this = seg.tangential_max_accel()
        acc_next = nxt.tangential_max_accel()
        v_reach_this = min(self._triangle_vel(seg), v_target_this)
        v_reach_next = min(self._triangle_vel(nxt), v_target_next)
        t_max_reachable = min(seg.target / v_reach_this, nxt.target / v_reach_next)
        t_max_blend = max(v_reach_this / acc_this, v_reach_next / acc_next)
        t_blend = min(t_max_reachable, t_max_blend)
        v_this = min(v_reach_this, t_blend * acc_this)
        v_next = min(v_reach_next, t_blend * acc_next)
        theta = bm.intersection_angle(seg.end_accel_unit(), nxt.start_accel_unit())
        cos_theta = math.cos(theta)
        if seg.tolerance > 0 and cos_theta > math.cos(math.pi / 2.0 - TP_MIN_ARC_ANGLE):
            tblend_vel = 2.0 * math.sqrt(acc_this * seg.tolerance / cos_theta)
            v_this = min(v_this, tblend_vel)
            v_next = min(v_next, tblend_vel)
        return v_this, v_next, math.sin(theta) * (v_this + v_next) / 2.0

    @staticmethod
    def _triangle_vel(seg: Segment) -> float:
        """``tpCalculateTriangleVel``."""
        length = seg.target if seg.finalized else seg.target / 2.0
        return find_v_peak(seg.tangential_max_accel(), length)

    def idle(self) -> bool:
        """No segment left."""
        return not self.queue

    def run_cycle(self) -> None:
        """``tpRunCycle``: one servo period."""
        if not self.queue:
            self.current_vel = 0.0
            return
        seg = self.queue[0]
        nxt = self.queue[1] if len(self.queue) > 1 else None
        self._activate(seg)
        seg.is_blending = False
        if nxt is not None:
            nxt.is_blending = False
        if seg.splitting:
            self._split_cycle(seg, nxt)
        else:
            self._regular_cycle(seg, nxt)
        if seg.remove:
            self._complete(seg)

    def _activate(self, seg: Segment) -> None:
        """``tpActivateSegment``: a short tangent feed segment gets a ramp instead of a trapezoid."""
        if seg.active:
            return
        cutoff_time = 1.0 / max(self.config.ramp_freq, TP_TIME_EPSILON)
        length = seg.target - seg.progress
        speed = seg.currentvel + min(seg.finalvel, self._real_target_vel(seg))
        segment_time = 2.0 * length / speed if speed > 0 else math.inf
        if segment_time < cutoff_time and not seg.traverse and seg.term_cond == TANGENT and length != 0:
            seg.accel_ramp = True
        seg.active = True
        seg.blending_next = False
        seg.on_final_decel = False

    def _complete(self, seg: Segment) -> None:
        """``tpCompleteSegment``."""
        self.queue.pop(0)

    def _move_to(self, seg: Segment, before: Vec) -> None:
        after = seg.position(seg.progress)
        self.current_pos = add(self.current_pos, sub(after, before))

    def _update_cycle(self, seg: Segment, nxt: Segment | None) -> None:
        """``tpUpdateCycle``."""
        before = seg.position(seg.progress)
        if not seg.blending_next:
            seg.vel_at_blend_start = seg.currentvel
        ramp = None
        if seg.accel_ramp and seg.term_cond == TANGENT:
            ramp = self._ramp_accel(seg, nxt)
        acc, vel_desired = ramp if ramp is not None else self._trapezoidal_accel(seg, nxt)
        self._dist_from_accel(seg, acc, vel_desired)
        self._check_end_condition(seg, nxt)
        self._move_to(seg, before)

    def _trapezoidal_accel(self, seg: Segment, nxt: Segment | None) -> tuple[float, float]:
        """``tpCalculateTrapezoidalAccel``."""
        tc_target_vel = self._real_target_vel(seg)
        tc_finalvel = self._real_final_vel(seg, nxt)
        dx = seg.target - seg.progress
        maxaccel = seg.tangential_max_accel()
        discr_term1 = tc_finalvel * tc_finalvel
        discr_term2 = maxaccel * (2.0 * dx - seg.currentvel * seg.cycle_time)
        tmp_adt = maxaccel * seg.cycle_time * 0.5
        discr_term3 = tmp_adt * tmp_adt
        discr = discr_term1 + discr_term2 + discr_term3
        maxnewvel = -tmp_adt
        if discr > discr_term3:
            maxnewvel += math.sqrt(discr)
        newvel = max(-tc_target_vel, min(maxnewvel, tc_target_vel))
        dt = max(seg.cycle_time, TP_TIME_EPSILON)
        maxnewaccel = (newvel - seg.currentvel) / dt
        return max(-maxaccel, min(maxnewaccel, maxaccel)), maxnewvel

    def _ramp_accel(self, seg: Segment, nxt: Segment | None) -> tuple[float, float] | None:
        """``tpCalculateRampAccel``."""
        dx = seg.target - seg.progress
        if not seg.blending_next:
            seg.vel_at_blend_start = seg.currentvel
        vel_final = self._real_final_vel(seg, nxt)
        if vel_final < TP_VEL_EPSILON:
            return None
        vel_avg = (seg.currentvel + vel_final) / 2.0
        dt = 1e-16
        if vel_avg > TP_VEL_EPSILON:
            dt = max(dx / vel_avg, 1e-16)
        acc_final = (vel_final - seg.currentvel) / dt
        acc_max = seg.tangential_max_accel()
        return max(-acc_max, min(acc_final, acc_max)), vel_final

    @staticmethod
    def _dist_from_accel(seg: Segment, acc: float, vel_desired: float) -> None:
        """``tcUpdateDistFromAccel``."""
        v_next = seg.currentvel + acc * seg.cycle_time
        if v_next < 0.0:
            v_next = 0.0
            if seg.target - seg.progress < seg.currentvel * seg.cycle_time:
                seg.progress = seg.target
        else:
            displacement = (v_next + seg.currentvel) * 0.5 * seg.cycle_time
            seg.progress += displacement
            seg.progress = min(max(seg.progress, 0.0), seg.target)
        seg.currentvel = v_next
        seg.on_final_decel = abs(vel_desired - seg.currentvel) < TP_VEL_EPSILON and acc < 0.0

    def _check_end_condition(self, seg: Segment, nxt: Segment | None) -> None:
        """``tpCheckEndCondition``: a segment that ends within this period is split."""
        cycle = self.config.cycle_time
        seg.cycle_time = cycle
        dx = seg.target - seg.progress
        if dx <= TP_POS_EPSILON:
            seg.progress = seg.target
            self._set_split(seg, 0.0, seg.currentvel)
            if seg.term_cond in (STOP, EXACT):
                seg.remove = True
            return
        if seg.term_cond in (STOP, EXACT):
            return
        v_f = self._real_final_vel(seg, nxt)
        v_avg = (seg.currentvel + v_f) / 2.0
        dt = TP_TIME_EPSILON / 2.0
        if v_avg > TP_VEL_EPSILON:
            dt = max(dt, dx / v_avg)
        elif dx > v_avg * cycle and dx > TP_POS_EPSILON:
            return
        a_f = (v_f - seg.currentvel) / dt
        a_max = seg.tangential_max_accel()
        a = max(-a_max, min(a_f, a_max))
        if a != a_f:
            disc = (seg.currentvel / a) ** 2 + 2.0 / a * dx
            if disc < 0:
                return
            if disc < TP_TIME_EPSILON * TP_TIME_EPSILON:
                dt = -seg.currentvel / a
            elif a > 0:
                dt = -seg.currentvel / a + math.sqrt(disc)
            else:
                dt = -seg.currentvel / a - math.sqrt(disc)
            v_f = seg.currentvel + dt * a
        if dt < TP_TIME_EPSILON:
            seg.progress = seg.target
            self._set_split(seg, 0.0, v_f)
        elif dt < cycle:
            self._set_split(seg, dt, v_f)

    @staticmethod
    def _set_split(seg: Segment, split_time: float, v_f: float) -> None:
        """``tcSetSplitCycle``."""
        if seg.splitting and split_time > 0.0:
            return
        seg.splitting = True
        seg.cycle_time = split_time
        seg.term_vel = v_f

    def _split_cycle(self, seg: Segment, nxt: Segment | None) -> None:
        """``tpHandleSplitCycle``: the rest of this segment and the start of the next."""
        if seg.remove:
            return
        before = seg.position(seg.progress)
        seg.progress = seg.target
        self._move_to(seg, before)
        seg.remove = True
        if nxt is None:
            return
        if seg.term_cond == TANGENT:
            nxt.cycle_time = self.config.cycle_time - seg.cycle_time
            nxt.currentvel = seg.term_vel
        next2 = self.queue[2] if len(self.queue) > 2 else None
        self._update_cycle(nxt, next2)

    def _regular_cycle(self, seg: Segment, nxt: Segment | None) -> None:
        """``tpHandleRegularCycle``: the trapezoid and, near the end, the parabolic blend."""
        if seg.remove:
            return
        seg.cycle_time = self.config.cycle_time
        self._update_cycle(seg, nxt)
        if nxt is None:
            seg.blend_vel = 0.0
            return
        v_this, v_next, _net = self._blend_velocity(seg, nxt, self._real_target_vel(seg), self._real_target_vel(nxt))
        seg.blend_vel = v_this
        nxt.blend_vel = v_next
        is_blending_next = seg.term_cond == PARABOLIC and seg.on_final_decel and seg.currentvel < seg.blend_vel
        seg.blending_next = seg.blending_next or is_blending_next
        if seg.blending_next:
            self._update_blend(seg, nxt)

    def _update_blend(self, seg: Segment, nxt: Segment) -> None:
        """``tpUpdateBlend``: the next segment starts while this one slows down."""
        save_vel = nxt.target_vel
        dv = seg.vel_at_blend_start - seg.currentvel
        vel_start = max(seg.vel_at_blend_start, TP_VEL_EPSILON)
        blend_progress = max(min(dv / vel_start, 1.0), 0.0)
        blend_scale = seg.vel_at_blend_start / seg.blend_vel
        nxt.target_vel = blend_progress * nxt.blend_vel * blend_scale
        nxt.is_blending = True
        self._update_cycle(nxt, None)
        nxt.target_vel = save_vel
