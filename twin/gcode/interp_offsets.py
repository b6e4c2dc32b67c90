"""Units, offsets and coordinate systems, as LinuxCNC's ``interp_convert.cc`` sets them:
G20 / G21 (``convert_length_units``), the tool length offset G43, G43.1, G43.2, G49
(``convert_tool_length_offset``), G10 L1 / L10 / L2 / L20 (``convert_setup``,
``convert_setup_tool``), G28 / G30 and their .1 (``convert_home``, ``convert_savehome``),
G52 / G92 and G92.1-G92.3 (``convert_axis_offsets``). The coordinate system selection
(G54-G59.3) is :meth:`~twin.gcode.interp_setup.InterpreterSetup._select_system`.
"""

from __future__ import annotations

from twin.gcode.interp_move import StraightMoves
from twin.gcode.interp_setup import AXES, MM_PER_INCH
from twin.gcode.modal import GCode, Param, coord_system_offset
from twin.gcode.moves import MoveKind
from twin.gcode.words import BlockError


class Offsets(StraightMoves):
    """Units, offsets and coordinate systems (see the module's description)."""

    def _units(self, inch: bool) -> None:
        """G20 / G21: every length held in program units converted (LinuxCNC's
        ``convert_length_units``; the feed too, as its canonical layer keeps it physical)."""
        s = self.state
        factor = 1.0 / MM_PER_INCH if inch else MM_PER_INCH
        s.inch, s.mm_per_unit = inch, MM_PER_INCH if inch else 1.0
        s.position = [v * factor for v in s.position]
        s.origin = [v * factor for v in s.origin]
        s.axis_offset = [v * factor for v in s.axis_offset]
        s.tool_offset *= factor
        if not self.comp.feed_held:  # a held feed change takes the units it is released in
            s.feed *= factor
        if s.tolerance is not None:
            s.tolerance *= factor
        self.cycle.scale(factor)
        self.comp.units(inch, factor, s.mm_per_unit)

    def _tool_length_offset(self, code: int, words: dict[str, float]) -> None:
        s = self.state
        old = self._machine_offset()
        if code == GCode.G_49:
            s.tool_offset = 0.0
        elif code == GCode.G_43:
            tool = int(words["h"]) if "h" in words else s.tool_in_spindle
            s.tool_offset = self._to_program(self._tool_length(tool))
        elif code == GCode.G_43_2:
            if "h" not in words:
                raise BlockError("G43.2 needs an H word: the tool whose length to add")
            s.tool_offset += self._to_program(self._tool_length(int(words["h"])))
        else:  # G43.1: the offset given by the Z word
            if "x" in words or "y" in words:
                raise BlockError("G43.1: the twin's tool length offset is along Z only")
            if "z" not in words:
                raise BlockError("G43.1 needs a Z word: the tool length offset")
            s.tool_offset = words["z"]
        self._rebase(old)

    def _modal_0(self, code: int, words: dict[str, float]) -> None:
        """G10, G28/G30 (and .1), G52, G92 (and .1, .2, .3)."""
        s = self.state
        numbered = self.params.numbered
        if code == GCode.G_10:
            self._g10(words)
        elif code in (GCode.G_28, GCode.G_30):
            base = Param.G28_HOME if code == GCode.G_28 else Param.G30_HOME
            middle = self._ends(words, machine=False)
            self._linear(MoveKind.RAPID, middle)
            home = list(middle)
            named = [i for i, k in enumerate(AXES) if k in words] or [0, 1, 2]
            offset = self._machine_offset()
            for i in named:
                home[i] = self._to_program(numbered.get(base + i, 0.0)) - offset[i]
            self._linear(MoveKind.RAPID, home)
        elif code in (GCode.G_28_1, GCode.G_30_1):
            base = Param.G28_HOME if code == GCode.G_28_1 else Param.G30_HOME
            offset = self._machine_offset()
            for i in range(3):
                numbered[base + i] = self._to_user(s.position[i] + offset[i])
        elif code in (GCode.G_52, GCode.G_92):
            old = self._machine_offset()
            for i, k in enumerate(AXES):
                if k in words:
                    if code == GCode.G_52:
                        s.axis_offset[i] = words[k]
                    else:
                        s.axis_offset[i] = s.position[i] + s.axis_offset[i] - words[k]
            self._rebase(old)
            numbered[Param.AXIS_OFFSET_APPLIED] = 1.0
            for i in range(3):
                numbered[Param.AXIS_OFFSET + i] = self._to_user(s.axis_offset[i])

    def _g92_applied(self, code: int) -> None:
        """G92.1 / G92.2 (G92 offsets off; G92.1 zeroes their parameters too), G92.3 (back
        from the parameters)."""
        s = self.state
        numbered = self.params.numbered
        old = self._machine_offset()
        if code in (GCode.G_92_1, GCode.G_92_2):
            s.axis_offset = [0.0, 0.0, 0.0]
            numbered[Param.AXIS_OFFSET_APPLIED] = 0.0
            if code == GCode.G_92_1:
                for i in range(3):
                    numbered[Param.AXIS_OFFSET + i] = 0.0
        else:
            s.axis_offset = [self._to_program(numbered.get(Param.AXIS_OFFSET + i, 0.0)) for i in range(3)]
            numbered[Param.AXIS_OFFSET_APPLIED] = 1.0
        self._rebase(old)

    def _g10(self, words: dict[str, float]) -> None:
        """G10 L2 / L20 (a coordinate system's offsets) and L1 / L10 (a tool's length)."""
        s = self.state
        numbered = self.params.numbered
        if "l" not in words:
            raise BlockError("line with G10 does not have L1, L10, L2 or L20")
        level = int(words["l"])
        p = words.get("p", 0.0)
        if abs(p - round(p)) > 0.0002:
            raise BlockError("P value not an integer with G10")
        number = round(p)
        if level in (2, 20):
            if not 0 <= number <= 9:
                raise BlockError(f"P value out of range (0-9) with G10 L{level}")
            if "i" in words or "j" in words:
                raise BlockError("I J words not allowed with G10 L2")
            if words.get("r", 0.0) != 0.0:
                raise BlockError("G10 L2 R: a rotated coordinate system is not supported")
            system = number or s.system
            if system == s.system and self.comp.side is not None:
                raise BlockError("Cannot change the active coordinate system with cutter radius compensation on")
            base = coord_system_offset(system)
            offset = self._machine_offset()
            for i, k in enumerate(AXES):
                if k not in words:
                    continue
                if level == 2:
                    numbered[base + i] = self._to_user(words[k])
                else:
                    current = s.position[i] + offset[i] - s.tool_offset * (i == 2)
                    if numbered.get(Param.AXIS_OFFSET_APPLIED):
                        current -= self._to_program(numbered.get(Param.AXIS_OFFSET + i, 0.0))
                    numbered[base + i] = self._to_user(current - words[k])
            if system == s.system:
                self._select_system(system)
        elif level in (1, 10):
            if number < 1:
                raise BlockError(f"P value out of range with G10 L{level}: the tool number")
            if "z" in words:
                tools = self.settings.tool_lengths_mm
                if level == 1:
                    tools[number] = self._to_user(words["z"])
                else:
                    old = s.tool_offset
                    machine_z = s.position[2] + self._machine_offset()[2] - old
                    tools[number] = self._to_user(machine_z - words["z"])
        else:
            raise BlockError(f"G10 L{level} is not supported (L1, L2, L10, L20 are)")
