"""LinuxCNC's names for the interpreter's numbers (twin.gcode.modal) against LinuxCNC's own
documentation (G-code overview, "Numbered Parameters" and ``#<_coord_system>``), and the O-word
handler table against the keywords the reader knows."""

import pytest

from twin.gcode.flow import Flow, ProgramText
from twin.gcode.modal import COORD_SYSTEM_CODES, GCode, Param, coord_system_offset
from twin.gcode.parameters import Parameters
from twin.gcode.reader import Reader
from twin.gcode.words import O_KEYWORDS

#: LinuxCNC's documented first (X) parameter of each coordinate system 1-9 (G54-G59.3).
DOCUMENTED_X_PARAMETER = {1: 5221, 2: 5241, 3: 5261, 4: 5281, 5: 5301, 6: 5321, 7: 5341, 8: 5361, 9: 5381}


def _moves(program: str):
    return list(Reader(program.splitlines()).moves())


@pytest.mark.parametrize("system", range(1, 10))
def test_a_coordinate_systems_offsets_are_in_linuxcncs_parameters(system):
    """G10 L2 P<system> sets the documented parameters, read back by a move (mm)."""
    number = DOCUMENTED_X_PARAMETER[system]
    assert coord_system_offset(system) == number
    (move,) = _moves(f"G21 G10 L2 P{system} X1.5 Y-2 Z3\nG0 X#{number} Y#{number + 1} Z#{number + 2}")
    assert move.end_mm == (1.5, -2.0, 3.0)


@pytest.mark.parametrize(
    ("code", "documented"), [("G54", 540), ("G55", 550), ("G59", 590), ("G59.1", 591), ("G59.3", 593)]
)
def test_coord_system_parameter_reads_as_linuxcnc_documents(code, documented):
    """``#<_coord_system>``: 550 in G55, 591 in G59.1; ``#5220`` the system's number 1-9."""
    (move,) = _moves(f"{code}\nG0 X[#<_coord_system> / 100] Y#{Param.COORD_SYSTEM}")
    assert move.end_mm[0] == pytest.approx(documented / 100)
    assert move.end_mm[1] == COORD_SYSTEM_CODES.index(GCode(documented)) + 1


def test_g28_home_and_g92_offset_parameters():
    """G28.1 stores the position in #5161-#5163; G92 sets #5210 to 1 and its offset in #5211-#5213."""
    moves = _moves(
        "G21 G0 X4 Y5 Z6\nG28.1\nG92 X1 Y1 Z1\n"
        f"G0 X#{Param.G28_HOME} Y#{Param.G28_HOME + 2} Z#{Param.AXIS_OFFSET_APPLIED}\n"
        f"G0 X#{Param.AXIS_OFFSET} Y#{Param.AXIS_OFFSET + 1} Z#{Param.AXIS_OFFSET + 2}"
    )
    assert (Param.G28_HOME, Param.AXIS_OFFSET_APPLIED, Param.AXIS_OFFSET) == (5161, 5210, 5211)
    assert moves[1].end_mm == (4.0, 6.0, 1.0)
    assert moves[2].end_mm == (3.0, 4.0, 5.0)  # the offset: 4 - 1, 5 - 1, 6 - 1


def test_every_o_keyword_has_a_handler():
    flow = Flow(ProgramText([]), Parameters(lambda key: None))
    assert set(flow.handlers) == set(O_KEYWORDS)
