"""The checks LinuxCNC's interpreter makes of a block before it runs it (``interp_check.cc``
and ``read_g`` / ``read_m``): one code a modal group, each word used by a code of the block
(``check_other_codes``), G4 and G53's needs (``check_g_codes``), what cannot run with cutter
compensation on; and what the twin refuses of LinuxCNC's G and M codes, with why.
"""

from __future__ import annotations

from twin.gcode.cycles import CYCLES, REFUSED_CYCLES
from twin.gcode.modal import COORD_SYSTEM_OF, GCode, MGroup, ModalGroup
from twin.gcode.words import BlockError

#: What the twin refuses of LinuxCNC's G codes, with why.
REFUSED_G: dict[int, str] = {
    GCode.G_5: "splines (G5) are not supported",
    GCode.G_5_1: "splines (G5.1) are not supported",
    GCode.G_5_2: "NURBS (G5.2) are not supported",
    GCode.G_5_3: "NURBS (G5.3) are not supported",
    GCode.G_6: "G6.2 NURBS are not supported",
    GCode.G_6_1: "G6.2 NURBS are not supported",
    GCode.G_6_2: "G6.2 NURBS are not supported",
    GCode.G_6_3: "G6.3 NURBS are not supported",
    GCode.G_7: "lathe diameter mode (G7) is not supported: the twin is a mill",
    GCode.G_17_1: "the UV plane (G17.1) is not supported: the machine has X, Y and Z",
    GCode.G_18_1: "the WU plane (G18.1) is not supported: the machine has X, Y and Z",
    GCode.G_19_1: "the VW plane (G19.1) is not supported: the machine has X, Y and Z",
    GCode.G_33: "spindle-synchronized motion (G33) is not supported",
    GCode.G_33_1: "rigid tapping (G33.1) is not supported",
    GCode.G_38_2: "probing (G38.2) is not supported: the twin has no probe",
    GCode.G_38_3: "probing (G38.3) is not supported: the twin has no probe",
    GCode.G_38_4: "probing (G38.4) is not supported: the twin has no probe",
    GCode.G_38_5: "probing (G38.5) is not supported: the twin has no probe",
    GCode.G_70: "lathe cycles (G70) are not supported",
    GCode.G_71: "lathe cycles (G71) are not supported",
    GCode.G_71_1: "lathe cycles (G71.1) are not supported",
    GCode.G_71_2: "lathe cycles (G71.2) are not supported",
    GCode.G_72: "lathe cycles (G72) are not supported",
    GCode.G_72_1: "lathe cycles (G72.1) are not supported",
    GCode.G_72_2: "lathe cycles (G72.2) are not supported",
    GCode.G_93: "inverse-time feed (G93) is not supported: use G94 (units per minute)",
    GCode.G_95: "feed per revolution (G95) is not supported: use G94 (units per minute)",
    GCode.G_96: "constant surface speed (G96) is not supported: use G97",
    **{code: f"{what} is not supported" for code, what in REFUSED_CYCLES.items()},
}
#: M codes the twin refuses, with why (the rest of LinuxCNC's are read).
REFUSED_M = {
    98: "Fanuc-style subprograms (M98/M99) are not supported: use O-word sub/call",
    99: "Fanuc-style subprograms (M98/M99) are not supported: use O-word sub/call",
    **{code: f"M{code}: user M codes run external programs, which the twin does not have" for code in range(100, 200)},
}
#: Words an XYZ machine has not got.
OTHER_AXES = "abcuvw"
#: Words no code needs (LinuxCNC's checks pass them whatever the block).
UNCHECKED_WORDS = frozenset("xyzfst")
#: The modes of a block without G (or M) codes.
NO_MODES: dict[int, int] = {}
#: The arc motions.
_ARCS = (GCode.G_2, GCode.G_3)
#: The cutter compensation codes that turn it on.
_COMPENSATION_ON = (GCode.G_41, GCode.G_41_1, GCode.G_42, GCode.G_42_1)


