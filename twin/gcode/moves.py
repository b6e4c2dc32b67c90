"""What the interpreter reads a program into: :class:`Move` s, each of a :class:`MoveKind`, with
the modal state they run in (mm, work coordinates and the offset to machine coordinates)."""

from __future__ import annotations

from enum import StrEnum
from typing import NamedTuple

#: The in-plane axes (LinuxCNC's order) and the normal axis of each plane, as indices of x, y, z.
PLANES = {"xy": (0, 1, 2), "zx": (2, 0, 1), "yz": (1, 2, 0)}
#: The arc-centre words of each plane, in the plane's axis order.
CENTER_WORDS = {"xy": ("i", "j"), "zx": ("k", "i"), "yz": ("j", "k")}


class MoveKind(StrEnum):
    """What a move does (its value is what ``twin gcode`` prints)."""

    #: G0, and the rapids of G28, G30, G53 G0 and the canned cycles.
    RAPID = "rapid"
    #: G1, and the feeds of the canned cycles.
    FEED = "feed"
    #: G2 / G3.
    ARC = "arc"
    #: G4, and a canned cycle's dwell.
    DWELL = "dwell"


class Move(NamedTuple):
    """One move as read.

    Attributes
    ----------
    line : int
        1-based line of the program.
    kind : MoveKind
        G0 (and G28, G30, G53 G0, a cycle's rapids), G1, G2/G3, G4 (and a cycle's dwell).
    start_mm, end_mm : tuple of float
        Start and end [x, y, z] in work coordinates (mm).
    offset_mm : tuple of float
        Work offset, G92/G52 and tool length (Z) that turn work into machine coordinates (mm).
    feed_mm_per_min : float
        The programmed feed (0 for rapids and dwells).
    spindle_rpm : float
        S word in force.
    spindle : {"off", "cw", "ccw"}
        M3/M4/M5 state.
    plane : str
        For arcs: "xy" (G17), "zx" (G18), "yz" (G19).
    center_mm : tuple of float
        For arcs: the centre's two in-plane coordinates, in the plane's order (work, mm).
    turns : int
        For arcs: signed, > 0 counter-clockwise; |turns| > 1 adds full circles.
    dwell_s : float
        For dwells: the time (s).
    tolerance_mm : float or None
        G64 P in force (mm); None for G64 without P (or P <= 0: LinuxCNC's "best speed").
    text : str
        The block as written (stripped).
    tool : int
        The tool in the spindle (T with M6, M61 Q; 0: none).
    coolant : {"off", "mist", "flood", "mist+flood"}
        M7/M8/M9 state.
    path_mode : {"G64", "G61", "G61.1"}
        Path control in force: blend within the tolerance, exact path (a canned cycle's moves
        too), exact stop.
    """

    line: int
    kind: MoveKind
    start_mm: tuple[float, ...]
    end_mm: tuple[float, ...]
    offset_mm: tuple[float, ...]
    feed_mm_per_min: float = 0.0
    spindle_rpm: float = 0.0
    spindle: str = "off"
    plane: str = ""
    center_mm: tuple[float, ...] = (0.0, 0.0)
    turns: int = 0
    dwell_s: float = 0.0
    tolerance_mm: float | None = None
    text: str = ""
    tool: int = 0
    coolant: str = "off"
    path_mode: str = "G64"

    def as_dict(self) -> dict:
        """The move as ``twin gcode --json`` prints it."""
        out = {
            "line": self.line,
            "kind": str(self.kind),
            "end_mm": [round(v, 6) for v in self.end_mm],
            "feed_mm_per_min": self.feed_mm_per_min,
            "spindle": self.spindle,
            "spindle_rpm": self.spindle_rpm,
            "coolant": self.coolant,
        }
        if self.kind == MoveKind.ARC:
            out |= {"plane": self.plane, "center_mm": [round(v, 6) for v in self.center_mm], "turns": self.turns}
        if self.kind == MoveKind.DWELL:
            out["dwell_s"] = self.dwell_s
        return out
