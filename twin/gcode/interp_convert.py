"""A block's codes run in LinuxCNC's order (``interp_convert.cc``): the motion the block
makes (``enhance_block``), the M codes (``convert_m``), the G codes up to the motion
(``convert_g``) and the motion itself (``convert_motion``: G0, G1, G2, G3, G80 and the canned
cycles of :mod:`twin.gcode.cycles`).
"""

from __future__ import annotations

from twin.gcode.cycles import CYCLES, CycleStep, cycle_calls
from twin.gcode.interp_arc import Arcs
from twin.gcode.interp_check import check_g_under_compensation, check_m_under_compensation
from twin.gcode.interp_offsets import Offsets
from twin.gcode.interp_setup import PLANE_OF, SAVED_MODAL_STATE
from twin.gcode.modal import COORD_SYSTEM_OF, GCode, MGroup, ModalGroup
from twin.gcode.moves import MoveKind
from twin.gcode.words import BlockError

#: The codes of the non-modal group that set something (LinuxCNC's ``convert_modal_0``, less G4 and G53).
_SETTING_CODES = (GCode.G_10, GCode.G_28, GCode.G_28_1, GCode.G_30, GCode.G_30_1, GCode.G_52, GCode.G_92)


class BlockConverter(Offsets, Arcs):
    """A block's codes and motion (see the module's description)."""

    def _motion_to_be(self, g_modes: dict[int, int], words: dict[str, float]) -> int | None:
        """LinuxCNC's ``enhance_block``: the motion the block makes, and its checks."""
        polar = "@" in words or "^" in words
        if polar:
            if g_modes.get(ModalGroup.SET_PLANE, self.state.plane) != GCode.G_17:
                raise BlockError("cannot use polar coordinates except in the G17 plane")
            if "x" in words or "y" in words:
                raise BlockError("cannot specify X or Y words with polar coordinates")
        axis = polar or "x" in words or "y" in words or "z" in words
        mode0, mode1 = g_modes.get(ModalGroup.MODAL_0), g_modes.get(ModalGroup.MOTION)
        covets = mode0 in (GCode.G_10, GCode.G_28, GCode.G_30, GCode.G_52, GCode.G_92)
        if mode1 is not None:
            if mode1 == GCode.G_80:
                if axis and not covets:
                    raise BlockError("cannot use axis values with G80")
                if not axis and mode0 in (GCode.G_52, GCode.G_92):
                    raise BlockError("all axes missing with G52 or G92")
            else:
                if covets:
                    raise BlockError("cannot use two G codes that both use axis values")
                if not axis and mode1 not in (GCode.G_0, GCode.G_1, GCode.G_2, GCode.G_3):
                    raise BlockError(f"all axes missing with motion code G{mode1 / 10:g}")
            return mode1
        if covets:
            if not axis and mode0 in (GCode.G_52, GCode.G_92):
                raise BlockError("all axes missing with G52 or G92")
            return None
        if axis:
            if g_modes.get(ModalGroup.TOOL_LENGTH_OFFSET) == GCode.G_43_1:
                return None
            if self.state.motion in (None, GCode.G_80):
                raise BlockError("cannot use axis values without a G code that uses them (give G0, G1, G2 or G3)")
            return self.state.motion
        if ("i" in words or "j" in words or "k" in words) and self.state.motion in (GCode.G_2, GCode.G_3):
            return self.state.motion
        return None

    def _select_tool(self, tool: int) -> None:
        if tool < 0:
            raise BlockError(f"negative tool number: T{tool}")
        known = self.settings.tools
        if known is not None and tool != 0 and tool not in known:
            raise BlockError(f"T{tool}: no such tool (tools: {sorted(known)})")
        self.state.selected_tool = tool

    def _m_codes(self, m_modes: dict[int, int], words: dict[str, float]) -> None:
        """LinuxCNC's ``convert_m`` (what a mill's twin keeps of it)."""
        s = self.state
        io = m_modes.get(MGroup.IO)
        if self.comp.side is not None:
            check_m_under_compensation(m_modes, words)
        if io in (62, 63, 64, 65) and "p" not in words:
            raise BlockError(f"M{io} needs a P word (the output number)")
        if io in (67, 68) and ("e" not in words or "q" not in words):
            raise BlockError(f"M{io} needs an E word (the output) and a Q word (the value)")
        if io == 66 and "p" not in words and "e" not in words:
            raise BlockError("need to have either a valid P or a valid E word with M66")
        change = m_modes.get(MGroup.TOOL_CHANGE)
        if change == 6:
            s.tool_in_spindle = s.selected_tool
            s.spindle = "off"
        elif change == 61:
            if "q" not in words or words["q"] < 0 or words["q"] != int(words["q"]):
                raise BlockError("M61 needs a Q word: the tool number, a whole number >= 0")
            self._select_tool(int(words["q"]))
            s.tool_in_spindle = s.selected_tool
        spindle = m_modes.get(MGroup.SPINDLE)
        if spindle in (3, 4, 5, 19):
            s.spindle = {3: "cw", 4: "ccw"}.get(spindle, "off")
        elif spindle == 70:
            self.saved.append({name: getattr(s, name) for name in SAVED_MODAL_STATE})
        elif spindle == 73:
            if not self.flow.depth:
                raise BlockError("M73 is only allowed inside a subroutine")
            self.autorestore.append((self.flow.depth, {name: getattr(s, name) for name in SAVED_MODAL_STATE}))
        elif spindle == 71:
            if self.saved:
                self.saved.pop()
        elif spindle == 72:
            if not self.saved:
                raise BlockError("M72: no modal state saved (M70 or M73 first)")
            self._restore(self.saved.pop())
        coolant = m_modes.get(MGroup.COOLANT)
        if coolant == 7:
            s.set_coolant(True, s.flood)
        elif coolant == 8:
            s.set_coolant(s.mist, True)
        elif coolant == 9:
            s.set_coolant(False, False)
        # group 9 (M48-M53: override switches) and the I/O group 5 change no motion

    def _restore(self, saved: dict) -> None:
        s = self.state
        if saved["inch"] != s.inch:
            self._units(saved["inch"])
        for name, value in saved.items():
            if name == "system" and value != s.system:
                self._select_system(value)
            elif name not in ("inch", "feed", "mist", "flood"):
                setattr(s, name, value)
        s.feed = saved["feed"]
        s.set_coolant(saved["mist"], saved["flood"])

    def _g_codes(self, g_modes: dict[int, int], words: dict[str, float]) -> None:
        """LinuxCNC's ``convert_g`` up to the motion."""
        s = self.state
        mode0 = g_modes.get(ModalGroup.MODAL_0)
        if mode0 == GCode.G_4:
            dwell = words["p"]
            if dwell < 0:
                raise BlockError(f"P = {dwell:g}: a dwell cannot be negative")
            dwell_move = self._move(MoveKind.DWELL, s.position, dwell_s=dwell)
            if not self.comp.hold(dwell_move):
                self.out.append(dwell_move)
        plane = g_modes.get(ModalGroup.SET_PLANE)
        comp_on = self.comp.side is not None
        if plane is not None:
            if comp_on and plane != s.plane:
                raise BlockError("Cannot change planes with cutter radius compensation on")
            s.plane = plane
        units = g_modes.get(ModalGroup.LENGTH_UNITS)
        if units is not None and (units == GCode.G_20) != s.inch:
            self._units(units == GCode.G_20)
        compensation = g_modes.get(ModalGroup.CUTTER_COMP)
        if compensation is not None:
            self._cutter_compensation(compensation, words)
            comp_on = self.comp.side is not None
        if comp_on:
            check_g_under_compensation(g_modes)
        length = g_modes.get(ModalGroup.TOOL_LENGTH_OFFSET)
        if length is not None:
            self._tool_length_offset(length, words)
        system = g_modes.get(ModalGroup.COORD_SYSTEM)
        if system is not None:
            self._select_system(COORD_SYSTEM_OF[system])
        control = g_modes.get(ModalGroup.CONTROL_MODE)
        if control == GCode.G_61:
            s.path_mode, s.tolerance = "G61", None
        elif control == GCode.G_61_1:
            s.path_mode, s.tolerance = "G61.1", None
        elif control == GCode.G_64:
            s.path_mode = "G64"
            p = words.get("p", -1.0)
            s.tolerance = p if p > 0 else None
        distance = g_modes.get(ModalGroup.DISTANCE_MODE)
        if distance is not None:
            s.incremental = distance == GCode.G_91
        arc_distance = g_modes.get(ModalGroup.IJK_DISTANCE_MODE)
        if arc_distance is not None:
            s.arc_incremental = arc_distance == GCode.G_91_1
        retract = g_modes.get(ModalGroup.RETRACT_MODE)
        if retract is not None:
            s.retract_to_r = retract == GCode.G_99
        if mode0 in _SETTING_CODES:
            self._modal_0(mode0, words)
        applied = g_modes.get(ModalGroup.G92_IS_APPLIED)
        if applied is not None:
            self._g92_applied(applied)

    def _cutter_compensation(self, code: int, words: dict[str, float]) -> None:
        """G40, G41, G42, G41.1, G42.1 (:mod:`twin.gcode.compensation`)."""
        s = self.state
        plane = PLANE_OF[s.plane]
        if code == GCode.G_40:
            s.position = self.comp.turn_off(s.position, plane)
        else:
            self.comp.turn_on(code, words, plane, self._tool_diameter)

    def _tool_diameter(self, tool: int | None) -> float:
        """The diameter of ``tool`` (None or 0: the tool in the spindle; none: 0), program units."""
        settings = self.settings
        if not tool:
            tool = self.state.tool_in_spindle
            if not tool:
                return 0.0
        elif not (
            tool in settings.tool_diameters_mm
            or tool in settings.tool_lengths_mm
            or (settings.tools is not None and tool in settings.tools)
        ):
            raise BlockError(f"Requested tool {tool} not found in the tool table (reference.tool_diameters_mm)")
        return self._to_program(settings.tool_diameters_mm.get(tool, 0.0))

    def _motion(self, motion: int, words: dict[str, float], g_modes: dict[int, int]) -> None:
        s = self.state
        if motion in CYCLES:
            self._cycle(motion, words)
            s.motion = motion
            return
        self.cycle.initial = None
        if motion == GCode.G_80:
            s.motion = GCode.G_80
            return
        if motion in (GCode.G_0, GCode.G_1):
            comp = self.comp
            comp.arc_not_allowed = False
            end = self._ends(words, machine=g_modes.get(ModalGroup.MODAL_0) == GCode.G_53)
            if comp.active:
                if motion == GCode.G_1 and s.feed <= 0:
                    raise BlockError("cannot do G1 with zero feed rate (give F)")
                if g_modes.get(ModalGroup.MODAL_0) == GCode.G_53:
                    raise BlockError("Cannot use g53 with cutter radius comp")
                kind = MoveKind.FEED if motion == GCode.G_1 else MoveKind.RAPID
                s.position = comp.straight(
                    kind, end, position=s.position, plane=PLANE_OF[s.plane], make=self._compensated_move
                )
            else:
                self._linear(MoveKind.FEED if motion == GCode.G_1 else MoveKind.RAPID, end)
        else:
            self._arc(motion, words)
        s.motion = motion

    def _cycle(self, motion: int, words: dict[str, float]) -> None:
        """A canned cycle's moves, at exact path (LinuxCNC runs its moves in G61)."""
        s = self.state
        if self.comp.side is not None:
            raise BlockError("Cannot use canned cycles with cutter compensation on")
        if s.feed <= 0:
            raise BlockError("cannot feed with zero feed rate (give F before the cycle)")
        calls = cycle_calls(
            motion,
            words,
            previous_motion=s.motion,
            plane=s.plane,
            position=s.position,
            incremental=s.incremental,
            retract_to_r=s.retract_to_r,
            inch=s.inch,
            spindle=s.spindle,
            memory=self.cycle,
        )
        mode, tolerance = s.path_mode, s.tolerance
        position = list(s.position)  # cycle_calls moves s.position to where the block ends
        end_of_block = s.position
        s.position = position
        try:
            for step, value in calls:
                if step is CycleStep.DWELL:
                    assert isinstance(value, float)
                    self.out.append(self._move(MoveKind.DWELL, s.position, dwell_s=value))
                elif step is CycleStep.SPINDLE:
                    assert isinstance(value, str)
                    s.spindle = value
                elif step is CycleStep.EXACT_PATH:
                    s.path_mode, s.tolerance = "G61", None
                else:
                    assert isinstance(value, tuple)
                    self._linear(MoveKind.FEED if step is CycleStep.FEED else MoveKind.RAPID, list(value))
        finally:
            s.path_mode, s.tolerance = mode, tolerance
        s.position = end_of_block
