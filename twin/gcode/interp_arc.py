"""Arcs, G2 and G3, as LinuxCNC's ``interp_arc.cc`` reads them: the centre from I, J, K
(``arc_data_ijk``, with its radius checks) or from R (``arc_data_r``), P full turns, in the
plane selected (G17, G18, G19); under cutter compensation :mod:`twin.gcode.compensation`.
"""

from __future__ import annotations

import math

from twin.gcode.compensation import COMPENSATED_PLANES
from twin.gcode.interp_move import StraightMoves
from twin.gcode.interp_setup import MM_PER_INCH, PLANE_OF
from twin.gcode.modal import GCode
from twin.gcode.moves import CENTER_WORDS, PLANES, Move, MoveKind
from twin.gcode.words import BlockError

#: LinuxCNC's arc tolerances (interp_internal.hh) in program units: the R-arc and zero-radius
#: tolerance, and the centre-arc (spiral) tolerance, for inches and mm.
RADIUS_TOLERANCE = {True: 0.00005, False: 0.00005 * MM_PER_INCH}
CENTER_ARC_RADIUS_TOLERANCE = {True: 2 * 0.001 * math.sqrt(2), False: 2 * 0.01 * math.sqrt(2)}
#: A centre arc whose end radius differs from its start radius by more than this share, and by
#: more than the tolerance above, or by more than 100 times that tolerance, is refused.
SPIRAL_RELATIVE_TOLERANCE = 0.001
#: Most full turns an arc's P word may ask for (ours).
MAX_ARC_TURNS = 1000


class Arcs(StraightMoves):
    """G2 / G3 (see the module's description)."""

    def _arc(self, motion: int, words: dict[str, float]) -> None:
        move = self._arc_move(motion, words)
        if move is not None:
            self.out.append(move)

    def _arc_move(self, motion: int, words: dict[str, float]) -> Move | None:
        """G2 / G3: LinuxCNC's ``convert_arc2`` with ``arc_data_ijk`` / ``arc_data_r`` (under
        compensation ``convert_arc_comp1`` / ``comp2``, whose moves go to :attr:`out`: None)."""
        s = self.state
        comp = self.comp
        if comp.arc_not_allowed:
            raise BlockError("The move just after exiting cutter compensation mode must be straight, not an arc")
        if s.feed <= 0:
            raise BlockError(f"cannot do G{motion // 10} with zero feed rate (give F)")
        plane = PLANE_OF[s.plane]
        first, second, normal = PLANES[plane]
        i_word, j_word = CENTER_WORDS[plane]
        normal_word = "ijk"[normal]
        end = self._ends(words, machine=False)
        p = words.get("p", 1.0)
        turns = round(p)
        if abs(turns - p) > 0.001:
            raise BlockError("P value not an integer with G2 or G3")
        if not 1 <= turns <= MAX_ARC_TURNS:
            raise BlockError(f"P = {p:g}: the turns of an arc are a whole number from 1 to {MAX_ARC_TURNS}")
        a1, b1 = end[first], end[second]
        clockwise = motion == GCode.G_2
        tolerance = RADIUS_TOLERANCE[s.inch]
        spiral = CENTER_ARC_RADIUS_TOLERANCE[s.inch]
        if "r" in words:
            if i_word in words or j_word in words or normal_word in words:
                raise BlockError("give the arc's centre (I, J, K) or its radius R, not both")
            radius = words["r"]

            def center_of(a0: float, b0: float) -> tuple[float, float]:
                return arc_center_r(clockwise, a0=a0, b0=b0, a1=a1, b1=b1, radius=radius, tolerance=tolerance)

        else:
            if normal_word in words:
                raise BlockError(
                    f"{normal_word.upper()} = {words[normal_word]:g}: {normal_word.upper()} word given for an arc in "
                    f"the {plane.upper()} plane (G{s.plane // 10}: its centre is {i_word.upper()} and {j_word.upper()})"
                )
            if i_word not in words and j_word not in words:
                raise BlockError(
                    f"R, I, J and K words all missing for the arc (in this plane: {i_word.upper()}, "
                    f"{j_word.upper()} or R)"
                )
            ci, cj = words.get(i_word, 0.0), words.get(j_word, 0.0)

            def center_of(a0: float, b0: float) -> tuple[float, float]:
                center = (a0 + ci, b0 + cj) if s.arc_incremental else (ci, cj)
                check_arc_radii(center, a0=a0, b0=b0, a1=a1, b1=b1, tolerance=tolerance, spiral=spiral)
                return center

        signed_turns = -turns if clockwise else turns
        if comp.active and plane in COMPENSATED_PLANES:
            radius_word = words.get("r")
            s.position = comp.arc(
                motion,
                end,
                position=s.position,
                plane=plane,
                turns=signed_turns,
                radius_word=radius_word,
                center_of=center_of,
                spiral_tolerance=spiral,
                make=self._compensated_move,
            )
            return None
        center = center_of(s.position[first], s.position[second])
        scale = s.mm_per_unit
        move = self._move(
            MoveKind.ARC,
            end,
            feed_mm_per_min=s.feed * scale,
            plane=plane,
            center_mm=(center[0] * scale, center[1] * scale),
            turns=signed_turns,
        )
        s.position = end
        return move