def block_modes(codes: list[int], groups: dict[int, int], refused: dict[int, str], letter: str) -> dict[int, int]:
    """The block's codes by modal group (LinuxCNC's ``read_g`` / ``read_m`` checks); a code the
    twin does not take is refused with why."""
    modes: dict[int, int] = {}
    for code in codes:
        if code in refused:
            raise BlockError(refused[code])
        group = groups.get(code)
        if group is None:
            shown = f"G{code / 10:g}" if letter == "g" else f"M{code}"
            raise BlockError(f"unknown {letter.upper()} code used: {shown}")
        if group in modes:
            if letter == "g" and code == GCode.G_80:
                continue  # G80 beside a motion word: LinuxCNC lets the motion stand
            if letter == "g" and modes[group] == GCode.G_80:
                modes[group] = code
                continue
            raise BlockError(f"two {letter.upper()} codes used from the same modal group")
        modes[group] = code
    return modes


def check_other_codes(words: dict[str, float], g_modes: dict[int, int], m_modes: dict[int, int], motion) -> None:
    """LinuxCNC's ``check_other_codes``: each word a block has needs a code that uses it."""
    mode0 = g_modes.get(ModalGroup.MODAL_0)
    arc = motion in _ARCS
    cycle = motion in CYCLES
    io = m_modes.get(MGroup.IO)
    control = g_modes.get(ModalGroup.CONTROL_MODE)
    orient = m_modes.get(MGroup.SPINDLE) == 19  # M19 takes R (angle), Q (timeout) and P (direction)
    if "d" in words and g_modes.get(ModalGroup.CUTTER_COMP) not in _COMPENSATION_ON:
        raise BlockError("D word with no G41, G41.1, G42 or G42.1 to use it")
    if "e" in words and io not in (66, 67, 68):
        raise BlockError("E word with no G70, G76, M66, M67 or M68 to use it (RS-274 has no exponents)")
    if "h" in words and g_modes.get(ModalGroup.TOOL_LENGTH_OFFSET) not in (GCode.G_43, GCode.G_43_2):
        raise BlockError("H word with no G43 to use it")
    if "i" in words and not (arc or mode0 == GCode.G_10):
        raise BlockError("I word with no G2, G3 or G10 to use it")
    if "j" in words and not (arc or mode0 == GCode.G_10):
        raise BlockError("J word with no G2, G3 or G10 to use it")
    if "k" in words and not arc:
        raise BlockError("K word with no G2 or G3 to use it")
    if "l" in words and not (
        cycle or mode0 == GCode.G_10 or io == 66 or g_modes.get(ModalGroup.CUTTER_COMP) in _COMPENSATION_ON
    ):
        raise BlockError("L word with no G10, G41, G42, canned cycle or M66 to use it")
    if "p" in words and not (
        orient
        or mode0 in (GCode.G_4, GCode.G_10)
        or control == GCode.G_64
        or motion in (GCode.G_2, GCode.G_3, GCode.G_82, GCode.G_86, GCode.G_89)
        or m_modes.get(MGroup.OVERRIDES) in (50, 51, 52, 53)
        or io in (62, 63, 64, 65, 66)
    ):
        raise BlockError("P word with no G2, G3, G4, G10, G64, G82, G86, G89, M50-M53 or M62-M66 to use it")
    if "q" in words and not (
        motion in (GCode.G_73, GCode.G_83)
        or mode0 == GCode.G_10
        or control == GCode.G_64
        or io in (66, 67, 68)
        or m_modes.get(MGroup.TOOL_CHANGE) == 61
        or orient
    ):
        raise BlockError("Q word with no G10, G64, G73, G83, M61, M66, M67 or M68 that uses it")
    if "r" in words and not (arc or cycle or mode0 == GCode.G_10 or orient):
        raise BlockError("R word with no G code that uses it")
    if "$" in words:
        raise BlockError("the spindle-select word ($) is not supported: the machine has one spindle")


