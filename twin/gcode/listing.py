"""The moves as ``twin gcode`` prints them: one JSON object or one table row each, formatted
directly (a CAM program is read and listed at about rs274's speed; ``json.dumps`` of
:meth:`~twin.gcode.reader.Move.as_dict` gives the same text, which the tests check)."""

from __future__ import annotations

from twin.gcode.reader import Move

#: The table's header (``twin gcode FILE`` without ``--json``).
HEADER = f"{'line':>6}  {'kind':<6} {'end_mm (x, y, z)':<34} {'feed mm/min':>11}  spindle"


def move_json(move: Move) -> str:
    """The move as one JSON object: ``json.dumps(move.as_dict())``, faster."""
    x, y, z = move.end_mm
    text = (
        f'{{"line": {move.line}, "kind": "{move.kind}", "end_mm": [{round(x, 6)!r}, {round(y, 6)!r}, '
        f'{round(z, 6)!r}], "feed_mm_per_min": {move.feed_mm_per_min!r}, "spindle": "{move.spindle}", '
        f'"spindle_rpm": {move.spindle_rpm!r}, "coolant": "{move.coolant}"'
    )
    if move.kind == "arc":
        a, b = move.center_mm
        text += f', "plane": "{move.plane}", "center_mm": [{round(a, 6)!r}, {round(b, 6)!r}], "turns": {move.turns}'
    elif move.kind == "dwell":
        text += f', "dwell_s": {move.dwell_s!r}'
    return text + "}"


def move_row(move: Move) -> str:
    """The move as one row of the table under :data:`HEADER`."""
    end = ", ".join(f"{v:.4f}" for v in move.end_mm)
    extra = f"  arc {move.plane} turns {move.turns}" if move.kind == "arc" else ""
    spindle = f"{move.spindle} {move.spindle_rpm:g}" if move.spindle != "off" else "off"
    return f"{move.line:>6}  {move.kind:<6} {end:<34} {move.feed_mm_per_min:>11.1f}  {spindle}{extra}"
