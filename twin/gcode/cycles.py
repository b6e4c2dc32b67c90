"""Canned cycles G73, G81, G82, G83, G85, G86, G89 expanded into moves exactly as LinuxCNC 2.9's
interpreter expands them (``interp_cycles.cc``: ``convert_cycle``, ``convert_cycle_xy`` /
``_yz`` / ``_zx``, the ``CYCLE_MACRO`` repeat loop), in any plane, with G98/G99, R, Q, P, L
and incremental distance mode.

Coordinates are in program units and work coordinates, and the arithmetic is LinuxCNC's own
(the same order of operations in double precision), so the number of pecks of a G83 comes out
as rs274's. In a plane, ``aa`` and ``bb`` are the plane's two axes and ``cc`` the one along the
tool (G17: x, y, z; G18: z, x, y; G19: y, z, x).
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass
from enum import StrEnum

from twin.gcode.modal import GCode
from twin.gcode.words import BlockError

#: The cycles read.
CYCLES = (GCode.G_73, GCode.G_81, GCode.G_82, GCode.G_83, GCode.G_85, GCode.G_86, GCode.G_89)
#: The cycles that are not: tapping, back boring, boring with a manual retract.
REFUSED_CYCLES: dict[int, str] = {
    GCode.G_74: "left-hand tapping (G74)",
    GCode.G_84: "tapping (G84)",
    GCode.G_87: "back boring (G87)",
    GCode.G_88: "boring with a manual retract (G88)",
    GCode.G_76: "threading (G76)",
}
#: The cycles that dwell at the bottom (P) and those that peck (Q).
_DWELLING = (GCode.G_82, GCode.G_86, GCode.G_89)
_PECKING = (GCode.G_73, GCode.G_83)
#: The rapid clearance of a G73 / G83 peck, inches (LinuxCNC 2.9's G83_RAPID_DELTA).
PECK_CLEARANCE_INCH = 0.010
#: The (aa, bb, cc) axis indices (x 0, y 1, z 2) of each plane.
CYCLE_AXES: dict[int, tuple[int, int, int]] = {GCode.G_17: (0, 1, 2), GCode.G_18: (2, 0, 1), GCode.G_19: (1, 2, 0)}


class CycleStep(StrEnum):
    """What one of a cycle's canonical calls does."""

    #: A rapid to the point given.
    RAPID = "rapid"
    #: A feed to the point given.
    FEED = "feed"
    #: A dwell of the seconds given.
    DWELL = "dwell"
    #: The spindle set ("off", "cw", "ccw").
    SPINDLE = "spindle"
    #: The cycle's own moves begin: exact path (G61) from here.
    EXACT_PATH = "exact_path"


@dataclass
class CycleMemory:
    """What the interpreter keeps between cycle blocks (LinuxCNC's ``cycle_*`` settings), in
    program units: the R plane, the bottom, the dwell, the peck and the initial level."""

    r: float = 0.0
    cc: float = 0.0
    p: float = 0.0
    q: float = 0.0
    initial: float | None = None

    def scale(self, factor: float) -> None:
        """G20/G21 in between: the lengths in the new units."""
        self.r *= factor
        self.cc *= factor
        self.q *= factor
        if self.initial is not None:
            self.initial *= factor