def arc_center_r(clockwise: bool, *, a0: float, b0: float, a1: float, b1: float, radius: float, tolerance: float):
    """LinuxCNC's ``arc_data_r``: the centre of an R arc (negative R: more than half a circle)."""
    if a0 == a1 and b0 == b1:
        raise BlockError("current point same as end point of arc (an R arc cannot be a full circle: use I, J, K)")
    if radius == 0:
        raise BlockError("R = 0: zero-radius arc")
    abs_radius = abs(radius)
    mid_a, mid_b = (a1 + a0) / 2.0, (b1 + b0) / 2.0
    half = math.hypot(mid_a - a1, mid_b - b1)
    if half - abs_radius > tolerance:
        raise BlockError(f"arc radius too small to reach end point: R = {radius:g}, half the chord {half:.4f}")
    if half / abs_radius > 1 - 1e-12:
        half = abs_radius
    if (clockwise and radius > 0) or (not clockwise and radius < 0):
        theta = math.atan2(b1 - b0, a1 - a0) - math.pi / 2
    else:
        theta = math.atan2(b1 - b0, a1 - a0) + math.pi / 2
    offset = abs_radius * math.cos(math.asin(half / abs_radius))
    return (mid_a + offset * math.cos(theta), mid_b + offset * math.sin(theta))


def check_arc_radii(center, *, a0: float, b0: float, a1: float, b1: float, tolerance: float, spiral: float) -> None:
    """LinuxCNC's ``arc_data_ijk`` checks: no zero radius; the end's radius within the spiral
    tolerance of the start's (absolute *and* relative, or 100 times the absolute alone)."""
    r1 = math.hypot(center[0] - a0, center[1] - b0)
    r2 = math.hypot(center[0] - a1, center[1] - b1)
    if r1 < tolerance or r2 < tolerance:
        raise BlockError(f"zero-radius arc: r start {r1:.4f}, r end {r2:.4f}")
    abs_err = abs(r1 - r2)
    rel_err = abs_err / max(r1, r2)
    if abs_err > spiral * 100.0 or (rel_err > SPIRAL_RELATIVE_TOLERANCE and abs_err > spiral):
        raise BlockError(
            f"radius to end of arc differs from radius to start: r start {r1:.4f}, r end {r2:.4f}, "
            f"difference {abs_err:.4g} ({rel_err * 100:.4f} %; LinuxCNC's limits: over {spiral:.4g} and over "
            f"{SPIRAL_RELATIVE_TOLERANCE * 100:g} %, or over {spiral * 100:.4g})"
        )
