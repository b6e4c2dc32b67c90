"""Cutter radius compensation (G40, G41, G42, G41.1, G42.1) as LinuxCNC 2.9's interpreter does
it: ``convert_straight_comp1`` / ``comp2``, ``convert_arc_comp1`` / ``comp2`` and the queue of
``interp_queue.cc`` (``move_endpoint_and_flush``), ported one for one.

With compensation on, the tool's centre runs one tool radius to the left (G41) or right (G42) of
the programmed path, in the XY plane (G17) or the XZ plane (G18). The first move after G41/G42
is the entry: it ends one radius beside the programmed end point, square to the move. After it,
each move is held back until the next one is known: at an inside corner the held move's end is
pulled back to where the two offset paths meet (an arc's end onto the circle it runs on), at an
outside corner an arc about the programmed corner is added between them (a G0 goes straight
there instead). G40 releases the held moves; the next move starts from the programmed point.

Everything here is in the program's units and in the plane's coordinates ``(a, b, c)``: (x, y,
z) in G17, (z, x, y) in G18 (LinuxCNC's ``comp_get_current``). The moves released go, as
:class:`~twin.gcode.reader.Move` s in mm, to the reader's list of moves of the block.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from twin.gcode.modal import GCode
from twin.gcode.moves import MoveKind
from twin.gcode.words import BlockError

#: The plane's coordinates (a, b, c) as indices of x, y, z: the two planes compensation works in.
COMPENSATED_PLANES = {"xy": (0, 1, 2), "zx": (2, 0, 1)}
#: LinuxCNC's TOLERANCE_CONCAVE_CORNER (rad): a corner turning less than this is straight on.
TOLERANCE_CONCAVE_CORNER = 0.05
#: LinuxCNC's TOLERANCE_EQUAL: a cosine below this is zero.
TOLERANCE_EQUAL = 1e-6
#: How much longer than programmed an arc's sweep may become when its end is moved to an inside
#: corner (LinuxCNC's 0.001 in, 0.0254 mm: the length of an arc of radius 1 unit, rad).
ARC_SWEEP_SLACK = {True: 0.001, False: 0.0254}
#: Largest difference of a moved arc end's radius from its start's (program units; LinuxCNC's).
ARC_END_RADIUS_SLACK = 0.01
#: Most calls held at once (ours: moves along the normal axis and dwells are held until the next
#: move in the plane; LinuxCNC holds any number).
MAX_HELD = 10_000

#: A move the reader makes from its modal state: (kind, end [x, y, z], centre, turns) to a Move.
MoveMaker = Callable[[MoveKind, list[float], tuple[float, float], int], Any]


@dataclass
class _Queued:
    """One held call (LinuxCNC's ``queued_canon``): a move with its end (a, b, c), a straight's
    programmed direction (a, b), an arc's centre (a, b), turns and programmed sweep (rad); or a
    dwell, which follows the move before it."""

    move: Any
    end: list[float]
    direction: tuple[float, float] = (0.0, 0.0)
    center: tuple[float, float] = (0.0, 0.0)
    turn: int = 0
    original_turns: float = 0.0


def find_turn(a1: float, b1: float, ca: float, cb: float, *, turn: int, a2: float, b2: float) -> float:
    """LinuxCNC's ``find_turn``: the angle an arc sweeps from (a1, b1) to (a2, b2) about
    (ca, cb), ``turn`` full or partial circles (> 0 counter-clockwise), rad (negative: clockwise)."""
    if turn == 0:
        return 0.0
    alpha = math.atan2(b1 - cb, a1 - ca)
    beta = math.atan2(b2 - cb, a2 - ca)
    if turn > 0:
        if beta <= alpha:
            beta += 2 * math.pi
        return beta - alpha + (turn - 1) * 2 * math.pi
    if alpha <= beta:
        alpha += 2 * math.pi
    return beta - alpha + (turn + 1) * 2 * math.pi


class CutterCompensation:
    """The compensation state of one program being read, and its held moves.

    Parameters
    ----------
    out : list
        Where released moves go (the reader's moves of the block being run).
    """

    def __init__(self, out: list):
        self.out = out
        self.side: str | None = None  # "left" (G41), "right" (G42), None (G40)
        self.radius = 0.0  # program units, >= 0
        self.orientation = 0  # a lathe tool's orientation (G41.1 L in G18); 0 a mill's
        self.first = True  # the next move is the entry move
        self.program = [0.0, 0.0, 0.0]  # the programmed point, x y z (LinuxCNC's program_x...)
        self.queue: list[_Queued] = []
        self.stale: _Queued | None = None  # LinuxCNC reads the emptied queue's first call
        self.endpoint = (0.0, 0.0)
        self.endpoint_valid = False
        self.arc_not_allowed = False  # the move after G40 must be straight
        self.tool_mm: tuple[float, float, float] | None = None  # where the tool is after G40 (mm)
        self.last_mm = (0.0, 0.0, 0.0)  # where the last released move ends (mm)
        self.mm_per_unit = 1.0
        self.inch = False
        #: An F word was read while moves were held: LinuxCNC sends its number on when they are
        #: released, in the units then in force (a G20/G21 between keeps the number, not the speed),
        #: for the held moves from ``feed_held_at`` on.
        self.feed_held = False
        self.feed_held_at = 0

    @property
    def engaged(self) -> bool:
        """Compensation is on, or its exit is not done (the reader's fast path steps aside)."""
        return self.side is not None or self.arc_not_allowed or self.tool_mm is not None

    @property
    def active(self) -> bool:
        """Moves are offset: compensation on with a radius above 0."""
        return self.side is not None and self.radius > 0.0

    # --- G40 / G41 / G42 -------------------------------------------------------------------

    def turn_on(self, code: int, words: dict[str, float], plane: str, diameter_of: Callable[[int | None], float]):
        """LinuxCNC's ``convert_cutter_compensation_on``: G41 / G42 (``code`` G_41 / G_42) with
        the D word's tool (the tool in the spindle without D; ``diameter_of`` gives a tool's
        diameter, program units), G41.1 / G42.1 with the diameter as D and L the orientation
        (G18 only). A negative diameter switches the side."""
        if plane not in COMPENSATED_PLANES:
            raise BlockError("Cutter radius compensation allowed only in XY, XZ planes")
        if self.side is not None:
            raise BlockError("Cannot turn cutter radius comp on when on")
        side = "left" if code in (GCode.G_41, GCode.G_41_1) else "right"
        if code in (GCode.G_41_1, GCode.G_42_1):
            if "d" not in words:
                raise BlockError(f"G{code // 10}.1 with no D word (the tool's diameter)")
            radius = words["d"] / 2
            orientation = 0
            if "l" in words:
                if plane != "zx":
                    raise BlockError(f"G{code // 10}.1 with L word, but plane is not G18")
                orientation = int(words["l"])
        else:
            tool = None
            if "d" in words:
                tool = int(words["d"] + 0.5)  # LinuxCNC's is_near_int: a negative D is no whole number
                if abs(words["d"] - tool) >= 0.0001:
                    raise BlockError(f"G{code // 10} requires D word to be a whole number")
            radius = diameter_of(tool) / 2
            orientation = 0
        if radius < 0:
            radius, side = -radius, "right" if side == "left" else "left"
        self.radius, self.orientation, self.side = radius, orientation, side

    def turn_off(self, position: list[float], plane: str) -> list[float]:
        """LinuxCNC's ``convert_cutter_compensation_off`` (G40): the held moves released; the
        new current point, the programmed point where compensation moved the tool."""
        if self.active and not self.first:
            a, b, _ = _in_plane(position, plane)
            self._move_endpoint_and_flush(a, b, plane)
            self._dequeue(plane)
            self.tool_mm = self.last_mm
            position = list(self.program)
            self.arc_not_allowed = True
        self.side, self.first = None, True
        return position

    def flush(self, position: list[float], plane: str) -> None:
        """M0, M1, M2, M30, M60 (LinuxCNC's ``convert_stop``): every held move released."""
        if plane in COMPENSATED_PLANES:
            a, b, _ = _in_plane(position, plane)
            self._move_endpoint_and_flush(a, b, plane)
        self._dequeue(plane)

    def hold(self, move: Any) -> bool:
        """A dwell: held behind the held moves (True), or made at once where none is held."""
        if not self.queue:
            return False
        self._check_held()
        self.queue.append(_Queued(move, []))
        return True

    def hold_feed(self) -> None:
        """An F word read while moves are held (sent on when they are released)."""
        if not self.feed_held:
            self.feed_held, self.feed_held_at = True, len(self.queue)

    def units(self, inch: bool, factor: float, mm_per_unit: float) -> None:
        """G20 / G21 with compensation on (LinuxCNC's ``qc_scale``): held moves, the programmed
        point and the radius in the new units; the held moves after a held F word at its number
        in the new units."""
        if self.feed_held:
            for q in self.queue[self.feed_held_at :]:
                q.move = q.move._replace(feed_mm_per_min=q.move.feed_mm_per_min * mm_per_unit / self.mm_per_unit)
        self.inch, self.mm_per_unit = inch, mm_per_unit
        self.radius *= factor
        self.program = [v * factor for v in self.program]
        for q in self.queue:  # LinuxCNC scales the corner point once for each held call
            self.endpoint = (self.endpoint[0] * factor, self.endpoint[1] * factor)
            q.end = [v * factor for v in q.end]
            q.center = (q.center[0] * factor, q.center[1] * factor)

    def start_mm(self, start: tuple[float, float, float]) -> tuple[float, float, float]:
        """Where the reader's next move starts: the tool's point after G40, else ``start``."""
        if self.tool_mm is None:
            return start
        start, self.tool_mm = self.tool_mm, None
        return start

    # --- straight moves ---------------------------------------------------------------------

    def straight(
        self, kind: MoveKind, end: list[float], *, position: list[float], plane: str, make: MoveMaker
    ) -> list[float]:
        """G0 / G1 (``kind`` RAPID / FEED) to the programmed ``end`` [x, y, z] from the
        current point ``position``; the new current point (the compensated end)."""
        p = _in_plane(end, plane)
        c = _in_plane(position, plane)
        if self.first:
            new = self._straight_entry(kind, p, c, position=position, make=make, plane=plane)
        else:
            new = self._straight_next(kind, p, c, make=make, plane=plane)
        self.program = list(end)
        return _from_plane(new, plane)

    def _straight_entry(self, kind, p, c, *, position, make, plane) -> list[float]:
        """LinuxCNC's ``convert_straight_comp1``: the entry move."""
        pa, pb, pc = p
        ca, cb, _ = c
        radius = self.radius
        if math.hypot(pa - ca, pb - cb) <= radius:
            raise BlockError("Length of cutter compensation entry move is not greater than the tool radius")
        alpha = math.atan2(pb - cb, pa - ca) + (math.pi / 2 if self.side == "left" else -math.pi / 2)
        ea, eb = pa + radius * math.cos(alpha), pb + radius * math.sin(alpha)
        self._begin(position)
        self._set_endpoint(ca, cb)
        self._enqueue(kind, [ea, eb, pc], make=make, plane=plane, direction=(math.cos(alpha), math.sin(alpha)))
        self.first = False
        return [ea, eb, pc]

    def _straight_next(self, kind, p, c, *, make, plane) -> list[float]:
        """LinuxCNC's ``convert_straight_comp2``: a move after the entry, its corner with the
        move before."""
        pa, pb, pc = p
        ca, cb, cc = c
        opa, opb, _ = _in_plane(self.program, plane)
        if pa == opa and pb == opb:  # no motion in the plane: the tool stays beside the point
            self._enqueue(kind, [ca, cb, pc], make=make, plane=plane, direction=(0.0, 0.0))
            return [ca, cb, pc]
        radius = self.radius
        small = TOLERANCE_CONCAVE_CORNER
        theta = math.atan2(cb - opb, ca - opa)
        alpha = math.atan2(pb - opb, pa - opa)
        if self.side == "left":
            if theta < alpha:
                theta += 2 * math.pi
            beta = theta - alpha - math.pi / 2
            gamma = math.pi / 2
        else:
            if alpha < theta:
                alpha += 2 * math.pi
            beta = alpha - theta - math.pi / 2
            gamma = -math.pi / 2
        ea, eb = pa + radius * math.cos(alpha + gamma), pb + radius * math.sin(alpha + gamma)
        mid_a, mid_b = opa + radius * math.cos(alpha + gamma), opb + radius * math.sin(alpha + gamma)
        concave = beta < -small or beta > math.pi + small
        if not concave and beta > math.pi - small and self.queue and self.queue[0].move.kind == MoveKind.ARC:
            # "h" shape: over a tangent arc onto the line, stay on the arc's outer side
            turn = self.queue[0].turn
            concave = (self.side == "right" and turn > 0) or (self.side == "left" and turn < 0)
        if not concave and beta > small:  # outside corner: an arc about it (a G0 goes straight)
            self._move_endpoint_and_flush(ca, cb, plane)
            if kind == MoveKind.FEED:
                turn = -1 if self.side == "left" else 1
                self._enqueue(MoveKind.ARC, [mid_a, mid_b, cc], make=make, plane=plane, center=(opa, opb), turn=turn)
            else:
                self._enqueue(MoveKind.RAPID, [mid_a, mid_b, cc], make=make, plane=plane)
            self._dequeue(plane)
            self._set_endpoint(mid_a, mid_b)
        elif concave:
            front = self._front()
            if front is None or front.move.kind != MoveKind.ARC:  # line to line: pull back along the last
                halfcorner = (beta + math.pi) / 2
                if halfcorner == 0.0:
                    raise BlockError("Zero degree inside corner is invalid for cutter compensation")
                retreat = radius / math.tan(halfcorner)
                mid_a = ca + retreat * math.cos(theta + gamma)
                mid_b = cb + retreat * math.sin(theta + gamma)
                self._move_endpoint_and_flush(mid_a, mid_b, plane)
            else:  # arc to line: the arc's end where the line's offset meets its circle
                self._move_endpoint_and_flush(*self._arc_to_line(front, pa=pa, pb=pb, opa=opa, opb=opb), plane)
        else:  # straight on (collinear, or a tangent arc into the line)
            self._dequeue(plane)
            self._set_endpoint(ca, cb)
        self._enqueue(kind, [ea, eb, pc], make=make, plane=plane, direction=(pa - opa, pb - opb))
        return [ea, eb, pc]

    def _arc_to_line(self, prev: _Queued, *, pa, pb, opa, opb) -> tuple[float, float]:
        """Where the (compensated) arc ``prev`` meets the next line's offset."""
        radius = self.radius
        pca, pcb = prev.center
        oldrad = math.hypot(pcb - prev.end[1], pca - prev.end[0])
        base_dir = math.atan2(pb - opb, pa - opa)
        theta = base_dir + math.pi / 2 if prev.turn > 0 else base_dir - math.pi / 2
        phi = math.atan2(pcb - opb, pca - opa)
        inside = _tool_inside_arc(self.side, prev.turn)
        oldrad_uncomp = oldrad + radius if inside else oldrad - radius
        d = oldrad_uncomp * math.cos(theta - phi)  # old centre's distance square to the line
        message = "Arc to straight motion makes a corner the compensated tool can't fit in without gouging"
        ratio = ((d - radius) if inside else (d + radius)) / oldrad
        if ratio > 1.0 or ratio < -1.0:
            raise BlockError(message)
        if inside:
            angle = (-math.acos(ratio) if prev.turn > 0 else math.acos(ratio)) + theta + math.pi
        else:
            angle = (math.acos(ratio) if prev.turn > 0 else -math.acos(ratio)) + theta + math.pi
        return pca + oldrad * math.cos(angle), pcb + oldrad * math.sin(angle)

    # --- arcs -------------------------------------------------------------------------------

    def arc(
        self,
        motion: int,
        end: list[float],
        *,
        position: list[float],
        plane: str,
        turns: int,
        radius_word: float | None,
        center_of: Callable[[float, float], tuple[float, float]],
        spiral_tolerance: float,
        make: MoveMaker,
    ) -> list[float]:
        """G2 / G3 (``motion`` 20 / 30) to the programmed ``end`` [x, y, z], ``turns`` (> 0
        counter-clockwise); ``center_of(a0, b0)`` is the programmed arc's centre from a start
        (the reader's R or I J K rules), ``radius_word`` the R word (None: I J K)."""
        p = _in_plane(end, plane)
        c = _in_plane(position, plane)
        if self.first:
            new = self._arc_entry(
                motion,
                p,
                c,
                position=position,
                plane=plane,
                turns=turns,
                radius_word=radius_word,
                center_of=center_of,
                spiral_tolerance=spiral_tolerance,
                make=make,
            )
        else:
            new = self._arc_next(motion, p, c, plane=plane, turns=turns, center_of=center_of, make=make)
        self.program = list(end)
        return _from_plane(new, plane)

    def _radius_check(self, motion: int, arc_radius: float) -> None:
        inside = (self.side == "left" and motion == 30) or (self.side == "right" and motion == 20)
        if inside and arc_radius <= self.radius:
            raise BlockError("Tool radius not less than arc radius with comp")

    def _arc_entry(self, motion, p, c, *, position, plane, turns, radius_word, center_of, spiral_tolerance, make):
        """LinuxCNC's ``convert_arc_comp1``: an arc as the entry move, tangent to the tool where
        it stands."""
        pa, pb, pc = p
        ca, cb, cc = c
        radius = self.radius
        if math.hypot(pa - ca, pb - cb) <= radius:
            raise BlockError("Radius of cutter compensation entry arc is not greater than the tool radius")
        if radius_word is not None:
            self._radius_check(motion, abs(radius_word))
            center_a, center_b = center_of(ca, cb)
        else:
            center_a, center_b = center_of(ca, cb)
            self._radius_check(motion, math.hypot(center_a - ca, center_b - cb))
        turn = turns
        if _tool_inside_arc(self.side, turn):
            gamma = math.atan2(center_b - pb, center_a - pa)
        else:
            gamma = math.atan2(pb - center_b, pa - center_a)
        self.first = False
        ea, eb = pa + radius * math.cos(gamma), pb + radius * math.sin(gamma)
        b_len = math.hypot(cb - eb, ca - ea) / 2.0
        ab_angle = math.atan2(center_b - eb, center_a - ea)
        a_angle = math.atan2(cb - eb, ca - ea) - ab_angle
        if abs(math.cos(a_angle)) < TOLERANCE_EQUAL:
            raise BlockError("Tool radius not less than arc radius with comp")
        c_len = b_len / math.cos(a_angle)
        center_a, center_b = ea + c_len * math.cos(ab_angle), eb + c_len * math.sin(ab_angle)
        if abs(math.hypot(center_a - ea, center_b - eb) - math.hypot(center_a - ca, center_b - cb)) > spiral_tolerance:
            raise BlockError("Bug in tool radius comp")
        self._begin(position)
        if self.orientation not in (0, 9):  # a lathe tool: its origin moved first
            self._enqueue(MoveKind.FEED, [ca, cb, cc], make=make, plane=plane)
            self._set_endpoint(ca, cb)
        sweep = find_turn(ca, cb, center_a, center_b, turn=turn, a2=ea, b2=eb)
        self._enqueue(
            MoveKind.ARC, [ea, eb, pc], make=make, plane=plane, center=(center_a, center_b), turn=turn, sweep=sweep
        )
        return [ea, eb, pc]

    def _arc_next(self, motion, p, c, *, plane, turns, center_of, make):
        """LinuxCNC's ``convert_arc_comp2``: an arc after the entry, its corner with the move
        before."""
        pa, pb, pc = p
        ca, cb, cc = c
        opa, opb, _ = _in_plane(self.program, plane)
        center_a, center_b = center_of(opa, opb)
        turn = turns
        side, radius = self.side, self.radius
        small = TOLERANCE_CONCAVE_CORNER
        arc_radius = math.hypot(center_a - pa, center_b - pb)
        theta = math.atan2(cb - opb, ca - opa)
        theta = theta - math.pi / 2 if side == "left" else theta + math.pi / 2
        delta = math.atan2(center_b - opb, center_a - opa)
        alpha = delta - math.pi / 2 if motion == 30 else delta + math.pi / 2
        beta = theta - alpha if side == "left" else alpha - theta
        if beta > 1.5 * math.pi:
            beta -= 2 * math.pi
        elif beta < -math.pi / 2:
            beta += 2 * math.pi
        if (side == "left" and motion == 30) or (side == "right" and motion == 20):
            gamma = math.atan2(center_b - pb, center_a - pa)
            if arc_radius <= radius:
                raise BlockError("Tool radius not less than arc radius with comp")
        else:
            gamma = math.atan2(pb - center_b, pa - center_a)
            delta += math.pi
        new_a, new_b = pa + radius * math.cos(gamma), pb + radius * math.sin(gamma)
        inside = _tool_inside_arc(side, turn)
        sweep = find_turn(opa, opb, center_a, center_b, turn=turn, a2=pa, b2=pb)
        if beta < -small or beta > math.pi + small or (abs(beta - math.pi) < small and not inside):
            front = self._front()
            if front is None or front.move.kind != MoveKind.ARC:  # line to arc
                self._move_endpoint_and_flush(
                    *self._line_to_arc(
                        beta,
                        theta,
                        arc_radius=arc_radius,
                        inside=inside,
                        turn=turn,
                        center_a=center_a,
                        center_b=center_b,
                    ),
                    plane,
                )
            else:  # arc to arc
                self._move_endpoint_and_flush(
                    *self._arc_to_arc(front, center_a=center_a, center_b=center_b, arc_radius=arc_radius, turn=turn),
                    plane,
                )
        elif beta > small:  # outside corner: an arc about it first
            mid_a, mid_b = opa + radius * math.cos(delta), opb + radius * math.sin(delta)
            self._dequeue(plane)
            corner_turn = -1 if side == "left" else 1
            self._enqueue(MoveKind.ARC, [mid_a, mid_b, cc], make=make, plane=plane, center=(opa, opb), turn=corner_turn)
            self._dequeue(plane)
            self._set_endpoint(mid_a, mid_b)
        else:  # straight on
            self._dequeue(plane)
            self._set_endpoint(ca, cb)
        self._enqueue(
            MoveKind.ARC,
            [new_a, new_b, pc],
            make=make,
            plane=plane,
            center=(center_a, center_b),
            turn=turn,
            sweep=sweep,
        )
        return [new_a, new_b, pc]

    def _line_to_arc(self, beta, theta, *, arc_radius, inside, turn, center_a, center_b) -> tuple[float, float]:
        """Where the held line's end meets the next arc's offset circle (an inside corner)."""
        radius = self.radius
        cy = arc_radius * math.sin(beta - math.pi / 2)
        message = "Arc move in concave corner cannot be reached by the tool without gouging"
        if inside:
            dist = arc_radius - radius
            ratio = (cy + radius) / dist
            if ratio > 1.0 or ratio < -1.0:
                raise BlockError(message)
            angle = theta + math.asin(ratio) if turn > 0 else theta - math.asin(ratio)
        else:
            dist = arc_radius + radius
            ratio = (cy - radius) / dist
            if ratio > 1.0 or ratio < -1.0:
                raise BlockError(message)
            angle = theta + math.pi - math.asin(ratio) if turn > 0 else theta + math.pi + math.asin(ratio)
        return center_a + dist * math.cos(angle), center_b + dist * math.sin(angle)

    def _arc_to_arc(self, prev: _Queued, *, center_a, center_b, arc_radius, turn) -> tuple[float, float]:
        """Where the held arc's end meets the next arc's offset circle (an inside corner)."""
        pca, pcb = prev.center
        oldrad = math.hypot(pcb - prev.end[1], pca - prev.end[0])
        newrad = arc_radius - self.radius if _tool_inside_arc(self.side, turn) else arc_radius + self.radius
        arc_cc = math.hypot(pcb - center_b, pca - center_a)
        if oldrad == 0 or arc_cc == 0:
            raise BlockError("Arc to arc motion is invalid because the arcs have the same center")
        a = (oldrad**2 + arc_cc**2 - newrad**2) / (2 * oldrad * arc_cc)
        if a > 1.0 or a < -1.0:
            raise BlockError("Arc to arc motion makes a corner the compensated tool can't fit in without gouging")
        pullback = math.acos(a)
        cc_dir = math.atan2(center_b - pcb, center_a - pca)
        if _tool_inside_arc(self.side, prev.turn):
            direction = cc_dir + pullback if turn > 0 else cc_dir - pullback
        else:
            direction = cc_dir - pullback if turn > 0 else cc_dir + pullback
        return pca + oldrad * math.cos(direction), pcb + oldrad * math.sin(direction)

    # --- the queue (interp_queue.cc) --------------------------------------------------------

    def _begin(self, position: list[float]) -> None:
        """The entry move starts where the tool is (after a G40: where it was left)."""
        s = self.mm_per_unit
        self.last_mm = self.start_mm((position[0] * s, position[1] * s, position[2] * s))

    def _front(self) -> _Queued | None:
        return self.queue[0] if self.queue else self.stale

    def _set_endpoint(self, a: float, b: float) -> None:
        self.endpoint, self.endpoint_valid = (a, b), True

    def _enqueue(self, kind, end, *, make, plane, direction=(0.0, 0.0), center=(0.0, 0.0), turn=0, sweep=0.0) -> None:
        self._check_held()
        xyz = _from_plane(end, plane)
        move = make(kind, xyz, center, turn)
        self.queue.append(_Queued(move, list(end), direction, center, turn, sweep))

    def _check_held(self) -> None:
        if len(self.queue) >= MAX_HELD:
            raise BlockError(
                f"more than {MAX_HELD} moves and dwells held by cutter compensation (none moves in its plane)"
            )

    def _move_endpoint_and_flush(self, a: float, b: float, plane: str) -> None:
        """Every held move's end moved to (a, b), each checked not to turn back, and released."""
        if not self.queue:
            return
        ea, eb = self.endpoint
        for q in self.queue:
            kind = q.move.kind
            if kind == MoveKind.ARC:
                ca, cb = q.center
                r1 = math.hypot(q.end[0] - ca, q.end[1] - cb)
                r2 = math.hypot(a - ca, b - cb)
                sweep = find_turn(ea, eb, ca, cb, turn=q.turn, a2=a, b2=b)
                if abs(r1 - r2) > ARC_END_RADIUS_SLACK:
                    raise BlockError(
                        "BUG: cutter compensation has generated an invalid arc with mismatched radii "
                        f"r1 {r1:f} r2 {r2:f}"
                    )
                slack = ARC_SWEEP_SLACK[self.inch]
                if q.original_turns != 0.0 and self.endpoint_valid and abs(sweep) > abs(q.original_turns) + slack:
                    raise BlockError("Arc move in concave corner cannot be reached by the tool without gouging")
            elif kind in (MoveKind.FEED, MoveKind.RAPID):
                da, db = q.direction
                if self.endpoint_valid and da * (a - ea) + db * (b - eb) < 0:
                    what = "Straight feed" if kind == MoveKind.FEED else "Straight traverse"
                    raise BlockError(f"{what} in concave corner cannot be reached by the tool without gouging")
            else:
                continue
            q.end[0], q.end[1] = a, b
        self._dequeue(plane)
        self._set_endpoint(a, b)

    def _dequeue(self, plane: str) -> None:
        """The held moves released, in order, each from where the one before ends (mm)."""
        self.endpoint_valid = False
        self.feed_held = False
        if not self.queue:
            return
        s = self.mm_per_unit
        shift = self._lathe_origin(plane)
        last = self.last_mm
        for q in self.queue:
            if not q.end:  # a dwell, where the tool is
                self.out.append(q.move._replace(start_mm=last, end_mm=last))
                continue
            x, y, z = _from_plane(q.end, plane)
            end_mm = ((x + shift[0]) * s, y * s, (z + shift[2]) * s)
            if q.move.kind == MoveKind.ARC:
                center = _from_plane([q.center[0], q.center[1], 0.0], plane)
                ia, ib = (0, 1) if plane == "xy" else (2, 0)
                center_mm = ((center[ia] + shift[ia]) * s, (center[ib] + shift[ib]) * s)
                self.out.append(q.move._replace(start_mm=last, end_mm=end_mm, center_mm=center_mm))
            else:
                self.out.append(q.move._replace(start_mm=last, end_mm=end_mm))
            last = end_mm
        self.last_mm = last
        self.stale = self.queue[0]
        self.queue = []

    def _lathe_origin(self, plane: str) -> tuple[float, float, float]:
        """LinuxCNC's ``latheorigin_x`` / ``_z``: a lathe tool's origin is not its nose's
        centre (orientations 1-8, G18); what x and z move by (program units)."""
        o, r = self.orientation, self.radius
        if plane != "zx":
            return (0.0, 0.0, 0.0)
        dx = -r if o in (2, 6, 1) else r if o in (3, 8, 4) else 0.0
        dz = -r if o in (2, 7, 3) else r if o in (1, 5, 4) else 0.0
        return (dx, 0.0, dz)


def _tool_inside_arc(side: str | None, turn: int) -> bool:
    """LinuxCNC's TOOL_INSIDE_ARC: the tool on the arc's centre side."""
    return (side == "left" and turn > 0) or (side == "right" and turn < 0)


def _in_plane(xyz: list[float], plane: str) -> tuple[float, float, float]:
    ia, ib, ic = COMPENSATED_PLANES[plane]
    return xyz[ia], xyz[ib], xyz[ic]


def _from_plane(abc: list[float], plane: str) -> list[float]:
    ia, ib, ic = COMPENSATED_PLANES[plane]
    xyz = [0.0, 0.0, 0.0]
    xyz[ia], xyz[ib], xyz[ic] = abc[0], abc[1], abc[2]
    return xyz