#: What LinuxCNC refuses while cutter compensation is on, by G code.
_REFUSED_UNDER_COMPENSATION: dict[int, str] = {
    **dict.fromkeys(
        (GCode.G_43, GCode.G_43_1, GCode.G_43_2, GCode.G_49),
        "Cannot change tool offset with cutter radius compensation on",
    ),
    **dict.fromkeys(COORD_SYSTEM_OF, "Cannot change coordinate systems with cutter radius compensation on"),
    **dict.fromkeys(
        (GCode.G_61, GCode.G_61_1, GCode.G_64), "Cannot change control mode with cutter radius compensation on"
    ),
    **dict.fromkeys((GCode.G_98, GCode.G_99), "Cannot change retract mode with cutter radius compensation on"),
    **dict.fromkeys((GCode.G_28, GCode.G_30), "Cannot use g28 or g30 with cutter radius comp"),
    **dict.fromkeys((GCode.G_28_1, GCode.G_30_1), "Cannot set reference point with cutter compensation in effect"),
    **dict.fromkeys((GCode.G_52, GCode.G_92), "Cannot change axis offsets with cutter radius comp"),
}
#: The groups whose codes LinuxCNC checks with cutter compensation on, in its order.
_GROUPS_CHECKED_UNDER_COMPENSATION = (
    ModalGroup.TOOL_LENGTH_OFFSET,
    ModalGroup.COORD_SYSTEM,
    ModalGroup.CONTROL_MODE,
    ModalGroup.RETRACT_MODE,
    ModalGroup.MODAL_0,
)
#: The I/O M codes LinuxCNC refuses while cutter compensation is on, with its words.
_IO_REFUSED_UNDER_COMPENSATION = {
    62: "set motion output",
    63: "set motion digital output",
    64: "set auxiliary digital output",
    65: "set auxiliary digital output",
    67: "set motion analog output",
    68: "set auxiliary analog output",
}


def check_m_under_compensation(m_modes: dict[int, int], words: dict[str, float]) -> None:
    """LinuxCNC's checks of the I/O and override M codes with cutter compensation on."""
    io = m_modes.get(MGroup.IO)
    if io == 66:
        what = "digital" if "p" in words else "analog"
        raise BlockError(f"Cannot wait for {what} input with cutter radius compensation on")
    if io in _IO_REFUSED_UNDER_COMPENSATION:
        raise BlockError(f"Cannot {_IO_REFUSED_UNDER_COMPENSATION[io]} with cutter radius compensation on")
    switch = m_modes.get(MGroup.OVERRIDES)
    if switch is not None:
        enable = switch == 48 or (switch != 49 and words.get("p", -1.0) != 0)
        raise BlockError(f"Cannot {'enable' if enable else 'disable'} overrides with cutter radius compensation on")


def check_g_under_compensation(g_modes: dict[int, int]) -> None:
    """LinuxCNC's checks of each code that cannot run with cutter compensation on, in its order."""
    for group in _GROUPS_CHECKED_UNDER_COMPENSATION:
        code = g_modes.get(group)
        if code in _REFUSED_UNDER_COMPENSATION:
            raise BlockError(_REFUSED_UNDER_COMPENSATION[code])


def check_g_codes(g_modes: dict[int, int], words: dict[str, float], motion: int | None, incremental: bool) -> None:
    """LinuxCNC's ``check_g_codes`` (G4 needs P; G53 goes with G0 or G1, not incremental)."""
    mode0 = g_modes[ModalGroup.MODAL_0]
    if mode0 == GCode.G_4 and "p" not in words:
        raise BlockError("dwell time missing with G4 (give P, seconds)")
    if mode0 == GCode.G_4 and motion in (GCode.G_2, GCode.G_3):
        raise BlockError("G4 not allowed with G2 or G3 because they both use P")
    if mode0 == GCode.G_53:
        if motion not in (GCode.G_0, GCode.G_1):
            raise BlockError("must use G0 or G1 with G53")
        distance = g_modes.get(ModalGroup.DISTANCE_MODE)
        if distance == GCode.G_91 or (distance != GCode.G_90 and incremental):
            raise BlockError("cannot use G53 incremental")