def cycle_calls(
    motion: int,
    words: dict[str, float],
    previous_motion: int | None,
    plane: int,
    position: list[float],
    incremental: bool,
    retract_to_r: bool,
    inch: bool,
    spindle: str,
    memory: CycleMemory,
) -> Iterator[tuple[CycleStep, tuple[float, float, float] | float | str]]:
    """The canonical calls of one cycle block, each a :class:`CycleStep` and its value:
    ``(RAPID, xyz)``, ``(FEED, xyz)``, ``(DWELL, seconds)``, ``(SPINDLE, "off" | "cw" | "ccw")``
    and ``(EXACT_PATH, "G61")``
    where the cycle's own moves begin (as LinuxCNC, after the rapid up to the R plane from
    below it, which runs in the path mode in force); ``position`` (work coordinates, program
    units) is updated as the block ends.

    Raises
    ------
    BlockError
        What LinuxCNC refuses: no R or depth the first time, R below the bottom, a missing P
        or Q, L = 0, a zero or negative Q, G86 with the spindle off.
    """
    a_i, b_i, c_i = CYCLE_AXES[plane]
    name = "xyz"
    letter_a, letter_b, letter_c = name[a_i], name[b_i], name[c_i]
    same = previous_motion == motion
    g = f"G{motion / 10:g}"
    if "r" in words:
        r_word = words["r"]
    elif same:
        r_word = memory.r
    else:
        raise BlockError(f"R clearance plane unspecified in cycle ({g} needs an R word the first time)")
    repeats = int(words.get("l", 1))
    if "l" in words and repeats == 0:
        raise BlockError("cannot do zero repeats of cycle (L0)")
    if repeats < 0:
        raise BlockError(f"L = {repeats}: a cycle's repeats are a whole number >= 1")
    if not same and letter_c not in words:
        raise BlockError(
            f"{letter_c.upper()} value unspecified in the canned cycle ({g} needs its depth the first time)"
        )
    c_word = words.get(letter_c, memory.cc)
    current_cc = position[c_i]
    if memory.initial is None:
        memory.initial = current_cc
    old_cc = memory.initial
    radius_step = theta_step = 0.0
    if incremental:
        aa_step, bb_step = words.get(letter_a, 0.0), words.get(letter_b, 0.0)
        radius_step, theta_step = words.get("@", 0.0), math.radians(words.get("^", 0.0))
        r = r_word + old_cc
        cc = r + c_word
        aa, bb = position[a_i], position[b_i]
    else:
        aa_step = bb_step = 0.0
        r, cc = r_word, c_word
        aa, bb = words.get(letter_a, position[a_i]), words.get(letter_b, position[b_i])
        if "@" in words or "^" in words:  # polar (G17 only)
            radius = words.get("@", math.hypot(position[1], position[0]))
            theta = math.radians(words["^"]) if "^" in words else math.atan2(position[1], position[0])
            aa, bb = radius * math.cos(theta), radius * math.sin(theta)
    if r < cc:
        raise BlockError(f"R less than {letter_c.upper()} in cycle: the R plane ({r:g}) is below the bottom ({cc:g})")
    p = q = 0.0
    if motion in _DWELLING:
        if "p" not in words and not same:
            raise BlockError(f"dwell time P word missing with {g}")
        p = words.get("p", memory.p)
        if p < 0.0:  # rs274 refuses P-1 (its "no P"), reads P-2 as a dwell of -2 s: a dwell is not negative
            raise BlockError(f"P = {p:g}: a dwell cannot be negative (with {g})")
    if motion in _PECKING:
        if "q" not in words and not same:
            raise BlockError(f"Q word missing with {g}")
        q = words.get("q", memory.q)
        if q <= 0.0:
            raise BlockError(f"negative or zero Q value used with {g}")
    if motion == GCode.G_86 and spindle == "off":
        raise BlockError("spindle not turning in G86")

    def point(a: float, b: float, c: float) -> tuple[float, float, float]:
        xyz = [0.0, 0.0, 0.0]
        xyz[a_i], xyz[b_i], xyz[c_i] = a, b, c
        return (xyz[0], xyz[1], xyz[2])

    if old_cc < r:  # below the R plane: straight up to it first
        yield (CycleStep.RAPID, point(position[a_i], position[b_i], r))
        old_cc = r
        current_cc = old_cc
    yield (CycleStep.EXACT_PATH, "G61")
    clear_cc = r if retract_to_r else old_cc
    delta = PECK_CLEARANCE_INCH if inch else PECK_CLEARANCE_INCH * 25.4
    for repeat in range(repeats, 0, -1):
        aa = aa + aa_step
        bb = bb + bb_step
        for radius_add, theta_add in ((radius_step, 0.0), (0.0, theta_step)):
            if radius_add or theta_add:
                if aa == 0 and bb == 0:
                    raise BlockError("incremental motion with polar coordinates is indeterminate when at the origin")
                theta, radius = math.atan2(bb, aa) + theta_add, math.hypot(bb, aa) + radius_add
                aa, bb = radius * math.cos(theta), radius * math.sin(theta)
        if repeat == repeats and current_cc > r:
            yield (CycleStep.RAPID, point(aa, bb, current_cc))
            yield (CycleStep.RAPID, point(aa, bb, r))
        else:
            yield (CycleStep.RAPID, point(aa, bb, clear_cc))
            if clear_cc > r:
                yield (CycleStep.RAPID, point(aa, bb, r))
        if motion in _PECKING:
            depth = r - q
            while depth > cc:
                yield (CycleStep.FEED, point(aa, bb, depth))
                if motion == GCode.G_83:
                    yield (CycleStep.RAPID, point(aa, bb, r))
                yield (CycleStep.RAPID, point(aa, bb, depth + delta))
                depth = depth - q
        yield (CycleStep.FEED, point(aa, bb, cc))
        if motion in _DWELLING:
            yield (CycleStep.DWELL, p)
        if motion == GCode.G_86:
            yield (CycleStep.SPINDLE, "off")
        if motion == GCode.G_85:
            yield (CycleStep.FEED, point(aa, bb, r))
        if motion == GCode.G_89:
            yield (CycleStep.FEED, point(aa, bb, clear_cc))
        else:
            yield (CycleStep.RAPID, point(aa, bb, clear_cc))
        if motion == GCode.G_86:
            yield (CycleStep.SPINDLE, spindle)
    position[a_i], position[b_i], position[c_i] = aa, bb, clear_cc
    memory.r, memory.cc = r_word, c_word
    if motion in _DWELLING:
        memory.p = p
    if motion in _PECKING:
        memory.q = q
    if not math.isfinite(aa + bb + clear_cc):
        raise BlockError("the cycle's positions are not finite")
