"""Where a block's move ends and the move it makes (LinuxCNC's ``interp_find.cc``:
``find_ends``; polar coordinates; ``convert_straight``'s G0 and G1): the :class:`Move` record
built from the modal state, straight moves and the moves cutter compensation holds.
"""

from __future__ import annotations

import math

from twin.gcode.interp_setup import AXES, PLANE_OF, InterpreterSetup
from twin.gcode.moves import Move, MoveKind
from twin.gcode.words import BlockError

#: Largest coordinate of any move (mm; ours: a kilometre, far beyond any machine).
MAX_COORDINATE_MM = 1e6


class StraightMoves(InterpreterSetup):
    """End points, the move record and G0 / G1 (see the module's description)."""

    def _ends(self, words: dict[str, float], machine: bool) -> list[float]:
        """LinuxCNC's ``find_ends``: the end point (work coordinates, program units)."""
        s = self.state
        comp = self.comp
        x, y, z = comp.program if comp.side is not None and not comp.first and not machine else s.position
        if not machine and "@" not in words and "^" not in words:
            if s.incremental:
                return [x + words.get("x", 0.0), y + words.get("y", 0.0), z + words.get("z", 0.0)]
            return [words.get("x", x), words.get("y", y), words.get("z", z)]
        end = [x, y, z]
        if machine:
            if "@" in words or "^" in words:
                raise BlockError("cannot use polar coordinates with G53")
            offset = self._machine_offset()
            for i, k in enumerate(AXES):
                if k in words:
                    end[i] = words[k] - offset[i]
            return end
        for i, k in enumerate(AXES):
            if k in words:
                end[i] = end[i] + words[k] if s.incremental else words[k]
        if "@" in words or "^" in words:
            end[0], end[1] = polar_end(
                end[0], end[1], radius=words.get("@"), angle=words.get("^"), incremental=s.incremental
            )
        return end

    def _move(
        self,
        kind: MoveKind,
        end: list[float],
        *,
        feed_mm_per_min: float = 0.0,
        plane: str = "",
        center_mm: tuple[float, float] = (0.0, 0.0),
        turns: int = 0,
        dwell_s: float = 0.0,
    ) -> Move:
        """A move from the current point to ``end`` (program units) with the modal state."""
        s = self.state
        scale = s.mm_per_unit
        x, y, z = s.position
        x1, y1, z1 = end
        end_mm = (x1 * scale, y1 * scale, z1 * scale)
        start_mm = (x * scale, y * scale, z * scale)
        if self.comp.tool_mm is not None:  # just after G40: the tool is not at the current point
            if kind == MoveKind.DWELL:
                start_mm = end_mm = self.comp.tool_mm
            else:
                start_mm = self.comp.start_mm(start_mm)
        ox, oy, oz = offset_mm = self._offset_mm
        if not (
            abs(end_mm[0] + ox) <= MAX_COORDINATE_MM
            and abs(end_mm[1] + oy) <= MAX_COORDINATE_MM
            and abs(end_mm[2] + oz) <= MAX_COORDINATE_MM
        ):
            raise BlockError(
                f"the move ends at {[round(v + o, 6) for v, o in zip(end_mm, offset_mm)]} mm "
                f"(machine coordinates), beyond {MAX_COORDINATE_MM:g} mm"
            )
        return Move(
            line=self.lines_read,
            kind=kind,
            start_mm=start_mm,
            end_mm=end_mm,
            offset_mm=offset_mm,
            feed_mm_per_min=feed_mm_per_min,
            spindle_rpm=s.spindle_rpm,
            spindle=s.spindle,
            plane=plane,
            center_mm=center_mm,
            turns=turns,
            dwell_s=dwell_s,
            tolerance_mm=None if s.tolerance is None else s.tolerance * scale,
            text=self.text,
            tool=s.tool_in_spindle,
            coolant=s.coolant,
            path_mode=s.path_mode,
        )

    def _linear(self, kind: MoveKind, end: list[float]) -> None:
        """G0 (``MoveKind.RAPID``) or G1 (``MoveKind.FEED``) to ``end``, into :attr:`out`."""
        self.out.append(self._linear_move(kind == MoveKind.FEED, end))

    def _compensated_move(self, kind: MoveKind, end: list[float], center: tuple[float, float], turns: int) -> Move:
        """A move compensation holds (its start and end are set when it is released)."""
        s = self.state
        if kind == MoveKind.RAPID:
            return self._move(MoveKind.RAPID, end)
        scale = s.mm_per_unit
        if kind == MoveKind.FEED:
            return self._move(MoveKind.FEED, end, feed_mm_per_min=s.feed * scale)
        center_mm = (center[0] * scale, center[1] * scale)
        return self._move(
            MoveKind.ARC, end, feed_mm_per_min=s.feed * scale, plane=PLANE_OF[s.plane], center_mm=center_mm, turns=turns
        )

    def _linear_move(self, feeding: bool, end: list[float]) -> Move:
        """G1 (``feeding``) or G0 to ``end`` (program units), made the current point."""
        s = self.state
        if feeding and s.feed <= 0:
            raise BlockError("cannot do G1 with zero feed rate (give F)")
        move = (
            self._move(MoveKind.FEED, end, feed_mm_per_min=s.feed * s.mm_per_unit)
            if feeding
            else self._move(MoveKind.RAPID, end)
        )
        s.position = end
        return move


def polar_end(x: float, y: float, *, radius: float | None, angle: float | None, incremental: bool):
    """LinuxCNC's polar coordinates (``@`` radius, ``^`` angle in degrees, G17): the end point
    from the current one ``(x, y)``; incremental adds to the current radius and angle."""
    if incremental:
        if x == 0 and y == 0:
            raise BlockError("incremental motion with polar coordinates is indeterminate when at the origin")
        if radius is not None:
            theta, r = math.atan2(y, x), math.hypot(y, x) + radius
            x, y = r * math.cos(theta), r * math.sin(theta)
        if angle is not None:
            theta, r = math.atan2(y, x) + math.radians(angle), math.hypot(y, x)
            x, y = r * math.cos(theta), r * math.sin(theta)
        return x, y
    if radius is not None and angle is not None:
        return radius * math.cos(math.radians(angle)), radius * math.sin(math.radians(angle))
    if radius is not None:
        if x == 0 and y == 0:
            raise BlockError("must specify angle in polar coordinate if at the origin")
        theta = math.atan2(y, x)
        return radius * math.cos(theta), radius * math.sin(theta)
    assert angle is not None
    r = math.hypot(y, x)
    return r * math.cos(math.radians(angle)), r * math.sin(math.radians(angle))
