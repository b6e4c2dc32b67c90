"""The interpreter's state and what every part of it uses (LinuxCNC's ``setup`` and
``interp_setup.cc``): the controller's :class:`Settings`, the modal state in program units, the
parameters the settings fill and the read-only system parameters computed from the state, the
unit conversions and the offsets from work to machine coordinates.

:class:`InterpreterSetup` is the first of the classes the interpreter is built of, one a topic
as LinuxCNC's ``Interp`` is spread over its ``interp_*.cc`` files: :mod:`~twin.gcode.interp_move`
(end points, straight moves), :mod:`~twin.gcode.interp_arc` (arcs),
:mod:`~twin.gcode.interp_offsets` (units, coordinate systems, G10, G28/G30, G52/G92, tool length),
:mod:`~twin.gcode.interp_convert` (a block's G and M codes and its motion) and
:class:`twin.gcode.reader.Reader` (the program, line by line).
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import NoReturn

from twin.errors import TwinInputError
from twin.gcode.compensation import CutterCompensation
from twin.gcode.cycles import CycleMemory
from twin.gcode.flow import Flow, ProgramText
from twin.gcode.modal import AXES_IN_PARAMETERS, COORD_SYSTEM_CODES, GCode, Param, coord_system_offset
from twin.gcode.moves import Move
from twin.gcode.parameters import Parameters

MM_PER_INCH = 25.4
#: Characters of a program's path an error line shows (its end: the file's name).
SOURCE_CHARS = 68
#: The plane of each plane-selection code.
PLANE_OF: dict[int, str] = {GCode.G_17: "xy", GCode.G_18: "zx", GCode.G_19: "yz"}
#: The axis words, in the order of their indices.
AXES = "xyz"


class GcodeError(TwinInputError):
    """A program the reader cannot take: its file and line (1-based), the block's text and why;
    the error line reads ``FILE:LINE = 'BLOCK': REASON``."""

    def __init__(self, line: int, text: str, reason: str, source: str = "program"):
        self.line, self.text, self.source = line, text, source
        # a long path loses its start, never the file's name and line (the field has 80 characters)
        shown = source if len(source) <= SOURCE_CHARS else "..." + source[3 - SOURCE_CHARS :]
        super().__init__(f"{shown}:{line}", text.strip(), reason)


@dataclass
class Settings:
    """What the machine's controller holds besides the program (mm, machine coordinates).

    Attributes
    ----------
    work_offsets_mm : dict of int to tuple
        Offset [x, y, z] of each coordinate system 1-9 (G54-G59, G59.1-G59.3); 0 by default.
    tool_lengths_mm : dict of int to float
        Tool length offset (Z) by tool number.
    g28_home_mm, g30_home_mm : tuple of float
        G28's and G30's home positions.
    tools : frozenset of int or None
        The tool numbers a T word may select (None: any).
    tool_diameters_mm : dict of int to float
        Tool diameter by tool number (G41 / G42's D word; negative: compensation on the other
        side, as LinuxCNC takes it).
    """

    work_offsets_mm: dict[int, tuple[float, float, float]] = field(default_factory=dict)
    tool_lengths_mm: dict[int, float] = field(default_factory=dict)
    g28_home_mm: tuple[float, float, float] = (0.0, 0.0, 0.0)
    g30_home_mm: tuple[float, float, float] = (0.0, 0.0, 0.0)
    tools: frozenset[int] | None = None
    tool_diameters_mm: dict[int, float] = field(default_factory=dict)


class ModalState:
    """The interpreter's modal state, in program units (LinuxCNC's ``setup``)."""

    def __init__(self) -> None:
        self.position = [0.0, 0.0, 0.0]  # the current point, work coordinates
        self.inch = False
        self.mm_per_unit = 1.0  # 25.4 under G20
        self.incremental = False
        self.arc_incremental = True
        self.plane: int = GCode.G_17
        self.motion: int | None = None  # a GCode of the motion group (G_80: none)
        self.feed = 0.0
        self.spindle_rpm = 0.0
        self.spindle = "off"
        self.mist = self.flood = False
        self.coolant = "off"  # M7 / M8 / M9, from mist and flood
        self.system = 1
        self.selected_tool = 0
        self.tool_in_spindle = 0
        self.origin = [0.0, 0.0, 0.0]  # the work offset of the active system
        self.axis_offset = [0.0, 0.0, 0.0]  # G92 / G52
        self.tool_offset = 0.0  # G43 (Z)
        self.path_mode = "G64"
        self.tolerance: float | None = None  # G64 P, program units
        self.retract_to_r = True  # G99 (LinuxCNC's initial retract mode) or G98 (False)
        self.ended = False

    def set_coolant(self, mist: bool, flood: bool) -> None:
        self.mist, self.flood = mist, flood
        self.coolant = {(False, False): "off", (True, False): "mist", (False, True): "flood"}.get(
            (mist, flood), "mist+flood"
        )


#: What M70 / M73 save and M72 restores (LinuxCNC's saved modal state).
SAVED_MODAL_STATE = (
    *("inch", "incremental", "arc_incremental", "plane", "feed", "spindle_rpm", "spindle", "mist", "flood"),
    *("path_mode", "tolerance", "retract_to_r", "system"),
)


class InterpreterSetup:
    """The interpreter's state, parameters and offsets (see the module's description).

    Parameters
    ----------
    lines : iterable of str, or None
        The program's lines (see :class:`twin.gcode.flow.ProgramText`).
    settings : Settings, optional
        Work offsets, tool lengths, G28/G30 homes and the tools a T word may select.
    source : str
        The program's name, for error lines.
    path : str or Path, optional
        A file to read instead of ``lines``.
    """

    def __init__(
        self,
        lines: Iterable[str] | None,
        settings: Settings | None = None,
        source: str = "program",
        path: str | Path | None = None,
    ):
        self.settings, self.source = settings or Settings(), source
        self.state = ModalState()
        self.params = Parameters(self._system)
        self.text_source = ProgramText(lines, path)
        self.flow = Flow(self.text_source, self.params)
        self.cycle = CycleMemory()
        self.out: list[Move] = []  # the moves of the block being run
        self.comp = CutterCompensation(self.out)
        self.saved: list[dict] = []  # M70
        self.autorestore: list[tuple[int, dict]] = []  # M73: (call depth, state)
        self.lines_read, self.text = 0, ""
        self._load_settings()
        self._select_system(1)
        self.state.position = [0.0 - v for v in self._machine_offset()]  # the machine starts at machine zero
        self._offset_mm = self._offset_tuple()

    # --- parameters -----------------------------------------------------------------------

    def _load_settings(self) -> None:
        """The controller's values into their parameters (mm: the machine's units)."""
        numbered = self.params.numbered
        for i in range(3):
            numbered[Param.G28_HOME + i] = self.settings.g28_home_mm[i]
            numbered[Param.G30_HOME + i] = self.settings.g30_home_mm[i]
        for system, offset in self.settings.work_offsets_mm.items():
            if not 1 <= system <= 9:
                raise GcodeError(0, "", f"work offset of coordinate system {system}: the systems are 1-9", self.source)
            for i in range(3):
                numbered[coord_system_offset(system) + i] = float(offset[i])
        numbered[Param.COORD_SYSTEM] = 1.0

    def _system(self, key: int | str) -> float | None:
        """The read-only parameters LinuxCNC computes from its state."""
        s = self.state
        if isinstance(key, int):
            axis = key - Param.POSITION
            if 0 <= axis < AXES_IN_PARAMETERS:
                return s.position[axis] if axis < len(AXES) else 0.0
            if key == Param.TOOL_NUMBER:
                return float(s.tool_in_spindle)
            axis = key - Param.TOOL_OFFSET
            if 0 <= axis < AXES_IN_PARAMETERS:
                return self._tool_length(s.tool_in_spindle) if axis == AXES.index("z") else 0.0
            return None
        scale = s.mm_per_unit
        values = {
            "_x": s.position[0],
            "_y": s.position[1],
            "_z": s.position[2],
            "_abs_x": (s.position[0] + self._machine_offset()[0]) * scale,
            "_abs_y": (s.position[1] + self._machine_offset()[1]) * scale,
            "_abs_z": (s.position[2] + self._machine_offset()[2]) * scale,
            "_feed": s.feed,
            "_rpm": s.spindle_rpm,
            "_metric": 0.0 if s.inch else 1.0,
            "_imperial": 1.0 if s.inch else 0.0,
            "_absolute": 0.0 if s.incremental else 1.0,
            "_incremental": 1.0 if s.incremental else 0.0,
            "_inverse_time": 0.0,
            "_units_per_minute": 1.0,
            "_units_per_rev": 0.0,
            "_coord_system": float(COORD_SYSTEM_CODES[s.system - 1]),
            "_tool_offset": 1.0 if s.tool_offset else 0.0,
            "_retract_r_plane": 1.0 if s.retract_to_r else 0.0,
            "_retract_old_z": 0.0 if s.retract_to_r else 1.0,
            "_spindle_rpm_mode": 1.0,
            "_spindle_css_mode": 0.0,
            "_ijk_absolute_mode": 0.0 if s.arc_incremental else 1.0,
            "_lathe_diameter_mode": 0.0,
            "_lathe_radius_mode": 1.0,
            "_spindle_on": 0.0 if s.spindle == "off" else 1.0,
            "_spindle_cw": 1.0 if s.spindle == "cw" else 0.0,
            "_mist": 1.0 if s.mist else 0.0,
            "_flood": 1.0 if s.flood else 0.0,
            "_speed_override": 1.0,
            "_feed_override": 1.0,
            "_adaptive_feed": 0.0,
            "_feed_hold": 0.0,
            "_current_tool": float(s.tool_in_spindle),
            "_current_pocket": float(s.tool_in_spindle),
            "_selected_tool": float(s.selected_tool),
            "_selected_pocket": float(s.selected_tool),
            "_motion_mode": float(s.motion if s.motion is not None else GCode.G_80),
            "_plane": float(s.plane),
            "_ccomp": float({"left": GCode.G_41, "right": GCode.G_42}.get(self.comp.side or "", GCode.G_40)),
            "_value": self.flow.return_value,
            "_value_returned": self.flow.value_returned,
            "_line": float(self.lines_read),
            "_call_level": float(self.flow.depth),
            "_task": 0.0,
            "_metric_machine": 1.0,
            "_vmajor": 2.0,
            "_vminor": 9.0,
        }
        return values.get(key)

    def _tool_length(self, tool: int) -> float:
        """Tool ``tool``'s length (mm), 0 for tool 0."""
        if tool == 0:
            return 0.0
        if tool not in self.settings.tool_lengths_mm:
            self.error(f"tool {tool} is not in the tool table (reference.tool_lengths_mm)")
        return self.settings.tool_lengths_mm[tool]

    def error(self, reason: str) -> NoReturn:
        """Raise :class:`GcodeError` for the line being read."""
        raise GcodeError(self.lines_read, self.text, reason, self.source)

    # --- units and offsets ----------------------------------------------------------------

    def _to_program(self, mm: float) -> float:
        return mm / MM_PER_INCH if self.state.inch else mm

    def _to_user(self, value: float) -> float:
        return value * MM_PER_INCH if self.state.inch else value

    def _machine_offset(self) -> tuple[float, float, float]:
        """What work coordinates add to reach machine coordinates (program units)."""
        s = self.state
        return (
            s.origin[0] + s.axis_offset[0],
            s.origin[1] + s.axis_offset[1],
            s.origin[2] + s.axis_offset[2] + s.tool_offset,
        )

    def _offset_tuple(self) -> tuple[float, float, float]:
        scale = self.state.mm_per_unit
        ox, oy, oz = self._machine_offset()
        return (ox * scale, oy * scale, oz * scale)

    def _rebase(self, old: tuple[float, float, float]) -> None:
        """The same machine position in the changed work coordinates."""
        new = self._machine_offset()
        self.state.position = [p + o - n for p, o, n in zip(self.state.position, old, new)]
        self._offset_mm = self._offset_tuple()

    def _select_system(self, system: int) -> None:
        s = self.state
        old = self._machine_offset()
        s.system = system
        self.params.numbered[Param.COORD_SYSTEM] = float(system)
        base = coord_system_offset(system)
        s.origin = [self._to_program(self.params.numbered.get(base + i, 0.0)) for i in range(3)]
        self._rebase(old)
